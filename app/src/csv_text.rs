//! Text cells of the CSV files frond writes (`summary.csv`, `results.csv`, `stability.csv`),
//! made safe for spreadsheets: a cell that starts with `=`, `+`, `-`, `@`, a tab or a carriage
//! return is read as a formula by Excel, LibreOffice and Google Sheets (a tree file named
//! `=HYPERLINK(…).glb` would run one), so such a cell gets a leading `'`, which those programs
//! show as text and do not display (OWASP's advice for CSV injection). Numbers are written as
//! numbers and never pass here.

use std::borrow::Cow;

/// `text` as a CSV cell that no spreadsheet reads as a formula.
pub fn text_cell(text: &str) -> Cow<'_, str> {
    match text.chars().next() {
        Some('=' | '+' | '-' | '@' | '\t' | '\r') => Cow::Owned(format!("'{text}")),
        _ => Cow::Borrowed(text),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formula_starts_are_quoted() {
        assert_eq!(text_cell("=HYPERLINK(\"x\").glb"), "'=HYPERLINK(\"x\").glb");
        for s in ["+1", "-2", "@SUM(A1)", "\tx", "\rx"] {
            assert_eq!(text_cell(s), format!("'{s}"));
        }
        assert_eq!(text_cell("oak/LOD"), "oak/LOD");
        assert_eq!(text_cell(""), "");
    }
}
