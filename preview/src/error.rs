//! What can go wrong making a preview.

/// A preview page could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// Rendering a still or a flip-book frame failed.
    #[error("{file}: rendering its {what}: {source}")]
    Render {
        file: String,
        what: &'static str,
        #[source]
        source: frond_render::RenderError,
    },
    /// The camera could not frame the tree (empty or degenerate bounds).
    #[error("{file}: framing the camera: {source}")]
    Camera {
        file: String,
        #[source]
        source: frond_metrics::MetricError,
    },
    /// An image could not be encoded.
    #[error("encoding {what}: {reason}")]
    Encode { what: String, reason: String },
    /// The combined file written by the run could not be read back.
    #[error("{file}: {reason}")]
    Combined { file: String, reason: String },
    /// The report and the LODs read back do not match.
    #[error("the report lists {report} LODs but {given} were read back")]
    LodCount { report: usize, given: usize },
}
