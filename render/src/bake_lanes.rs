//! The arithmetic of the bake's shading on eight samples of a row at once (AVX2), where one
//! triangle won them: the weights at each sample, the perspective-correct texture coordinates
//! and their bilinear footprints in the trilinear pair's levels, and the unit normal. Each
//! lane does exactly the scalar resolve's operations in its order (a multiply, then an add:
//! no fused multiply-add), so both give the same bits on every machine. The texels are then
//! read lane by lane ([`crate::software::sampling::LinearLevel::bilinear_at`]): gathering them was no
//! faster on an AMD EPYC than reading them, and the divisions and square root are what
//! vectors save. A lane whose footprint would wrap is left to the scalar path.
//!
//! Hand-written because the compiler does not vectorise the scalar resolve (it branches per
//! sample), and the operations must stay the scalar ones, in their order.

#[cfg(target_arch = "x86_64")]
use crate::sample_lanes::{span_weights, weighted_sum};

/// What the eight-sample arithmetic needs of the triangle that won the samples.
#[derive(Clone, Copy)]
pub(crate) struct ShadeLanes {
    /// Sample-space corners.
    pub(crate) x: [f32; 3],
    pub(crate) y: [f32; 3],
    pub(crate) inv_area: f32,
    /// `1/w` and texture coordinates divided by `w` at the corners.
    pub(crate) q: [f32; 3],
    pub(crate) uq: [[f32; 2]; 3],
    /// Normals divided by `w` at the corners.
    pub(crate) nq: [[f32; 3]; 3],
    /// The texture coordinates at the corners of an affine triangle, summed without dividing
    /// by `Σ b·q` ([`crate::software::setup::affine_uv`]).
    pub(crate) affine: Option<[[f32; 2]; 3]>,
    /// The normal is the same at every sample (found once, elsewhere): not computed here.
    pub(crate) flat: bool,
    /// A back face: its normal is turned to face the viewer.
    pub(crate) back: bool,
    /// The sizes of the levels whose footprints are found (the trilinear pair's, the second
    /// when blended in); none for an untextured material.
    pub(crate) levels: [Option<[u32; 2]>; 2],
}

/// Eight samples' arithmetic: lane `i` is sample `x + i`.
#[derive(Default)]
pub(crate) struct LaneShading {
    /// The lanes done here (the others are left to the scalar path).
    pub(crate) done: u32,
    /// Of those, the lanes with a normal (not too short to normalise); none when the
    /// triangle is flat.
    pub(crate) with_normal: u32,
    /// Per level, per lane: the footprint's top-left texel and its weights.
    pub(crate) first: [[i32; 8]; 2],
    pub(crate) fx: [[f32; 8]; 2],
    pub(crate) fy: [[f32; 8]; 2],
    /// Per axis, per lane: the unit normal facing the viewer (not when the triangle is flat).
    pub(crate) normal: [[f32; 8]; 3],
}

impl ShadeLanes {
    /// The arithmetic of the samples `x..x + 8` of sample row `y` in the lanes of `wanted`
    /// (see the module docs).
    ///
    /// # Safety
    /// The machine must have AVX2 ([`crate::sample_lanes::available`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(crate) unsafe fn shade(&self, x: usize, y: usize, wanted: u32) -> LaneShading {
        use std::arch::x86_64::*;
        let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let mut done = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_and_si256(_mm256_set1_epi32(wanted as i32), bits),
            bits,
        ));
        // `(x + i) as f32 + 0.5`: exact below 2²⁴ (a target is at most 2¹⁵ samples a side).
        let px = _mm256_add_ps(
            _mm256_cvtepi32_ps(_mm256_add_epi32(
                _mm256_set1_epi32(x as i32),
                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
            )),
            _mm256_set1_ps(0.5),
        );
        let py = y as f32 + 0.5;
        // `Setup::weights`: `(x[b] − x[a])·(py − y[a]) − (y[b] − y[a])·(px − x[a])`, times the
        // inverse area.
        let (sx, sy) = (self.x, self.y);
        let edge = |a: usize, b: usize| {
            let first = _mm256_set1_ps((sx[b] - sx[a]) * (py - sy[a]));
            let second = _mm256_mul_ps(
                _mm256_set1_ps(sy[b] - sy[a]),
                _mm256_sub_ps(px, _mm256_set1_ps(sx[a])),
            );
            _mm256_mul_ps(_mm256_sub_ps(first, second), _mm256_set1_ps(self.inv_area))
        };
        let b = [edge(1, 2), edge(2, 0), edge(0, 1)];
        // `Σ b·a` left to right, as `Setup::uv` and glam's sums.
        let dot = |a: [f32; 3]| weighted_sum(&b, a);
        let q = dot(self.q);
        let mut out = LaneShading::default();
        if self.levels[0].is_some() {
            let (u, v) = match self.affine {
                Some(c) => (dot(c.map(|t| t[0])), dot(c.map(|t| t[1]))),
                None => (
                    _mm256_div_ps(dot(self.uq.map(|c| c[0])), q),
                    _mm256_div_ps(dot(self.uq.map(|c| c[1])), q),
                ),
            };
            for (k, level) in self.levels.iter().enumerate() {
                let Some([w, h]) = *level else {
                    continue;
                };
                // `footprint_of`: `uv·size − 0.5`, its floor and the rest; kept where the
                // footprint does not wrap (`0 ≤ x0`, `x0 + 1 < w`; a NaN is neither).
                let half = _mm256_set1_ps(0.5);
                let fx = _mm256_sub_ps(_mm256_mul_ps(u, _mm256_set1_ps(w as f32)), half);
                let fy = _mm256_sub_ps(_mm256_mul_ps(v, _mm256_set1_ps(h as f32)), half);
                let (x0, y0) = (_mm256_floor_ps(fx), _mm256_floor_ps(fy));
                let zero = _mm256_setzero_ps();
                let within = |c: __m256, n: u32| {
                    _mm256_and_ps(
                        _mm256_cmp_ps::<_CMP_GE_OQ>(c, zero),
                        _mm256_cmp_ps::<_CMP_LT_OQ>(
                            _mm256_add_ps(c, _mm256_set1_ps(1.0)),
                            _mm256_set1_ps(n as f32),
                        ),
                    )
                };
                done = _mm256_and_ps(done, _mm256_and_ps(within(x0, w), within(y0, h)));
                let first = _mm256_add_epi32(
                    _mm256_mullo_epi32(
                        _mm256_cvttps_epi32(_mm256_and_ps(y0, done)),
                        _mm256_set1_epi32(w as i32),
                    ),
                    _mm256_cvttps_epi32(_mm256_and_ps(x0, done)),
                );
                // SAFETY: unaligned stores of eight values into arrays of eight.
                unsafe {
                    _mm256_storeu_si256(out.first[k].as_mut_ptr().cast(), first);
                    _mm256_storeu_ps(out.fx[k].as_mut_ptr(), _mm256_sub_ps(fx, x0));
                    _mm256_storeu_ps(out.fy[k].as_mut_ptr(), _mm256_sub_ps(fy, y0));
                }
            }
        }
        out.done = _mm256_movemask_ps(done) as u32;
        if out.done == 0 || self.flat {
            return out;
        }
        // `(b0·nq0 + b1·nq1 + b2·nq2) / q`, its squared length `(x² + y²) + z²`, then
        // `n · (1 / √len²)` (glam's `normalize`).
        let n = [0, 1, 2].map(|c| _mm256_div_ps(dot(self.nq.map(|v| v[c])), q));
        let len2 = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(n[0], n[0]), _mm256_mul_ps(n[1], n[1])),
            _mm256_mul_ps(n[2], n[2]),
        );
        let long = _mm256_cmp_ps::<_CMP_GT_OQ>(len2, _mm256_set1_ps(1e-12));
        out.with_normal = _mm256_movemask_ps(long) as u32 & out.done;
        let recip = _mm256_div_ps(_mm256_set1_ps(1.0), _mm256_sqrt_ps(len2));
        for (c, n) in n.into_iter().enumerate() {
            let unit = _mm256_mul_ps(n, recip);
            let facing = if self.back {
                _mm256_xor_ps(unit, _mm256_set1_ps(-0.0))
            } else {
                unit
            };
            // SAFETY: as above.
            unsafe { _mm256_storeu_ps(out.normal[c].as_mut_ptr(), facing) };
        }
        out
    }

    /// Never called: [`crate::sample_lanes::available`] is false off x86-64.
    ///
    /// # Safety
    /// None needed; it only mirrors the x86-64 signature.
    #[cfg(not(target_arch = "x86_64"))]
    pub(crate) unsafe fn shade(&self, _: usize, _: usize, _: u32) -> LaneShading {
        unreachable!("eight-sample lanes are only used where available() is true")
    }
}

/// The depth test of eight samples `x..x + 8` of a row in the lanes of `hits` (those whose
/// alpha test passed), whose weights at the span's first sample are `start`, changing by
/// `step` a sample, with `k0 = x − x0` ([`crate::software::spans::RowSpan`]): each lane whose
/// depth, interpolated from the corners' `z`, is below `depth`'s there takes it and the
/// triangle `ti` in `winner`. Every operation is the scalar test's, in its order: the same
/// depths and winners. The other lanes are written back as read.
///
/// # Safety
/// The machine must have AVX2 ([`crate::sample_lanes::available`]); `depth` and `winner`
/// hold at least eight entries.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[expect(
    clippy::too_many_arguments,
    reason = "a row span's and a triangle's parts"
)]
pub(crate) unsafe fn depth_test(
    k0: i32,
    start: [f32; 3],
    step: [f32; 3],
    z: [f32; 3],
    hits: u32,
    ti: u32,
    depth: &mut [f32],
    winner: &mut [u32],
) {
    use std::arch::x86_64::*;
    assert!(depth.len() >= 8 && winner.len() >= 8);
    // `RowSpan::weights_at`, then `Σ b·z` left to right.
    let lane_z = weighted_sum(&span_weights(k0, start, step), z);
    let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let wanted = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
        _mm256_and_si256(_mm256_set1_epi32(hits as i32), bits),
        bits,
    ));
    // SAFETY: both slices hold eight entries (asserted); unaligned loads and stores.
    unsafe {
        let old = _mm256_loadu_ps(depth.as_ptr());
        // `z < depth`: false on a NaN, as the scalar comparison.
        let take = _mm256_and_ps(wanted, _mm256_cmp_ps::<_CMP_LT_OQ>(lane_z, old));
        _mm256_storeu_ps(depth.as_mut_ptr(), _mm256_blendv_ps(old, lane_z, take));
        let owner = _mm256_loadu_si256(winner.as_ptr().cast());
        let new = _mm256_blendv_epi8(
            owner,
            _mm256_set1_epi32(ti as i32),
            _mm256_castps_si256(take),
        );
        _mm256_storeu_si256(winner.as_mut_ptr().cast(), new);
    }
}

/// Never called: [`crate::sample_lanes::available`] is false off x86-64.
///
/// # Safety
/// None needed; it only mirrors the x86-64 signature.
#[cfg(not(target_arch = "x86_64"))]
#[expect(
    clippy::too_many_arguments,
    reason = "a row span's and a triangle's parts"
)]
pub(crate) unsafe fn depth_test(
    _: i32,
    _: [f32; 3],
    _: [f32; 3],
    _: [f32; 3],
    _: u32,
    _: u32,
    _: &mut [f32],
    _: &mut [u32],
) {
    unreachable!("eight-sample lanes are only used where available() is true")
}
