//! The sRGB transfer function between bytes and linear light, by table: every byte's linear
//! value computed once, and the linear values at which the nearest byte steps up, so that
//! neither direction calls `powf` per texel (a 1024² leaf map's mip chain made 800,000 such
//! calls, most of a bake's texture preparation; the bake's texels as many again).

use std::sync::LazyLock;

/// Every sRGB byte's linear value ([`srgb_to_linear`]).
pub static SRGB_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|b| decode(b as u8)));

/// sRGB-encoded byte → linear light (IEC 61966-2-1), looked up.
#[inline]
pub fn srgb_to_linear(v: u8) -> f32 {
    SRGB_LINEAR[usize::from(v)]
}

/// The transfer function itself, in single precision.
fn decode(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear values at which the nearest sRGB byte steps up: entry `k` separates `k` and
/// `k + 1` (the midpoint `(k + ½)/255` decoded in double precision); the last entry, +∞,
/// is past every value.
static LINEAR_THRESHOLDS: LazyLock<[f32; 256]> = LazyLock::new(|| {
    std::array::from_fn(|k| {
        if k == 255 {
            return f32::INFINITY;
        }
        let c = (k as f64 + 0.5) / 255.0;
        let l = if c <= 0.040_45 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        };
        l as f32
    })
});

/// Per 1/[`BUCKETS`] of linear light from 0 to 1, how many of
/// [`LINEAR_THRESHOLDS`] lie at or below its start: where [`linear_to_srgb`] starts counting.
static BUCKET_STARTS: LazyLock<[u8; BUCKETS]> = LazyLock::new(|| {
    std::array::from_fn(|b| {
        let start = b as f32 / BUCKETS as f32;
        LINEAR_THRESHOLDS[..255].partition_point(|&t| t <= start) as u8
    })
});

/// Buckets of [`BUCKET_STARTS`]: narrower than the thresholds' least spacing (1/3294, near
/// 0), so a value is at most one threshold past its bucket's start.
const BUCKETS: usize = 4096;

/// Linear light → the nearest sRGB byte (rounding in sRGB space; 0 at or below 0 and for a
/// NaN, 255 from 1): the thresholds at or below `x` counted from its bucket's start, where
/// one comparison settles it (cheaper than a binary search over all 255 thresholds, or a
/// loop whose exit the processor cannot predict).
#[inline]
pub fn linear_to_srgb(x: f32) -> u8 {
    // The least threshold is above 0: nothing is at or below 0, a negative value or NaN; the
    // greatest is below 1.
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    if x >= 1.0 {
        return 255;
    }
    // `x · 4096` is exact (a power of two), so the bucket's start is at or below `x`, and
    // `x` is at most one threshold past it ([`BUCKETS`]); below 1, the +∞ entry is never
    // passed.
    let bucket = (x * BUCKETS as f32) as usize;
    let k = BUCKET_STARTS[bucket];
    k + u8::from(LINEAR_THRESHOLDS[usize::from(k)] <= x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bucketed_conversion_matches_the_binary_search() {
        // Every threshold and its float neighbours, a sweep, and the edges.
        let mut values = vec![0.0f32, -0.0, -1.0, 1.0, 1.5, f32::NAN, f32::INFINITY, 1e-30];
        for &t in &LINEAR_THRESHOLDS[..255] {
            values.extend([t, t.next_down(), t.next_up()]);
        }
        values.extend((0..=100_000).map(|i| i as f32 / 100_000.0));
        for x in values {
            let searched = LINEAR_THRESHOLDS[..255].partition_point(|&t| t <= x) as u8;
            assert_eq!(linear_to_srgb(x), searched, "{x}");
        }
    }

    #[test]
    fn round_trip_and_rounding() {
        for b in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(b)), b);
        }
        assert_eq!(linear_to_srgb(0.5), 188);
        assert_eq!(linear_to_srgb(-1.0), 0);
        assert_eq!(linear_to_srgb(2.0), 255);
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
    }

    #[test]
    fn the_table_rounds_as_the_transfer_function_does_away_from_its_steps() {
        // The single-precision formula (what mip levels were averaged with before the table)
        // agrees wherever a value is not within a few units in the last place of a step.
        let formula = |c: f32| {
            let e = if c <= 0.003_130_8 {
                c * 12.92
            } else {
                1.055 * c.powf(1.0 / 2.4) - 0.055
            };
            (e * 255.0 + 0.5) as u8
        };
        let near_a_step =
            |x: f32| (LINEAR_THRESHOLDS.iter()).any(|&t| (x - t).abs() <= 4.0 * t * f32::EPSILON);
        let mut differ = 0;
        for i in 0..=1_000_000 {
            let x = i as f32 / 1_000_000.0;
            if linear_to_srgb(x) != formula(x) {
                assert!(
                    near_a_step(x),
                    "{x}: {} against {}",
                    linear_to_srgb(x),
                    formula(x)
                );
                differ += 1;
            }
        }
        assert!(differ <= 10, "{differ} values differ");
    }
}
