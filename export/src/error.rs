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
    #[error("source texture {0} (or its image) does not exist in the tree")]
    NoTexture(usize),
    #[error("a texture map of material '{0}' has no texture index")]
    NoTextureIndex(String),
    #[error("nothing to write: no LOD")]
    NoLod,
    #[error(transparent)]
    Vat(#[from] crate::vat::VatError),
    #[error(
        "--animation spectral: method '{0}' gives billboards sampled rigid motion, which has no \
         spectral form; use a spectral method (or per-bone), or --animation skin/vat"
    )]
    NoSpectralForm(String),
    #[error("encoding a KTX2 texture: {0}")]
    Ktx2(String),
    #[error("serialising a sidecar: {0}")]
    Json(String),
}
