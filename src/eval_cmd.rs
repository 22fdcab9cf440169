//! `frond eval ORIGINAL CANDIDATE`: how well a candidate (a `frond lod` LOD, a decimated tree,
//! an artist's LOD) reproduces an animated tree, by the metrics of spec
//! animated-billboard-clouds §5 and App. A, each with its definition in the report.
//!
//! The evaluation itself (matching, metrics, report) is `frond_metrics::eval`; this is the
//! command's glue: which files are the same, and the names the CLI and the sweep use.

use std::path::Path;

pub use frond_metrics::eval::{
    EvalContext, EvalError, EvalRequest, evaluate, image_for_screen_height,
};
pub use frond_metrics::report::{Costs, CoverageMetrics, EvalReport, Metric};

/// Whether two files hold the same bytes (the candidate is the original itself): sizes first,
/// so a sweep does not read both files whole for every run.
pub fn same_bytes(a: &Path, b: &Path) -> bool {
    let len = |p: &Path| std::fs::metadata(p).map(|m| m.len()).ok();
    match (len(a), len(b)) {
        (Some(x), Some(y)) if x == y => std::fs::read(a).ok() == std::fs::read(b).ok(),
        _ => false,
    }
}
