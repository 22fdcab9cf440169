//! Errors of the scene stage: every one names the file and the problem in one line.

use std::path::PathBuf;

/// Why a tree could not be read, sampled or written.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// The file is not glTF, or its content breaks the glTF rules we rely on.
    #[error("{path}: {problem}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the part of the file (node, mesh, accessor, ...).
        problem: String,
    },
    /// `extensionsRequired` names an extension frond cannot read.
    #[error("{path}: requires unsupported glTF extension {extension}")]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
        /// The extension's name.
        extension: String,
    },
    /// A request that does not fit the tree (unknown clip or material name, bad sample count).
    #[error("{path}: {problem}")]
    Request {
        /// The tree's file.
        path: PathBuf,
        /// What does not fit.
        problem: String,
    },
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
