//! The index page of a batch: one line per tree, linking its preview page.

use crate::html::{esc, href, page};
use crate::units;

/// One tree of a batch, as its index line shows it.
pub struct IndexEntry {
    /// The tree's name, the line's label.
    pub name: String,
    /// The tree's preview page, relative to the index page (None: the tree failed or wrote no
    /// preview).
    pub page: Option<String>,
    /// Its LOD0 still, relative to the index page.
    pub thumbnail: Option<String>,
    /// A line of what was made (LODs, triangles, bytes), or the error.
    pub summary: String,
    /// The tree failed: the summary is the error, shown as a warning.
    pub failed: bool,
}

/// The index page of `entries` under `title`.
pub fn index_page(title: &str, intro: &str, entries: &[IndexEntry]) -> String {
    let mut b = format!(
        "<header><h1>{}</h1><p class=\"meta\">{}</p></header>\n<ul class=\"index\">\n",
        esc(title),
        intro
    );
    for e in entries {
        let name = match &e.page {
            Some(p) => format!("<a href=\"{}\">{}</a>", href(p), esc(&e.name)),
            None => esc(&e.name),
        };
        let thumb = e.thumbnail.as_ref().map_or(String::new(), |t| {
            format!(
                "<img src=\"{}\" height=\"64\" alt=\"\" style=\"vertical-align:middle\"> ",
                href(t)
            )
        });
        b.push_str(&format!(
            "<li>{thumb}<b>{name}</b> — <span class=\"{}\">{}</span></li>\n",
            if e.failed { "over" } else { "muted" },
            esc(&e.summary)
        ));
    }
    b.push_str("</ul>\n");
    page(title, &b)
}

/// `n` trees as "3 trees", with the total of `bytes` when given.
pub fn trees_line(n: usize, bytes: Option<u64>) -> String {
    let trees = if n == 1 {
        "1 tree".to_string()
    } else {
        format!("{n} trees")
    };
    match bytes {
        Some(b) => format!("{trees}, {} written", units::bytes(b as f64)),
        None => trees,
    }
}
