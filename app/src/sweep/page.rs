//! The sweep's page (`index.html` in its folder, what `frond view OUTDIR` opens): every chart,
//! the runs as a table in the units people use, the Pareto front, links to the tables.

use frond_preview::charts::Chart;
use frond_preview::html::{esc, href, page};
use frond_preview::units;

use super::charts::ACCURACY;
use super::results::{self, Row};

/// The page of a sweep of `input` with `rows`, `charts` (written as `<stem>.png`/`.svg` beside
/// it) and the runs on the Pareto front.
pub fn sweep_page(input: &str, rows: &[Row], charts: &[Chart], pareto: &[String]) -> String {
    let failed = rows.iter().filter(|r| r.failure.is_some()).count();
    let mut b = format!(
        "<header><h1>frond sweep: {}</h1><p class=\"meta\">{} runs, {failed} failed · tables: \
         <a href=\"results.csv\">results.csv</a>, <a href=\"stability.md\">stability.md</a>, \
         <a href=\"summary.json\">summary.json</a></p></header>\n<h2>Charts</h2>\n",
        esc(input),
        rows.len()
    );
    b.push_str(&format!(
        "<p class=\"muted\">Accuracy is the {} (spec §5.4 on covered fractions): per view and \
         frame the covered area the LOD misses or adds, over the area the tree covers, with the \
         tree seen at the run's screen height; 0 is a perfect match, 1 what a LOD covering \
         nothing scores, above 1 a LOD that adds more area outside the tree than it shares \
         with it (a failed run). The \
         coverage ratio is the LOD's covered area over the tree's: below 1 it thins, above 1 it \
         bloats. Each line is a method; its points are labelled with the screen height the LOD \
         was built and measured at. Click a chart for its SVG.</p>\n",
        esc(ACCURACY.label())
    ));
    for c in charts {
        b.push_str(&format!(
            "<figure><a href=\"{0}.svg\"><img src=\"{0}.png\" alt=\"{1}\" style=\"max-width:100%\"></a>\
             <figcaption>{1}</figcaption></figure>\n",
            href(&c.file_stem),
            esc(&c.panels.iter().map(|p| p.title.as_str()).collect::<Vec<_>>().join(" · "))
        ));
    }
    b.push_str(&format!(
        "<h2>Runs</h2>\n<table class=\"costs\"><tr><th>run</th><th>method</th><th>screen height</th>\
         <th>seed</th><th>ε</th><th>{}</th><th>coverage ratio</th><th>billboards</th>\
         <th>texture bytes</th><th>build time</th><th></th></tr>\n",
        esc(ACCURACY.label())
    ));
    let num = |r: &Row, c: &str, f: fn(f64) -> String| {
        let v = r.get(c);
        if v.is_finite() { f(v) } else { "–".into() }
    };
    for r in rows {
        let front = pareto.contains(&r.run);
        b.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{} px</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            esc(&r.run),
            esc(&r.method),
            units::significant(f64::from(r.screen_height)),
            r.seed.map_or("–".into(), |s| s.to_string()),
            r.epsilon_pct
                .map_or("–".into(), |e| format!("{} %", units::significant(e))),
            num(r, ACCURACY.column(), units::significant),
            num(r, results::COVERAGE_RATIO, units::significant),
            num(r, "billboards", |v| units::count(v as u64)),
            num(r, "texture_bytes", units::bytes),
            num(r, "t_lod", units::duration),
            match (&r.failure, front) {
                (Some(f), _) => format!("<span class=\"over\">{}</span>", esc(f)),
                (None, true) => "Pareto front".into(),
                _ => String::new(),
            },
        ));
    }
    b.push_str("</table>\n");
    page(&format!("frond sweep: {input}"), &b)
}
