//! Errors of skeleton simplification.

use thiserror::Error;

/// Why a skeleton could not be simplified.
#[derive(Debug, Error)]
pub enum SkeletonError {
    /// The tree has no skin joints, so there is no skeleton to simplify.
    #[error("the tree has no skeleton (no skin joints): skeleton simplification needs bones")]
    NoBones,
    /// A budget of zero billboard clouds was asked for.
    #[error("the cloud budget must be at least 1")]
    ZeroBudget,
}
