//! What a bake may be asked for: [`BakeParams`], the rasteriser choice, and their limits.

use crate::bake::baked::BakeError;

/// Largest supported atlas side: keeps both RGBA8 atlases under 2 GiB together.
pub const MAX_ATLAS_SIDE: u32 = 16384;
/// Largest supported supersampling factor per axis.
pub const MAX_SUPERSAMPLE: u32 = 16;

/// Settings of [`bake_cloud`](crate::bake_cloud).
#[derive(Clone, Debug, PartialEq)]
pub struct BakeParams {
    /// Texels per world unit along both quad axes (uniform density, improved-billboard-cloud
    /// §4 item 1); lowered automatically when the atlas would exceed `max_atlas`.
    pub texels_per_unit: f32,
    /// Supersampling factor per axis (4 gives the spec's 4x4, §4 item 4), 1..=16.
    pub supersample: u32,
    /// Texels of dilated padding around each quad's texture inside the atlas (§4 item 5: 4 is
    /// "probably a suitable general choice").
    pub padding: u32,
    /// Largest atlas width and height in texels, 4..=[`MAX_ATLAS_SIDE`].
    pub max_atlas: u32,
    /// Fraction of a texel's supersamples that must be covered for it to pass the billboard's
    /// alpha test at 0.5 (stored alpha >= 128 exactly then; §4 item 6), in (0, 1].
    pub alpha_cutoff: f32,
    /// Smallest texture side per quad, in texels.
    pub min_side: u32,
    /// Largest texture side per quad, in texels (a longer side scales the quad's texture
    /// down, keeping its aspect ratio).
    pub max_side: u32,
    /// Per quad, move the alpha-test threshold so that as many texels pass as the quad's
    /// summed coverage (in texels) times its foreshortening (its leaves' area over their
    /// projection onto it, [`foreshortening`](crate::bake::foreshortening)): sparse foliage
    /// baked at low resolution keeps its density instead of vanishing where no texel is half
    /// covered (the coverage-preserving rule the renderer's mip chains use), and leaves
    /// flattened onto a plane at an angle keep what they cover seen from every side, growing
    /// texels beside the covered ones where those are too few. Off: a texel passes when
    /// `alpha_cutoff` of it is covered.
    pub preserve_coverage: bool,
    /// With `preserve_coverage`, every quad's coverage is scaled by this besides its
    /// foreshortening: the correction [`bake_keeping_view_coverage`](crate::view_coverage::bake_keeping_view_coverage)
    /// finds so that the cloud covers as much as its leaves seen from around them. 1 keeps
    /// each quad's own rule.
    pub coverage_gain: f64,
    /// Each texel's alpha is the fraction of it covered, scaled as `preserve_coverage`
    /// scales each quad's coverage (the whole cell's covered area kept, a texel's alpha
    /// at most 1): for a far LOD drawn blended (glTF
    /// `BLEND`), where almost every pixel of a crown is partly covered and an alpha-tested texel
    /// covers all of a pixel or none ([`Atlas::blended`](crate::Atlas::blended)). Off: alpha-tested bytes.
    pub covered_fraction: bool,
    /// Which rasteriser draws the atlas: the CPU bake rasteriser (default: the same atlas on
    /// every machine) or the wgpu renderer (a GPU, when there is one).
    pub rasteriser: BakeRasteriser,
}

/// The rasteriser that draws a cloud's atlas ([`BakeParams::rasteriser`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BakeRasteriser {
    /// [`frond_render::BakeTarget`]: one pass over the atlas, cells in parallel, colour and
    /// normals together; byte-identical output whatever the machine or thread count.
    #[default]
    Cpu,
    /// [`Renderer::render_view`](frond_render::Renderer::render_view) in tiles, a colour then a normal pass: fast on a GPU, and
    /// what the adapter's rasteriser makes of the samples.
    Wgpu,
}

impl Default for BakeParams {
    /// 64 texels per unit, 4x4 supersampling, 4 texels of padding, atlases up to 4096²,
    /// majority coverage, texture sides 4..=1024 (animated-billboard-clouds §2.4 \[ENG\]).
    fn default() -> Self {
        Self {
            texels_per_unit: 64.0,
            supersample: 4,
            padding: 4,
            max_atlas: 4096,
            alpha_cutoff: 0.5,
            min_side: 4,
            max_side: 1024,
            preserve_coverage: false,
            coverage_gain: 1.0,
            covered_fraction: false,
            rasteriser: BakeRasteriser::Cpu,
        }
    }
}

pub(super) fn validate_params(p: &BakeParams) -> Result<(), BakeError> {
    let bad = |m: String| Err(BakeError::InvalidParams(m));
    if !(p.texels_per_unit.is_finite() && p.texels_per_unit > 0.0) {
        return bad(format!(
            "texels_per_unit must be finite and positive, got {}",
            p.texels_per_unit
        ));
    }
    if !(1..=MAX_SUPERSAMPLE).contains(&p.supersample) {
        return bad(format!(
            "supersample must be in 1..={MAX_SUPERSAMPLE}, got {}",
            p.supersample
        ));
    }
    if !(4..=MAX_ATLAS_SIDE).contains(&p.max_atlas) {
        return bad(format!(
            "max_atlas must be in 4..={MAX_ATLAS_SIDE}, got {}",
            p.max_atlas
        ));
    }
    if p.padding > p.max_atlas {
        return bad(format!(
            "padding {} exceeds max_atlas {}",
            p.padding, p.max_atlas
        ));
    }
    if p.min_side == 0 || p.max_side < p.min_side {
        return bad(format!(
            "need 1 <= min_side <= max_side, got {}..{}",
            p.min_side, p.max_side
        ));
    }
    if !(p.alpha_cutoff > 0.0 && p.alpha_cutoff <= 1.0) {
        return bad(format!(
            "alpha_cutoff must be in (0, 1], got {}",
            p.alpha_cutoff
        ));
    }
    if !(p.coverage_gain.is_finite() && p.coverage_gain > 0.0) {
        return bad(format!(
            "coverage_gain must be finite and positive, got {}",
            p.coverage_gain
        ));
    }
    Ok(())
}
