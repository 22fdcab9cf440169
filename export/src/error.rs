//! Why an export failed.

/// Export errors.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A LOD's skin needs more joints than `JOINTS_0` as written (unsigned 16-bit) can index.
    #[error("more than 65536 joints in one skin")]
    TooManyJoints,
    /// An image could not be encoded for the file.
    #[error("encoding image '{name}': {source}")]
    Image {
        /// The image's name in the document.
        name: String,
        /// The encoder's error.
        #[source]
        source: image::ImageError,
    },
    /// A primitive or billboard names a material the tree does not have (its index).
    #[error("material {0} does not exist in the tree")]
    NoMaterial(usize),
    /// A material names a texture the tree does not have, or whose image is missing (its
    /// index).
    #[error("source texture {0} (or its image) does not exist in the tree")]
    NoTexture(usize),
    /// A material's texture map has no texture index (the material's name).
    #[error("a texture map of material '{0}' has no texture index")]
    NoTextureIndex(String),
    /// A file was asked for with no LOD in it.
    #[error("nothing to write: no LOD")]
    NoLod,
    /// The vertex animation textures could not be encoded.
    #[error(transparent)]
    Vat(#[from] crate::vat::VatError),
    /// Spectral animation was asked for a cloud whose billboards move by sampled rigid
    /// motion (the method named), which has no cosine terms to write.
    #[error(
        "the animation mode spectral: method '{0}' gives billboards sampled rigid motion, which \
         has no spectral form; use a spectral method (or per-bone), or the animation mode skin \
         or vat"
    )]
    NoSpectralForm(String),
    /// A KTX2 texture could not be made (the reason).
    #[error("encoding a KTX2 texture: {0}")]
    Ktx2(String),
    /// A sidecar could not be serialised as JSON (the reason).
    #[error("serialising a sidecar: {0}")]
    Json(String),
}
