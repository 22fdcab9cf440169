//! The README's table of `<name>_report.json`'s fields is made from the report schema's own doc
//! comments (`LodReport` and `LodEntry` in lod/src/report.rs): a field added or redescribed
//! there shows in the README, and the two cannot drift apart. `FROND_BLESS=1 cargo test --test
//! readme_report_table` rewrites the README's table from the schema.

use std::path::Path;

/// The markers around the generated table in README.md.
const BEGIN: &str = "<!-- report-schema: generated from lod/src/report.rs; FROND_BLESS=1 cargo test --test frond_tests readme_report_table rewrites it -->";
const END: &str = "<!-- /report-schema -->";

/// Each public field of `pub struct NAME { ... }` in `source` with its doc comment, joined into
/// one line.
fn fields(source: &str, name: &str) -> Vec<(String, String)> {
    let start = source
        .find(&format!("pub struct {name} {{"))
        .unwrap_or_else(|| panic!("no struct {name} in lod/src/report.rs"));
    let body = &source[start..];
    let body = &body[..body.find("\n}\n").expect("the struct's end")];
    let mut out = Vec::new();
    let mut doc: Vec<&str> = Vec::new();
    for line in body.lines().skip(1) {
        let line = line.trim();
        if let Some(d) = line.strip_prefix("///") {
            doc.push(d.trim());
        } else if let Some(rest) = line.strip_prefix("pub ") {
            let field = rest
                .split(':')
                .next()
                .unwrap_or_default()
                .trim()
                .to_string();
            out.push((field, doc.join(" ")));
            doc.clear();
        } else if !line.starts_with("#[") {
            doc.clear();
        }
    }
    out
}

/// A doc comment as README text: intra-doc links (`` [`X`] ``) as plain code, `|` escaped.
fn markdown(doc: &str) -> String {
    doc.replace("[`", "`")
        .replace("`]", "`")
        .replace('|', "\\|")
}

/// The README's table, made from the schema.
fn table(source: &str) -> String {
    let mut rows = vec![
        BEGIN.to_string(),
        "| field | what it holds |".to_string(),
        "|---|---|".to_string(),
    ];
    let mut add = |prefix: &str, struct_name: &str| {
        for (field, doc) in fields(source, struct_name) {
            // A flattened field's keys stand in the entry itself.
            let key = match field.as_str() {
                "sections" => format!("`{prefix}spectral`, `{prefix}skeleton`, `{prefix}cards`, …"),
                _ => format!("`{prefix}{field}`"),
            };
            rows.push(format!("| {key} | {} |", markdown(&doc)));
        }
    };
    add("", "LodReport");
    add("lods[].", "LodEntry");
    rows.push(END.to_string());
    rows.join("\n")
}

#[test]
fn the_readme_report_table_is_the_schemas_docs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let source = std::fs::read_to_string(root.join("lod/src/report.rs")).unwrap();
    let want = table(&source);
    let readme_path = root.join("README.md");
    let readme = std::fs::read_to_string(&readme_path).unwrap();
    let (Some(a), Some(b)) = (readme.find(BEGIN), readme.find(END)) else {
        panic!("README.md has no generated report table (markers {BEGIN} … {END})");
    };
    let have = &readme[a..b + END.len()];
    if have != want && std::env::var_os("FROND_BLESS").is_some() {
        let new = format!("{}{want}{}", &readme[..a], &readme[b + END.len()..]);
        std::fs::write(&readme_path, new).unwrap();
        return;
    }
    assert_eq!(
        have, want,
        "README.md's report table differs from lod/src/report.rs's docs: run \
         FROND_BLESS=1 cargo test --test frond_tests readme_report_table"
    );
    // Every field of both structs is listed.
    for (field, doc) in fields(&source, "LodReport")
        .iter()
        .chain(&fields(&source, "LodEntry"))
    {
        assert!(!doc.is_empty(), "{field} has no doc comment");
    }
}
