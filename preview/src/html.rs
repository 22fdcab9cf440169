//! Small pieces of HTML shared by every page: escaping, the page shell with its style sheet.

/// The style sheet every page carries inline (one file, nothing else to fetch).
const CSS: &str = include_str!("../assets/preview.css");

/// `s` escaped for HTML text and attribute values.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A relative URL for a file name: each path segment percent-encoded where needed.
pub fn href(path: &str) -> String {
    let mut out = String::new();
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.~/".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// A whole page: `title`, the style sheet, `body` (already HTML).
pub fn page(title: &str, body: &str) -> String {
    format!(
        "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"frond {}\">\n<title>{}</title>\n<style>\n{CSS}</style>\n\
         </head>\n<body>\n{body}</body>\n</html>\n",
        env!("CARGO_PKG_VERSION"),
        esc(title)
    )
}

/// A figure: an image with a caption; `zoom` marks pixel images the zoom buttons scale.
pub fn figure(src: &str, size: [u32; 2], caption: &str, zoom: bool) -> String {
    format!(
        "<figure><img src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{}\"{}><figcaption>{}</figcaption></figure>",
        href(src),
        size[0],
        size[1],
        text_of(caption),
        if zoom { " class=\"px\"" } else { "" },
        caption
    )
}

/// The text of `markup` (HTML this crate built, its text already escaped) with its tags
/// removed: a caption's words as an image's `alt` attribute. A tag parts words as a space
/// would (a legend's swatch stands between its entries), and runs of spaces close up.
fn text_of(markup: &str) -> String {
    let mut spaced = String::with_capacity(markup.len());
    let mut in_tag = false;
    for c in markup.chars() {
        match c {
            '<' => {
                in_tag = true;
                spaced.push(' ');
            }
            '>' if in_tag => in_tag = false,
            c if !in_tag => spaced.push(c),
            _ => {}
        }
    }
    spaced.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_alt_is_its_caption_without_tags() {
        let caption = format!(
            "Difference: <span class=\"legend\"><span style=\"x\"></span>missing 2 px<span \
             style=\"y\"></span>extra 1 px</span> of {}",
            esc("LOD0's \"a\"")
        );
        let f = figure("d.png", [2, 3], &caption, true);
        assert!(
            f.contains("alt=\"Difference: missing 2 px extra 1 px of LOD0&#39;s &quot;a&quot;\""),
            "{f}"
        );
        assert!(f.contains(&format!("<figcaption>{caption}</figcaption>")));
    }

    #[test]
    fn text_and_urls_are_escaped() {
        assert_eq!(esc("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(
            href("oak dense_preview/lod1.png"),
            "oak%20dense_preview/lod1.png"
        );
        let p = page("x < y", "<p>hi</p>");
        assert!(p.starts_with("<!doctype html>"));
        assert!(p.contains("<title>x &lt; y</title>"));
    }
}
