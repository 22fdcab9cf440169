//! The error type of every fallible operation in this crate.

use thiserror::Error;

/// Everything that can go wrong while setting up the GPU or rendering a scene.
///
/// Input problems (bad indices, sizes, texture data) are reported before any GPU
/// work starts; GPU-side failures carry wgpu's own description.
#[derive(Debug, Error)]
pub enum RenderError {
    /// No graphics adapter at all: neither a GPU nor a CPU rasteriser such as llvmpipe.
    #[error(
        "no GPU or CPU graphics adapter found (backends searched: {backends}): install Mesa's \
         drivers (apt-get install mesa-vulkan-drivers libegl1-mesa libgl1-mesa-dri) or run on a \
         machine with a GPU{hint}"
    )]
    NoAdapter {
        /// The backends the instance searched, e.g. "Vulkan, GL".
        backends: String,
        /// Extra advice, e.g. about a `WGPU_BACKEND` setting that excluded adapters.
        hint: String,
    },

    /// Adapters exist but none of them would create a device.
    #[error("could not create a graphics device on any adapter: {0}")]
    DeviceCreation(String),

    /// The requested image size is zero or beyond what the device supports.
    #[error("invalid image size {width}x{height}: {reason}")]
    InvalidSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// Why the size was rejected.
        reason: String,
    },

    /// The camera cannot produce a projection (non-finite or non-positive values).
    #[error("invalid camera: {0}")]
    InvalidCamera(String),

    /// A mesh's index list does not describe whole triangles.
    #[error("mesh {mesh}: index count {count} is not a multiple of 3")]
    IndexCount {
        /// Mesh position in `DrawScene::meshes`.
        mesh: usize,
        /// Number of indices given.
        count: usize,
    },

    /// A triangle refers to a vertex that does not exist.
    #[error(
        "mesh {mesh}: index {index} at position {position} is out of range ({vertex_count} vertices)"
    )]
    IndexOutOfRange {
        /// Mesh position in `DrawScene::meshes`.
        mesh: usize,
        /// Position of the bad entry in `DrawMesh::indices`.
        position: usize,
        /// The bad index value.
        index: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },

    /// A per-vertex attribute has a different length than `positions`.
    #[error("mesh {mesh}: {attribute} has {len} entries but there are {expected} positions")]
    AttributeLength {
        /// Mesh position in `DrawScene::meshes`.
        mesh: usize,
        /// "normals" or "uvs".
        attribute: &'static str,
        /// Length given.
        len: usize,
        /// Length expected (number of positions).
        expected: usize,
    },

    /// A mesh has more vertices than 32-bit indices can address.
    #[error("mesh {mesh}: {vertex_count} vertices exceed the 32-bit index range")]
    TooManyVertices {
        /// Mesh position in `DrawScene::meshes`.
        mesh: usize,
        /// Number of vertices given.
        vertex_count: usize,
    },

    /// A mesh names a material that does not exist.
    #[error("mesh {mesh}: material {material} is out of range ({count} materials)")]
    MaterialOutOfRange {
        /// Mesh position in `DrawScene::meshes`.
        mesh: usize,
        /// The bad material index.
        material: usize,
        /// Number of materials in the scene.
        count: usize,
    },

    /// A material names a texture that does not exist.
    #[error("material {material}: texture {texture} is out of range ({count} textures)")]
    TextureOutOfRange {
        /// Material position in `DrawScene::materials`.
        material: usize,
        /// The bad texture index.
        texture: usize,
        /// Number of textures in the scene.
        count: usize,
    },

    /// A texture's pixel data does not match its size, or the size is unusable.
    #[error("texture {texture}: {reason}")]
    InvalidTexture {
        /// Texture position in `DrawScene::textures`.
        texture: usize,
        /// What is wrong with it.
        reason: String,
    },

    /// wgpu reported a validation, out-of-memory or internal error while rendering.
    #[error("GPU error while rendering: {0}")]
    Gpu(String),

    /// Reading the rendered image back from the GPU failed.
    #[error("reading the image back from the GPU failed: {0}")]
    Readback(String),
}
