//! What can go wrong making a preview.

/// A preview page could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// Rendering a still or a flip-book frame failed.
    #[error("{file}: rendering its {what}: {source}")]
    Render {
        /// The file whose picture it was.
        file: String,
        /// Which picture (`still`, `flip-book frame`, ...).
        what: &'static str,
        /// The renderer's error.
        #[source]
        source: frond_render::RenderError,
    },
    /// The camera could not frame the tree (empty or degenerate bounds).
    #[error("{file}: framing the camera: {source}")]
    Camera {
        /// The file whose bounds they were.
        file: String,
        /// Why the camera could not be placed.
        #[source]
        source: frond_metrics::MetricError,
    },
    /// An image could not be encoded.
    #[error("encoding {what}: {reason}")]
    Encode {
        /// Which picture.
        what: String,
        /// The encoder's reason.
        reason: String,
    },
    /// The combined file written by the run could not be read back.
    #[error("{file}: {reason}")]
    Combined {
        /// The combined file.
        file: String,
        /// Why it could not be read.
        reason: String,
    },
    /// The report and the LODs read back do not match.
    #[error("the report lists {report} LODs but {given} were read back")]
    LodCount {
        /// LODs in the report.
        report: usize,
        /// LODs read back.
        given: usize,
    },
}
