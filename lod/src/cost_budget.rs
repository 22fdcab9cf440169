//! What a billboard LOD may spend (spec view-dependent-hierarchies-gpu §2.3–2.4: costs sized by
//! the LOD's screen height): the hard limits every engine imposes, the screen-size budgets of
//! triangles, atlas texels and joints, and the budget the chain builder gives each LOD within
//! what the LOD before it spent (the monotone rule).

use serde::{Deserialize, Deserializer, Serialize};

/// Most skin joints of any LOD: 8-bit joint indices (Unreal) and three.js's WebGPU renderer
/// and Bevy draw no more.
pub const MAX_JOINTS: usize = 256;

/// Joint budget of a LOD `screen_height` pixels high: one joint per two pixels of height
/// (60 px: 30 joints, 200 px: 100), so that far LODs meet the 32 and 128 joints of mobile and
/// web skinning while a motion that moves a leaf half a pixel at a near LOD keeps a joint of
/// its own. A cap over the half-pixel rule, not a promise.
pub fn joints_for_screen(screen_height: f32) -> usize {
    (screen_height / 2.0).ceil().max(1.0) as usize
}

/// Atlas texels per squared pixel of screen height: a tree `H` pixels high covers about
/// `0.6·H²` pixels, and its billboards overlap several layers deep, so 16 texels per `H²` is
/// about one texel per pixel of every layer.
pub const ATLAS_TEXELS_PER_SQUARED_PIXEL: f32 = 16.0;

/// Triangles per squared pixel of screen height: a tree `H` pixels high covers about `0.6·H²`
/// pixels, so 2·H² is three triangles per covered pixel. More only draws sub-pixel triangles,
/// which GPUs shade in 2×2 quads (four times over) and which change nothing a viewer sees. It
/// binds only far LODs of large trees.
pub const TRIANGLES_PER_SQUARED_PIXEL: f32 = 2.0;

/// The largest screen height (pixels) of an impostor-class LOD: the far end of a chain, where a
/// tree is a handful of pixels across and engines draw thousands of them. SpeedTree and the
/// impostor bakers switch to their billboard LOD under about 5 % of the screen height (54 px
/// of 1080); open worlds draw most of their trees at 10–30 px. Such a LOD gets the far end's
/// budget ([`impostor_triangles`], [`IMPOSTOR_JOINTS`], [`IMPOSTOR_TEXTURE_BYTES`]).
pub const IMPOSTOR_HEIGHT: f32 = 32.0;

/// Whether a LOD `screen_height` pixels high is impostor-class ([`IMPOSTOR_HEIGHT`] or less):
/// the far end, with its own budget, method and bake.
pub fn is_impostor_class(screen_height: f32) -> bool {
    screen_height <= IMPOSTOR_HEIGHT
}

/// The coverage error an impostor-class LOD is judged against, whatever `--max-error` says of
/// the nearer ones: at the far end almost every pixel of a crown is partly covered, and even a
/// view-aligned impostor resampled through a texel grid misses part of each (spec
/// animated-billboard-clouds §5.4, filtered).
pub const IMPOSTOR_MAX_ERROR: f64 = 0.15;

/// Skin joints of an impostor-class LOD: within every engine's cheapest skinning path (mobile
/// GPUs' 8-bone palettes), and the number of motion clusters its foliage is given.
pub const IMPOSTOR_JOINTS: usize = 8;

/// Decoded texture bytes of an impostor-class LOD over all its images (colour and normal
/// atlases, bark): 256 KiB counted with a full mip chain (4/3), so 192 KiB of level 0. Every
/// instance of a species shares its far LOD's images, so they are no per-instance cost: the
/// budget buys [`IMPOSTOR_TEXELS_PER_PIXEL`] texels a pixel over the crown's billboards.
pub const IMPOSTOR_TEXTURE_BYTES: usize = 256 * 1024 * 3 / 4;

/// Billboard texels per screen pixel, each axis, of an impostor-class LOD: two, at which a
/// texel grid resampled at a random offset keeps a crown's covered fraction per pixel (the
/// far end's texels hold covered fractions; one texel a pixel blurs each leaf over four).
pub const IMPOSTOR_TEXELS_PER_PIXEL: f32 = 2.0;

/// Triangles of an impostor-class LOD of a tree of `input_triangles`: 1 % of them, at least 64
/// (a trunk and a few dozen billboards), at most 512 (a crown this far is a few hundred pixels,
/// and GPUs draw sub-pixel triangles at a quarter of their rate).
pub fn impostor_triangles(input_triangles: usize) -> usize {
    (input_triangles / 100).clamp(64, 512)
}

/// What one billboard LOD may spend, from the hard limits, the previous LOD and its screen
/// height (in that order of precedence).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodBudget {
    /// Triangles drawn: wood plus foliage.
    pub triangles: usize,
    /// Wood triangles (LOD0's share of wood in its triangles).
    pub wood_triangles: usize,
    /// Skin joints (rig joints, motion joints and the static joint together).
    pub joints: usize,
    /// Animated channels written over all clips.
    pub channels: usize,
    /// Decoded texture bytes (atlas and wood maps).
    pub texture_bytes: usize,
    /// Alpha-tested area (world units², cards or billboards; `null` when unbounded): the
    /// previous LOD's, so that no LOD asks for more overdraw. Card LODs keep within it;
    /// billboard methods do not yet control their quads' area, and `frond lod` warns when a
    /// written LOD exceeds its predecessor's.
    #[serde(deserialize_with = "null_as_unbounded")]
    pub alpha_tested_area: f64,
}

impl LodBudget {
    /// No budget but the hard limits (at most `joints` per skin).
    pub(crate) fn hard_limits_only(joints: usize) -> LodBudget {
        LodBudget {
            triangles: usize::MAX,
            wood_triangles: usize::MAX,
            joints,
            channels: usize::MAX,
            texture_bytes: usize::MAX,
            alpha_tested_area: f64::INFINITY,
        }
    }
}

/// Reads an area written `null` (JSON has no infinity) as unbounded.
fn null_as_unbounded<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}
