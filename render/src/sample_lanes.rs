//! A coverage render's per-sample work on eight samples of a row at once (AVX2): the inside
//! test, the perspective-correct texture coordinates and the alpha test decided from a
//! footprint bounds table ([`crate::software::alpha::AlphaBounds`]), the three steps that
//! take most of a coverage render's time. Each lane does exactly the scalar rasteriser's
//! operations in its order (a multiply, then an add: no fused multiply-add, which would round
//! differently), so both paths give the same bits and the same masks on every machine. The
//! samples the table leaves open are filtered here too (the trilinear filter and its edge
//! wrap); only a footprint reaching further off its level goes back, with its coordinates, to
//! the scalar filter.
//!
//! Hand-written because what it vectorises is a gather from a per-texture table keyed by
//! computed texel coordinates, which no SIMD crate's safe API expresses and which the
//! compiler does not vectorise from the scalar loop (it branches per sample).

use frond_scene::Wrap;

/// What one triangle's eight-sample test needs, fixed for all of its rows: its attributes,
/// and the bounds table of the mip level its samples are decided in.
#[derive(Clone, Copy)]
pub(crate) struct TriangleLanes<'a> {
    /// `1/w` at the corners.
    pub(crate) q: [f32; 3],
    /// Texture coordinates divided by `w`.
    pub(crate) uq: [[f32; 2]; 3],
    /// The texture coordinates at the corners of an affine triangle, summed as they are
    /// without dividing by `Σ b·q` (the bake's: [`crate::software::setup::affine_uv`]); `None`
    /// divides.
    pub(crate) affine: Option<[[f32; 2]; 3]>,
    /// The test itself: an opaque material passes every inside sample.
    pub(crate) test: LaneTest<'a>,
}

/// How a lane's alpha test is decided.
#[derive(Clone, Copy)]
pub(crate) enum LaneTest<'a> {
    /// No alpha test: every sample inside the triangle is covered.
    Opaque,
    /// A bounds table of the filter's first level, `filter.a` (each entry `[least, greatest]`
    /// alpha of a footprint, one padding entry past the last so that a 4-byte gather of the
    /// last entry stays within it): a footprint passes when its least alpha is at least
    /// `pass_from` and fails when its greatest is below `fail_below`; the samples it leaves
    /// open are `filter`ed.
    Table {
        table: &'a [[u8; 2]],
        pass_from: u16,
        fail_below: u16,
        filter: LaneFilter<'a>,
    },
    /// The bilinear alpha of `filter.a` (a single level: `filter.b` is not read) from one
    /// gather of a footprint's four texels, `quads` holding them for every footprint within
    /// the level (`crate::software::alpha::footprint_quads`); only the footprints on the level's
    /// last row or column (which wrap) are left to `filter`. The same answers as `Table` of
    /// the same level and test, which decides from bounds only what this filter would.
    Quads {
        quads: &'a [u32],
        /// The least alpha (bytes' units) that passes, where the test is monotone: then one
        /// comparison decides (the same answers).
        least_passing: Option<f32>,
        filter: LaneFilter<'a>,
    },
}

/// The scalar alpha test's filter (`Levels::alpha_test` after its bounds): the bilinear alpha
/// of level `a`, blended by `f` with level `b`'s when trilinear, then
/// `alpha / 255 · scale ≥ cutoff`. Lanes whose footprint leaves a level (it would wrap) stay
/// open, for the scalar path.
#[derive(Clone, Copy)]
pub(crate) struct LaneFilter<'a> {
    pub(crate) a: LaneLevel<'a>,
    /// The second level of a trilinear filter (its weight `f` above zero).
    pub(crate) b: Option<LaneLevel<'a>>,
    pub(crate) f: f32,
    pub(crate) scale: f32,
    pub(crate) cutoff: f32,
}

/// One alpha-only mip level: `width · height` texels, a byte each, sampled with `wrap`.
#[derive(Clone, Copy)]
pub(crate) struct LaneLevel<'a> {
    pub(crate) texels: &'a [u8],
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) wrap: [Wrap; 2],
}

/// One row's eight samples `x..x + 8` tested: bit `i` of each mask is sample `x + i`.
pub(crate) struct LaneResult {
    /// Inside the triangle and passing the alpha test.
    pub(crate) pass: u32,
    /// Inside, the test left to the filter: their coordinates are `u`, `v`.
    pub(crate) open: u32,
    pub(crate) u: [f32; 8],
    pub(crate) v: [f32; 8],
}

impl LaneResult {
    /// The lanes of `todo` that pass: those passed here, and the open ones that `test` (the
    /// scalar test) passes at their coordinates.
    #[inline]
    pub(crate) fn passing(&self, todo: u32, test: impl Fn([f32; 2]) -> bool) -> u32 {
        let mut hits = self.pass & todo;
        let mut open = self.open & todo;
        while open != 0 {
            let i = open.trailing_zeros() as usize;
            open &= open - 1;
            if test([self.u[i], self.v[i]]) {
                hits |= 1 << i;
            }
        }
        hits
    }
}

/// Whether this machine runs [`TriangleLanes::test`] (checked once per render by the caller).
pub(crate) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The lanes of `bits` as a vector mask (all ones where set).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn lane_mask(bits: u32) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let lane = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let set = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane);
    _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane))
}

/// The weights of the samples `k0..k0 + 8` of a row span ([`crate::software::spans::RowSpan`]:
/// `start + step · k`, a multiply then an add, as `RowSpan::weights_at`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn span_weights(
    k0: i32,
    start: [f32; 3],
    step: [f32; 3],
) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let k = _mm256_cvtepi32_ps(_mm256_add_epi32(
        _mm256_set1_epi32(k0),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
    ));
    [0, 1, 2].map(|j| {
        _mm256_add_ps(
            _mm256_set1_ps(start[j]),
            _mm256_mul_ps(_mm256_set1_ps(step[j]), k),
        )
    })
}

/// `Σ b·a` of eight lanes of weights `b`, left to right (`(b0·a0 + b1·a1) + b2·a2`): the
/// scalar sums' roundings, shared by the lanes here and the bake's ([`crate::bake_lanes`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn weighted_sum(
    b: &[std::arch::x86_64::__m256; 3],
    a: [f32; 3],
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(b[0], _mm256_set1_ps(a[0])),
            _mm256_mul_ps(b[1], _mm256_set1_ps(a[1])),
        ),
        _mm256_mul_ps(b[2], _mm256_set1_ps(a[2])),
    )
}

/// The scalar `bilinear` alpha (`footprint`, then `bilerp` of the four texels) of `level` at
/// `(u, v)` in the lanes of `wanted`, and the lanes it was computed for: those whose footprint
/// reaches at most one texel past the level's edges, where it wraps as `wrap_index` has it
/// (the others, and every lane of a level under 4 texels, are left to the scalar path).
///
/// # Safety
/// AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn bilinear(
    level: &LaneLevel,
    u: std::arch::x86_64::__m256,
    v: std::arch::x86_64::__m256,
    wanted: std::arch::x86_64::__m256,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    use std::arch::x86_64::*;
    if level.texels.len() < 4 {
        return (_mm256_setzero_ps(), _mm256_setzero_ps());
    }
    let half = _mm256_set1_ps(0.5);
    let x = _mm256_sub_ps(_mm256_mul_ps(u, _mm256_set1_ps(level.width as f32)), half);
    let y = _mm256_sub_ps(_mm256_mul_ps(v, _mm256_set1_ps(level.height as f32)), half);
    let (x0, y0) = (_mm256_floor_ps(x), _mm256_floor_ps(y));
    let (fx, fy) = (_mm256_sub_ps(x, x0), _mm256_sub_ps(y, y0));
    // The first texel within one of the level (a NaN coordinate is not).
    let near = |c: __m256, n: u32| {
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(c, _mm256_set1_ps(-1.0)),
            _mm256_cmp_ps::<_CMP_LT_OQ>(c, _mm256_set1_ps(n as f32)),
        )
    };
    let on = _mm256_and_ps(
        _mm256_and_ps(near(x0, level.width), near(y0, level.height)),
        wanted,
    );
    // `wrap_index` of `c` and `c + 1` along a side of `n` texels, for `c` in `-1..n`.
    let wrapped = |c: __m256, n: u32, wrap: Wrap| {
        let c = _mm256_cvttps_epi32(_mm256_and_ps(c, on));
        let next = _mm256_add_epi32(c, _mm256_set1_epi32(1));
        let (before, after) = match wrap {
            Wrap::Repeat => (n as i32 - 1, 0),
            Wrap::ClampToEdge | Wrap::MirroredRepeat => (0, n as i32 - 1),
        };
        (
            _mm256_blendv_epi8(
                c,
                _mm256_set1_epi32(before),
                _mm256_cmpeq_epi32(c, _mm256_set1_epi32(-1)),
            ),
            _mm256_blendv_epi8(
                next,
                _mm256_set1_epi32(after),
                _mm256_cmpeq_epi32(next, _mm256_set1_epi32(n as i32)),
            ),
        )
    };
    let (xa, xb) = wrapped(x0, level.width, level.wrap[0]);
    let (ya, yb) = wrapped(y0, level.height, level.wrap[1]);
    let width = _mm256_set1_epi32(level.width as i32);
    let (top, bottom) = (_mm256_mullo_epi32(ya, width), _mm256_mullo_epi32(yb, width));
    // A texel at `o` read as four bytes from at most three bytes before it, so that the read
    // stays within the level.
    let last = _mm256_set1_epi32(level.texels.len() as i32 - 4);
    let mask = _mm256_castps_si256(on);
    let texel = |o: __m256i| {
        let read = _mm256_min_epi32(o, last);
        let shift = _mm256_slli_epi32::<3>(_mm256_sub_epi32(o, read));
        // SAFETY: on lanes read `read..read + 4`, within the texels (`o` is a texel of the
        // level and the level has at least four); off lanes are not read.
        let bytes = unsafe {
            _mm256_mask_i32gather_epi32::<1>(
                _mm256_setzero_si256(),
                level.texels.as_ptr().cast::<i32>(),
                read,
                mask,
            )
        };
        _mm256_cvtepi32_ps(_mm256_and_si256(
            _mm256_srlv_epi32(bytes, shift),
            _mm256_set1_epi32(0xff),
        ))
    };
    let a = texel(_mm256_add_epi32(top, xa));
    let b = texel(_mm256_add_epi32(top, xb));
    let c = texel(_mm256_add_epi32(bottom, xa));
    let d = texel(_mm256_add_epi32(bottom, xb));
    // `bilerp`: the same operations in the same order.
    let upper = _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), fx));
    let lower = _mm256_add_ps(c, _mm256_mul_ps(_mm256_sub_ps(d, c), fx));
    let value = _mm256_add_ps(upper, _mm256_mul_ps(_mm256_sub_ps(lower, upper), fy));
    (value, on)
}

/// [`LaneTest::Quads`] of the samples at `(u, v)` in the lanes of `inside`: the lanes whose
/// footprint lies within the level filtered from its quad and passed or not, the others
/// (inside) left open for `filter` ([`TriangleLanes::test`]).
///
/// # Safety
/// AVX2. `quads` must hold an entry for every footprint within `filter.a`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn quads_decide(
    quads: &[u32],
    least_passing: Option<f32>,
    filter: &LaneFilter,
    u: std::arch::x86_64::__m256,
    v: std::arch::x86_64::__m256,
    inside: std::arch::x86_64::__m256,
) -> LaneResult {
    use std::arch::x86_64::*;
    let level = &filter.a;
    let half = _mm256_set1_ps(0.5);
    // `bilinear`'s footprint: `floor(u·w − 0.5)`, its weights the remainders.
    let x = _mm256_sub_ps(_mm256_mul_ps(u, _mm256_set1_ps(level.width as f32)), half);
    let y = _mm256_sub_ps(_mm256_mul_ps(v, _mm256_set1_ps(level.height as f32)), half);
    let (x0, y0) = (_mm256_floor_ps(x), _mm256_floor_ps(y));
    let (fx, fy) = (_mm256_sub_ps(x, x0), _mm256_sub_ps(y, y0));
    // Within the level: its first texel at most the last but one of its row and column (a
    // NaN is not).
    let within = |c: __m256, n: u32| {
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(c, _mm256_setzero_ps()),
            _mm256_cmp_ps::<_CMP_LT_OQ>(c, _mm256_set1_ps(n as f32 - 1.0)),
        )
    };
    let on = _mm256_and_ps(
        _mm256_and_ps(within(x0, level.width), within(y0, level.height)),
        inside,
    );
    let cell = _mm256_add_epi32(
        _mm256_mullo_epi32(
            _mm256_cvttps_epi32(_mm256_and_ps(y0, on)),
            _mm256_set1_epi32(level.width as i32),
        ),
        _mm256_cvttps_epi32(_mm256_and_ps(x0, on)),
    );
    // SAFETY: an on lane's cell is a footprint within the level, which `quads` holds; off
    // lanes are not read.
    let quad = unsafe {
        _mm256_mask_i32gather_epi32::<4>(
            _mm256_setzero_si256(),
            quads.as_ptr().cast::<i32>(),
            cell,
            _mm256_castps_si256(on),
        )
    };
    let byte = |shift: i32| {
        _mm256_cvtepi32_ps(_mm256_and_si256(
            _mm256_srlv_epi32(quad, _mm256_set1_epi32(shift)),
            _mm256_set1_epi32(0xff),
        ))
    };
    let (a, b, c, d) = (byte(0), byte(8), byte(16), byte(24));
    // `bilerp`: the same operations in the same order.
    let upper = _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), fx));
    let lower = _mm256_add_ps(c, _mm256_mul_ps(_mm256_sub_ps(d, c), fx));
    let alpha = _mm256_add_ps(upper, _mm256_mul_ps(_mm256_sub_ps(lower, upper), fy));
    // `passes_cutoff`: kept unless below the cutoff (a NaN is kept).
    let passes = match least_passing {
        Some(least) => _mm256_cmp_ps::<_CMP_NLT_UQ>(alpha, _mm256_set1_ps(least)),
        None => {
            let tested = _mm256_mul_ps(
                _mm256_div_ps(alpha, _mm256_set1_ps(255.0)),
                _mm256_set1_ps(filter.scale),
            );
            _mm256_cmp_ps::<_CMP_NLT_UQ>(tested, _mm256_set1_ps(filter.cutoff))
        }
    };
    let on_bits = _mm256_movemask_ps(on) as u32;
    LaneResult {
        pass: on_bits & _mm256_movemask_ps(passes) as u32,
        open: _mm256_movemask_ps(inside) as u32 & !on_bits,
        u: [0.0; 8],
        v: [0.0; 8],
    }
}

impl TriangleLanes<'_> {
    /// Tests the samples `x..x + 8` of a row whose weights at sample `x0` are `start`, changing
    /// by `step` a sample ([`crate::software::spans::RowSpan`]), with `k0 = x − x0`: the inside
    /// test, the texture coordinates where a texture is read, the decision by the triangle's
    /// table or quads, and the filter of the lanes they leave open.
    ///
    /// # Safety
    /// The machine must have AVX2 ([`available`]). A `Quads` table must hold every footprint
    /// within its level, and a `Table` `width · height + 1`
    /// entries.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) unsafe fn test(&self, k0: i32, start: [f32; 3], step: [f32; 3]) -> LaneResult {
        use std::arch::x86_64::*;
        // The scalar `start + step · k`, then `Σ b·a` left to right: the same roundings.
        let b = span_weights(k0, start, step);
        let inside = inside_lanes(&b);
        let inside_bits = _mm256_movemask_ps(inside) as u32;
        if inside_bits == 0 {
            return LaneResult::decided(0);
        }
        let (mut r, filter, u, v) = match self.test {
            LaneTest::Opaque => return LaneResult::decided(inside_bits),
            LaneTest::Quads {
                quads,
                least_passing,
                filter,
            } => {
                let (u, v) = self.texture_coordinates(&b);
                // SAFETY: AVX2, as this function's; a `Quads` test's table holds every
                // footprint within its level.
                let r = unsafe { quads_decide(quads, least_passing, &filter, u, v, inside) };
                (r, filter, u, v)
            }
            LaneTest::Table {
                table,
                pass_from,
                fail_below,
                filter,
            } => {
                let (u, v) = self.texture_coordinates(&b);
                let thresholds = [pass_from, fail_below];
                // SAFETY: AVX2, as this function's; a `Table` test's table has
                // `width · height + 1` entries.
                let r = unsafe { table_decide(table, thresholds, &filter.a, (u, v), inside) };
                (r, filter, u, v)
            }
        };
        if r.open != 0 {
            filter_open(&mut r, &filter, u, v);
        }
        if r.open != 0 {
            // SAFETY: unaligned stores of eight floats into arrays of eight.
            unsafe {
                _mm256_storeu_ps(r.u.as_mut_ptr(), u);
                _mm256_storeu_ps(r.v.as_mut_ptr(), v);
            }
        }
        r
    }

    /// The texture coordinates of the eight samples at weights `b`: summed as they are on an
    /// affine triangle, divided by `Σ b·q` otherwise (the scalar `Setup::uv`'s operations).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    fn texture_coordinates(
        &self,
        b: &[std::arch::x86_64::__m256; 3],
    ) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
        use std::arch::x86_64::*;
        let dot = |a: [f32; 3]| weighted_sum(b, a);
        match self.affine {
            Some(c) => (dot(c.map(|t| t[0])), dot(c.map(|t| t[1]))),
            None => {
                let q = dot(self.q);
                (
                    _mm256_div_ps(dot(self.uq.map(|t| t[0])), q),
                    _mm256_div_ps(dot(self.uq.map(|t| t[1])), q),
                )
            }
        }
    }

    /// Never called: [`available`] is false off x86-64.
    ///
    /// # Safety
    /// None needed; it only mirrors the x86-64 signature.
    #[cfg(not(target_arch = "x86_64"))]
    pub(crate) unsafe fn test(&self, _: i32, _: [f32; 3], _: [f32; 3]) -> LaneResult {
        unreachable!("eight-sample lanes are only used where available() is true")
    }
}

impl LaneResult {
    /// Eight samples decided without the filter: the lanes of `pass` pass, none is open.
    #[inline]
    fn decided(pass: u32) -> LaneResult {
        LaneResult {
            pass,
            open: 0,
            u: [0.0; 8],
            v: [0.0; 8],
        }
    }
}

/// The lanes whose weights `b` put the sample inside the triangle: none below zero (a NaN
/// weight is inside, as the scalar `b < 0.0` test has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn inside_lanes(b: &[std::arch::x86_64::__m256; 3]) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let zero = _mm256_setzero_ps();
    _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NLT_UQ>(b[0], zero),
            _mm256_cmp_ps::<_CMP_NLT_UQ>(b[1], zero),
        ),
        _mm256_cmp_ps::<_CMP_NLT_UQ>(b[2], zero),
    )
}

/// [`LaneTest::Table`] of the samples at `(u, v)` in the lanes of `inside`: each on-level
/// lane's footprint entry of `table` (of `level`, the filter's first) passes when its least
/// alpha is at least `pass_from`, fails when its greatest is below `fail_below`; the other
/// inside lanes are left open.
///
/// # Safety
/// AVX2. `table` must hold `width · height + 1` entries of `level`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn table_decide(
    table: &[[u8; 2]],
    [pass_from, fail_below]: [u16; 2],
    level: &LaneLevel,
    (u, v): (std::arch::x86_64::__m256, std::arch::x86_64::__m256),
    inside: std::arch::x86_64::__m256,
) -> LaneResult {
    use std::arch::x86_64::*;
    let zero = _mm256_setzero_ps();
    // The footprint's cell: `floor(u·w − 0.5)`, kept when on the level (a NaN is not, and
    // goes to the filter, which places it as the scalar path does).
    let (width, height) = (level.width, level.height);
    let (wf, hf) = (_mm256_set1_ps(width as f32), _mm256_set1_ps(height as f32));
    let half = _mm256_set1_ps(0.5);
    let fx = _mm256_floor_ps(_mm256_sub_ps(_mm256_mul_ps(u, wf), half));
    let fy = _mm256_floor_ps(_mm256_sub_ps(_mm256_mul_ps(v, hf), half));
    let on = _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(fx, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(fx, wf),
        ),
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(fy, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(fy, hf),
        ),
    );
    let on = _mm256_and_ps(on, inside);
    // Off-level lanes read entry 0 (masked off: the gather leaves them at zero).
    let cell = _mm256_add_epi32(
        _mm256_mullo_epi32(
            _mm256_cvttps_epi32(_mm256_and_ps(fy, on)),
            _mm256_set1_epi32(width as i32),
        ),
        _mm256_cvttps_epi32(_mm256_and_ps(fx, on)),
    );
    // Entries are two bytes: a 4-byte read at twice the cell holds this entry in its low half
    // (and the next one, or the padding, in its high half).
    // SAFETY: every cell of an on-level lane is below `width · height`, and the table has one
    // entry more, so the four bytes read are within it; off lanes are not read.
    let entries = unsafe {
        _mm256_mask_i32gather_epi32::<1>(
            _mm256_setzero_si256(),
            table.as_ptr().cast::<i32>(),
            _mm256_add_epi32(cell, cell),
            _mm256_castps_si256(on),
        )
    };
    let byte = _mm256_set1_epi32(0xff);
    let lo = _mm256_and_si256(entries, byte);
    let hi = _mm256_and_si256(_mm256_srli_epi32::<8>(entries), byte);
    let passes = _mm256_cmpgt_epi32(lo, _mm256_set1_epi32(i32::from(pass_from) - 1));
    let fails = _mm256_cmpgt_epi32(_mm256_set1_epi32(i32::from(fail_below)), hi);
    let on_bits = _mm256_movemask_ps(on) as u32;
    let pass = on_bits & _mm256_movemask_ps(_mm256_castsi256_ps(passes)) as u32;
    let fail = on_bits & _mm256_movemask_ps(_mm256_castsi256_ps(fails)) as u32;
    LaneResult {
        pass,
        open: _mm256_movemask_ps(inside) as u32 & !(pass | fail),
        u: [0.0; 8],
        v: [0.0; 8],
    }
}

/// The open lanes of `r` (samples at `(u, v)`) filtered as the scalar test filters them
/// (bilinear, blended trilinearly when `filter` has a second level, then
/// `alpha / 255 · scale ≥ cutoff`): those whose footprints the lanes can read are passed or
/// not and closed; the others stay open for the scalar path.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn filter_open(
    r: &mut LaneResult,
    filter: &LaneFilter,
    u: std::arch::x86_64::__m256,
    v: std::arch::x86_64::__m256,
) {
    use std::arch::x86_64::*;
    let open = lane_mask(r.open);
    // SAFETY: AVX2, as this function's.
    let (alpha, on) = unsafe {
        let (a, on_a) = bilinear(&filter.a, u, v, open);
        match &filter.b {
            Some(level) => {
                let (b, on_b) = bilinear(level, u, v, open);
                let blend = _mm256_add_ps(
                    a,
                    _mm256_mul_ps(_mm256_sub_ps(b, a), _mm256_set1_ps(filter.f)),
                );
                (blend, _mm256_and_ps(on_a, on_b))
            }
            None => (a, on_a),
        }
    };
    // `passes_cutoff`: kept unless below the cutoff (a NaN is kept).
    let tested = _mm256_mul_ps(
        _mm256_div_ps(alpha, _mm256_set1_ps(255.0)),
        _mm256_set1_ps(filter.scale),
    );
    let passes = _mm256_cmp_ps::<_CMP_NLT_UQ>(tested, _mm256_set1_ps(filter.cutoff));
    let on_bits = _mm256_movemask_ps(on) as u32 & r.open;
    r.pass |= on_bits & _mm256_movemask_ps(passes) as u32;
    r.open &= !on_bits;
}
