//! Errors of the scene stage: every one names the file and the problem in one line.

use std::path::PathBuf;

/// Why a tree could not be read, sampled or written.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    /// The file is not glTF, or its content breaks the glTF rules we rely on.
    #[error("{path}: {problem}")]
    Invalid { path: PathBuf, problem: String },
    /// `extensionsRequired` names an extension frond cannot read.
    #[error("{path}: requires unsupported glTF extension {extension}")]
    UnsupportedExtension { path: PathBuf, extension: String },
    /// A request that does not fit the tree (unknown clip or material name, bad sample count).
    #[error("{path}: {problem}")]
    Request { path: PathBuf, problem: String },
}

impl SceneError {
    /// A content problem in `path`.
    pub fn invalid(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        SceneError::Invalid {
            path: path.into(),
            problem: problem.into(),
        }
    }
}

/// Result alias for the scene stage.
pub type Result<T> = std::result::Result<T, SceneError>;
