//! Errors of skeleton simplification.

use thiserror::Error;

/// Why a skeleton could not be simplified.
#[derive(Debug, Error)]
pub enum SkeletonError {
    #[error("the tree has no skeleton (no skin joints): skeleton simplification needs bones")]
    NoBones,
    #[error("the cloud budget must be at least 1")]
    ZeroBudget,
}
