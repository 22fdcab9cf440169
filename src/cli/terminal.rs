//! Text bound for a terminal, made inert: names from a user's files (clips, materials, nodes,
//! file names) reach the terminal in messages, and a control character in one could move the
//! cursor, clear the screen, retitle the window or hide text. Every line the CLI prints, and the
//! log, passes [`safe`]: C0 controls but newline and tab, DEL, C1 controls and the Unicode
//! bidirectional overrides are written as visible escapes (`\x1b`, `\u{9b}`).

use std::borrow::Cow;
use std::io::Write;

/// Whether `c` must not reach a terminal as itself.
fn is_unsafe(c: char) -> bool {
    (c.is_control() && c != '\n' && c != '\t')
        || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// `text` with every unsafe character written as an escape (see the module doc).
pub fn safe(text: &str) -> Cow<'_, str> {
    if !text.chars().any(is_unsafe) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if !is_unsafe(c) {
            out.push(c);
        } else if (c as u32) < 0x80 {
            out.push_str(&format!("\\x{:02x}", c as u32));
        } else {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        }
    }
    Cow::Owned(out)
}

/// `println!` with the line passed through [`safe`].
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        println!("{}", $crate::cli::terminal::safe(&format!($($arg)*)))
    };
}

/// `eprintln!` with the line passed through [`safe`].
#[macro_export]
macro_rules! say_err {
    ($($arg:tt)*) => {
        eprintln!("{}", $crate::cli::terminal::safe(&format!($($arg)*)))
    };
}

/// A writer that passes what it is given through [`safe`] (bytes that are not UTF-8 as
/// `\xNN`): the log's writer, so names in log messages are inert too.
pub struct SafeWriter<W: Write>(pub W);

impl<W: Write> Write for SafeWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let text: Cow<'_, str> = match std::str::from_utf8(buf) {
            Ok(t) => Cow::Borrowed(t),
            Err(_) => Cow::Owned(
                buf.iter()
                    .map(|&b| {
                        if b.is_ascii() {
                            char::from(b).to_string()
                        } else {
                            format!("\\x{b:02x}")
                        }
                    })
                    .collect(),
            ),
        };
        self.0.write_all(safe(&text).as_bytes())?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_sequences_are_made_visible() {
        assert_eq!(safe("Wind\tloop\n"), "Wind\tloop\n");
        assert_eq!(safe("a\u{1b}]0;pwned\u{7}b"), "a\\x1b]0;pwned\\x07b");
        assert_eq!(safe("\u{1b}[2J"), "\\x1b[2J");
        assert_eq!(safe("x\u{9b}31m"), "x\\u{9b}31m");
        assert_eq!(safe("abc\u{202e}cba"), "abc\\u{202e}cba");
        assert_eq!(safe("\u{7f}"), "\\x7f");
        assert_eq!(safe("écorce 樹"), "écorce 樹");
        let mut out = Vec::new();
        SafeWriter(&mut out)
            .write_all(b"ok \x1b[31m \xff\n")
            .unwrap();
        assert_eq!(out, b"ok \\x1b[31m \\xff\n");
    }
}
