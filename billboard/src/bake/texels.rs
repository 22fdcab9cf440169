//! The downsampled atlas before dilation, and how a texel's covered samples become its bytes:
//! alpha from the covered fraction, colour in sRGB, normal encoded as glTF stores it.

use frond_render::linear_to_srgb;
use glam::Vec3;

use crate::bake::params::BakeParams;

/// Per-texel results of downsampling, before dilation.
pub(super) struct Downsampled {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) color: Vec<u8>,
    pub(super) normal: Vec<u8>,
    /// Covered supersamples per texel.
    pub(super) samples: Vec<u16>,
}

impl Downsampled {
    pub(super) fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            color: vec![0; n * 4],
            normal: vec![0; n * 4],
            samples: vec![0; n],
        }
    }
}

/// Alpha byte of a texel with `n` of `total` supersamples covered: 0 when none, 255 when all,
/// monotonic, and >= 128 exactly when `n >= needed` (the alpha-cutoff sample count).
pub(super) fn coverage_alpha(n: u32, total: u32, needed: u32) -> u8 {
    if n == 0 {
        0
    } else if n < needed {
        ((n * 127 + needed / 2) / needed).clamp(1, 127) as u8
    } else if needed == total {
        255
    } else {
        let extra = total - needed;
        (128 + ((n - needed) * 127 + extra / 2) / extra).min(255) as u8
    }
}

/// Covered supersamples (of `supersample²`) a texel needs to pass the alpha cutoff.
pub(super) fn cutoff_samples(params: &BakeParams) -> u32 {
    let total = params.supersample * params.supersample;
    (0..=total)
        .find(|&n| f64::from(n) >= f64::from(params.alpha_cutoff) * f64::from(total))
        .unwrap_or(total)
}

/// One covered texel's colour and normal bytes: `alpha` its coverage's
/// ([`coverage_alpha`]), `mean` its covered samples' linear colour, `normal_sum` the sum of
/// their normals (rgb 0 when it has no direction: "no normal", which no unit vector encodes to and
/// dilation replaces with the quad's normal).
pub(super) fn texel_bytes(alpha: u8, mean: [f32; 3], normal_sum: Vec3) -> ([u8; 4], [u8; 4]) {
    let [r, g, b] = mean.map(linear_to_srgb);
    let unit = normal_sum.normalize_or_zero();
    let normal = if unit == Vec3::ZERO {
        [0, 0, 0, alpha]
    } else {
        encode_normal(unit, alpha)
    };
    ([r, g, b, alpha], normal)
}

/// `rgb = n * 0.5 + 0.5` as bytes, with the given alpha.
pub(super) fn encode_normal(n: Vec3, alpha: u8) -> [u8; 4] {
    let e = |x: f32| round_byte((x * 0.5 + 0.5) * 255.0);
    [e(n.x), e(n.y), e(n.z), alpha]
}

/// `v.round().clamp(0.0, 255.0) as u8` (0 for a NaN), without a call to the C library's
/// `roundf` (the baseline x86-64 has no rounding instruction): `v` clamped first, which
/// changes nothing, then its integer part plus one where the rest is at least one half (the
/// rest is exact below 256), as `round` does.
#[inline]
pub(super) fn round_byte(v: f32) -> u8 {
    let c = v.clamp(0.0, 255.0);
    let whole = c as u32;
    (whole + u32::from(c - whole as f32 >= 0.5)) as u8
}
