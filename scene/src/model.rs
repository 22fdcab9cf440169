//! The tree model every later stage works on: node hierarchy, skeleton, skinned geometry split
//! into wood and foliage, materials, textures and animation clips (spec animated-billboard-clouds §1).

use std::path::PathBuf;

use glam::{Mat4, Vec2, Vec3, Vec4};
use serde::Serialize;

use crate::rig::Rig;

/// A bone: a node that is a joint of some skin.
#[derive(Clone, Debug)]
pub struct Bone {
    /// The joint node's name (`node<i>` when the node has none).
    pub name: String,
    /// Index of the joint node in [`Rig::nodes`](crate::Rig::nodes).
    pub node: usize,
    /// The nearest ancestor node that is also a bone.
    pub parent: Option<usize>,
    /// 1 for a root bone, parent's depth + 1 otherwise.
    pub depth: u32,
    /// World transform at rest (no animation applied).
    pub rest_world: Mat4,
}

/// What a group of vertices is deformed by.
#[derive(Clone, Debug)]
pub enum Binding {
    /// Linear-blend skinned: palette entry k = world(joint_k) · inverse_bind_k.
    Skin {
        /// Per palette entry, the bone (index into [`Tree::bones`]) of the skin's joint.
        joints: Vec<usize>,
        /// Per palette entry, the joint's inverse bind matrix (identity when the skin gives
        /// none).
        inverse_bind: Vec<Mat4>,
    },
    /// Rigidly attached to a node (unskinned mesh): palette entry 0 = world(node).
    Node(usize),
}

/// Whether a triangle belongs to the wood or the foliage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Part {
    /// Trunk and branches: simplified as a mesh (the wood LODs).
    Wood,
    /// Leaves and leaf cards: what billboard clouds replace (spec §1.3).
    Foliage,
}

/// How the wood/foliage decision for one primitive was made.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Classification {
    /// Name of the primitive's mesh (`mesh<i>` when unnamed).
    pub mesh: String,
    /// Index of the primitive within its mesh.
    pub primitive: usize,
    /// Name of the primitive's material (`(none)` without one).
    pub material: String,
    /// Where its triangles went.
    pub part: Part,
    /// Why, in words: the user's naming, a word in a name, the alpha mode or the card
    /// shape that decided it.
    pub reason: String,
    /// Triangles of the primitive.
    pub triangles: usize,
}

/// Per-vertex data, in the mesh space the binding expects.
#[derive(Clone, Debug, Default)]
pub struct Vertices {
    /// Positions in the binding's mesh space (before skinning).
    pub position: Vec<Vec3>,
    /// Unit normals in the same space (zero where the file gives none).
    pub normal: Vec<Vec3>,
    /// The input's `TANGENT` (xyz, w the bitangent's sign), for applying normal maps: empty
    /// when no primitive has one, else one per vertex (zero where a primitive lacks it). Code
    /// that makes or reorders vertices may leave it empty; readers check its length.
    pub tangent: Vec<Vec4>,
    /// The base-colour map's coordinates: the texCoord set its material names, with its
    /// `KHR_texture_transform` applied (what baking and rendering sample the decoded texture at).
    pub uv: Vec<Vec2>,
    /// The input's own `TEXCOORD_0`, `TEXCOORD_1` as stored (no transform applied), for writing
    /// the tree back with its materials unchanged: set `n` is `texcoords[n]`, one entry per
    /// vertex (zeros where a primitive lacks the set). Sets past `TEXCOORD_0` are kept only when
    /// some material's texture map uses them; at most [`MAX_TEXCOORD_SETS`] sets.
    pub texcoords: Vec<Vec<Vec2>>,
    /// Index into `Tree::bindings`.
    pub binding: Vec<u32>,
    /// Palette entries of the binding (skin-local joint indices); unused slots weigh 0.
    pub joints: Vec<[u16; 4]>,
    /// Normalised weights (sum 1).
    pub weights: Vec<[f32; 4]>,
}

impl Vertices {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// True when there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
}

/// One triangle of the tree.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Vertex indices into [`Tree::vertices`], in the input's winding.
    pub v: [u32; 3],
    /// Index into [`Tree::materials`] (primitives without a material use the default one
    /// appended after the imported ones).
    pub material: u32,
    /// Wood or foliage (see [`Tree::classification`] for why).
    pub part: Part,
    /// Zero area at rest: counted but skipped by later stages.
    pub degenerate: bool,
    /// For foliage: the single bone it follows (spec §1.3). None when the tree has no bones.
    pub bone: Option<u32>,
}

/// glTF alpha mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum AlphaMode {
    /// Alpha ignored: the surface is fully opaque.
    Opaque,
    /// Alpha-tested: texels under [`Material::alpha_cutoff`] are discarded (leaf cards).
    Mask,
    /// Alpha-blended over what lies behind.
    Blend,
}

/// How a texture is sampled outside [0, 1] along one axis (glTF sampler `wrapS`/`wrapT`; the
/// default when a texture has no sampler is [`Wrap::Repeat`]). Renderers must honour it:
/// a leaf texture clamped at a transparent border shows nothing outside its card, a repeating
/// one shows its neighbour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
pub enum Wrap {
    /// Tiles the texture (glTF `REPEAT`, the default).
    #[default]
    Repeat,
    /// Repeats the edge texels (glTF `CLAMP_TO_EDGE`).
    ClampToEdge,
    /// Tiles the texture, every other copy mirrored (glTF `MIRRORED_REPEAT`).
    MirroredRepeat,
}

impl Wrap {
    /// The texel (0..`size`) a texture coordinate `x`, in texels, reads under this mode.
    pub fn texel(self, x: f32, size: u32) -> u32 {
        let n = size.max(1) as f32;
        let t = match self {
            Wrap::Repeat => x.rem_euclid(n),
            Wrap::ClampToEdge => x.clamp(0.0, n - 1.0),
            Wrap::MirroredRepeat => {
                let m = x.rem_euclid(2.0 * n);
                if m < n { m } else { 2.0 * n - m }
            }
        };
        (t.max(0.0) as u32).min(size.max(1) - 1)
    }
}

/// How many texture coordinate sets ([`Vertices::texcoords`]) a tree carries at most:
/// `TEXCOORD_0` and `TEXCOORD_1` (a second set for lightmaps or occlusion is common; more are
/// rare). A material map naming a later set is written with `texCoord` 0 and a warning.
pub const MAX_TEXCOORD_SETS: usize = 2;

/// A material as far as billboards care: colour, texture, cut-out; plus, for an imported
/// material, the input's whole description ([`Material::source`]) so it is written back as is.
#[derive(Clone, Debug)]
pub struct Material {
    /// The material's name (`material<i>` when the input gives none).
    pub name: String,
    /// Base colour factor, linear RGBA, multiplied with the texture.
    pub base_color: [f32; 4],
    /// Index into `Tree::textures`.
    pub base_color_texture: Option<usize>,
    /// How the base-colour texture wraps along u and v (its sampler's modes).
    pub base_color_wrap: [Wrap; 2],
    /// Index into `Tree::textures`: the tangent-space normal map, decoded only when it samples
    /// the base colour's coordinates and the file gives `TANGENT` (frond does not generate
    /// tangent frames), so that renders light the surface as an engine would.
    pub normal_texture: Option<usize>,
    /// How alpha is used (glTF `alphaMode`).
    pub alpha_mode: AlphaMode,
    /// Alpha below which a masked texel is discarded (glTF `alphaCutoff`, default 0.5).
    pub alpha_cutoff: f32,
    /// Whether back faces are drawn (glTF `doubleSided`).
    pub double_sided: bool,
    /// The input's material, for writing it back unchanged (None: made by frond, such as the
    /// default material of primitives without one; written from the fields above).
    pub source: Option<MaterialSource>,
}

/// A material exactly as the input described it: every field, texture map, extension and
/// extra. Output materials are written from this, so LOD0 looks like the input (metallic,
/// roughness, normal, occlusion and emissive maps included), not like frond's summary of it.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSource {
    /// The material's JSON object as read. In every texture map (each object under a key that
    /// ends in `Texture`, at any depth: `baseColorTexture`, `normalTexture`, an extension's
    /// `clearcoatTexture`, ...) `index` is an index into [`Tree::source_textures`], not the
    /// input's texture index; `texCoord` is at most [`MAX_TEXCOORD_SETS`] − 1.
    pub json: serde_json::Value,
    /// Extension names the material uses (its own `extensions` and its maps'), for the output's
    /// `extensionsUsed`.
    pub extensions: Vec<String>,
}

/// A JSON object (a glTF material, texture map, sampler, ...).
pub type JsonObject = serde_json::Map<String, serde_json::Value>;

/// Calls `f` on every texture map (glTF textureInfo) of a material's JSON, with the key it is
/// under: each object under a key ending in `Texture`, at any depth, that has an `index` (the
/// core maps and extensions' maps such as `clearcoatTexture` alike: glTF names them all so).
/// Stops at the first error.
pub fn visit_texture_infos<E>(
    value: &mut serde_json::Value,
    f: &mut dyn FnMut(&str, &mut JsonObject) -> Result<(), E>,
) -> Result<(), E> {
    let serde_json::Value::Object(map) = value else {
        return Ok(());
    };
    for (key, v) in map.iter_mut() {
        match v {
            serde_json::Value::Object(info)
                if key.ends_with("Texture") && info.contains_key("index") =>
            {
                f(key, info)?;
            }
            serde_json::Value::Object(_) => visit_texture_infos(v, f)?,
            _ => {}
        }
    }
    Ok(())
}

/// A texture a material map names, as the input described it.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceTexture {
    /// The texture's name and extras as read (`source`, `sampler` and `extensions` left out:
    /// they are written from the fields below).
    pub json: serde_json::Value,
    /// Index into [`Tree::images`].
    pub image: usize,
    /// The sampler's JSON object as read (wrap modes, filters, name, extras); None: the input's
    /// texture had no sampler (repeat, filtering up to the client).
    pub sampler: Option<serde_json::Value>,
}

/// An image exactly as the input stored it, written back byte for byte (no re-encoding).
#[derive(Clone, Debug, PartialEq)]
pub struct SourceImage {
    /// The image's name (None when the input gave none).
    pub name: Option<String>,
    /// MIME type: the input's `mimeType`, else recognised from the bytes (`image/png`,
    /// `image/jpeg`).
    pub mime_type: String,
    /// The encoded file bytes.
    pub bytes: Vec<u8>,
}

impl SourceImage {
    /// The usual file extension of this image's type (`png`, `jpg`, ...; `bin` when unknown).
    pub fn extension(&self) -> &'static str {
        match self.mime_type.as_str() {
            "image/png" => "png",
            "image/jpeg" => "jpg",
            "image/webp" => "webp",
            "image/ktx2" => "ktx2",
            _ => "bin",
        }
    }
}

/// A decoded RGBA8 texture (sRGB, straight alpha).
#[derive(Clone, Debug)]
pub struct Texture {
    /// The image's name (`image<i>` when unnamed).
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height * 4` bytes, rows top to bottom.
    pub rgba: Vec<u8>,
    /// The encoded image it was decoded from (index into [`Tree::images`]), if imported.
    pub image: Option<usize>,
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, Serialize, serde::Deserialize, PartialEq)]
pub struct Bounds {
    /// Smallest x, y, z.
    pub min: [f32; 3],
    /// Largest x, y, z.
    pub max: [f32; 3],
}

impl Bounds {
    /// Bounds of a point set (zero box at the origin when empty).
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Bounds {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if lo.x > hi.x {
            lo = Vec3::ZERO;
            hi = Vec3::ZERO;
        }
        Bounds {
            min: lo.to_array(),
            max: hi.to_array(),
        }
    }
    /// Largest extent of the box.
    pub fn size(&self) -> f32 {
        (Vec3::from(self.max) - Vec3::from(self.min)).max_element()
    }
    /// Height along +Y (glTF up).
    pub fn height(&self) -> f32 {
        self.max[1] - self.min[1]
    }
    /// Length of the box's diagonal: what relative lengths (`2%`) are a fraction of.
    pub fn diagonal(&self) -> f32 {
        (Vec3::from(self.max) - Vec3::from(self.min)).length()
    }
}

/// A whole tree as imported.
#[derive(Clone, Debug)]
pub struct Tree {
    /// The file it was read from (or the name given with its bytes).
    pub source: PathBuf,
    /// Every glTF node with its rest transform, and every clip.
    pub rig: Rig,
    /// The skins' joints, each joint node once.
    pub bones: Vec<Bone>,
    /// What deforms each vertex group: the skins first (binding i is skin i), then one
    /// rigid binding per unskinned mesh node.
    pub bindings: Vec<Binding>,
    /// Every mesh instance's vertices, flattened.
    pub vertices: Vertices,
    /// Every triangle of every mesh instance, flattened.
    pub triangles: Vec<Triangle>,
    /// The materials (plus a default one when some primitive has none).
    pub materials: Vec<Material>,
    /// Decoded base-colour textures (what baking, rendering and metrics sample).
    pub textures: Vec<Texture>,
    /// The textures imported materials' maps name ([`MaterialSource`]), as in the input.
    pub source_textures: Vec<SourceTexture>,
    /// The encoded images of [`Tree::source_textures`], as in the input.
    pub images: Vec<SourceImage>,
    /// Per primitive, how it was classified as wood or foliage.
    pub classification: Vec<Classification>,
    /// Foliage triangles whose vertices were not all rigidly bound to their chosen bone.
    pub foliage_reassigned: usize,
    /// Warnings met while importing (static tree, unsupported channels, ...).
    pub warnings: Vec<String>,
    /// Rest-pose world bounds of all triangles.
    pub bounds: Bounds,
}

impl Tree {
    /// The height a LOD's screen height refers to (and metrics' distances are scaled by): the
    /// rest-pose height along +Y, or the largest extent when the tree is flat.
    pub fn height(&self) -> f32 {
        let h = self.bounds.height();
        if h > 0.0 { h } else { self.bounds.size() }
    }
    /// Skeleton depth: the longest chain of bones from a root bone.
    pub fn skeleton_depth(&self) -> u32 {
        self.bones.iter().map(|b| b.depth).max().unwrap_or(0)
    }
    /// Indices of non-degenerate foliage triangles, in file order.
    pub fn foliage(&self) -> Vec<usize> {
        self.triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| t.part == Part::Foliage && !t.degenerate)
            .map(|(i, _)| i)
            .collect()
    }
    /// Number of triangles of a part (degenerate ones included).
    pub fn count(&self, part: Part) -> usize {
        self.triangles.iter().filter(|t| t.part == part).count()
    }
    /// Number of distinct bones that foliage is bound to.
    pub fn foliage_bones(&self) -> usize {
        let mut seen = vec![false; self.bones.len()];
        for t in &self.triangles {
            if t.part == Part::Foliage
                && let Some(b) = t.bone
            {
                seen[b as usize] = true;
            }
        }
        seen.iter().filter(|s| **s).count()
    }
    /// Find a clip by name, or the first clip.
    pub fn clip_index(&self, name: Option<&str>) -> Option<usize> {
        match name {
            None => (!self.rig.clips.is_empty()).then_some(0),
            Some(n) => self.rig.clip_named(n),
        }
    }
}
