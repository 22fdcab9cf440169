//! Why an export failed.

/// Export errors.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("more than 65536 joints in one skin")]
    TooManyJoints,
    #[error("encoding image '{name}': {source}")]
    Image {
        name: String,
        #[source]
        source: image::ImageError,
    },
    #[error("material {0} does not exist in the tree")]
    NoMaterial(usize),
    #[error("nothing to write: no LOD")]
    NoLod,
    #[error(transparent)]
    Vat(#[from] crate::vat::VatError),
    #[error(
        "--animation spectral: method '{0}' gives billboards sampled rigid motion, which has no \
         spectral form; use a spectral method (or per-bone), or --animation skin/vat"
    )]
    NoSpectralForm(String),
    #[error("serialising a sidecar: {0}")]
    Json(String),
}
