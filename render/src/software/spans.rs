//! The span rasteriser's rows: each sample row of a triangle walked as the span of samples
//! its edge functions can put inside it ([`RowSpan`]), the weights stepped along the row.

use super::setup::Setup;

/// The samples `first..=last` (offsets from the row's first, at most `len`) of a row whose
/// weights start at `start` and change by `step` per sample that can be inside the triangle:
/// each weight's zero crossing (`−start · inv`, `inv` the step's reciprocal, 0 where the step
/// is too small to invert safely, which leaves that edge out) bounds the span, widened by
/// [`SPAN_SLACK`] samples against rounding (the samples are still tested one by one, so any
/// span holding the inside ones gives the same image). `None` when no sample can be.
#[inline]
fn row_span(start: [f32; 3], step: [f32; 3], inv: [f32; 3], len: usize) -> Option<(usize, usize)> {
    let (mut lo, mut hi) = (0.0f32, len as f32);
    for k in 0..3 {
        if inv[k] > 0.0 {
            lo = lo.max(-start[k] * inv[k] - SPAN_SLACK);
        } else if inv[k] < 0.0 {
            hi = hi.min(-start[k] * inv[k] + SPAN_SLACK);
        } else if step[k] == 0.0 && start[k] < 0.0 {
            return None;
        }
    }
    // The first sample at or after `lo` (a ceiling: `lo` is at least 0 here). Converted
    // through `i64`: one instruction, where a float's conversion to `usize` is a sequence
    // (x86-64 has no unsigned one before AVX-512); both are at least 0 where used.
    let first = lo as i64 as usize + usize::from((lo as i64 as f32) < lo);
    (lo <= hi && hi >= 0.0).then(|| (first, (hi as i64 as usize).min(len)))
}

/// How far a row's span reaches past its edges' computed zero crossings, in samples. The
/// crossing's rounding error is a few units in the last place of its offset (under 10⁻³
/// samples across the largest target) and a weight's own rounding moves the sample it turns
/// negative at by as little: a quarter sample is hundreds of times that.
const SPAN_SLACK: f32 = 0.25;

/// One sample row of a triangle: the samples `first..=last` it may cover (see [`row_span`])
/// and the weights along the row.
pub(crate) struct RowSpan {
    /// The sample row.
    pub(crate) y: usize,
    /// The span's first sample (a column of the target).
    pub(crate) first: usize,
    /// The span's last sample (inclusive).
    pub(crate) last: usize,
    /// The sample the weights `start` are at.
    pub(crate) x0: usize,
    /// The weights at sample `x0` of the row.
    pub(crate) start: [f32; 3],
    /// The weights' change per sample along the row.
    pub(crate) step: [f32; 3],
}

impl RowSpan {
    /// The screen-space barycentric weights of sample `x` of the row.
    #[inline]
    pub(crate) fn weights_at(&self, x: usize) -> [f32; 3] {
        let k = (x - self.x0) as f32;
        [
            self.start[0] + self.step[0] * k,
            self.start[1] + self.step[1] * k,
            self.start[2] + self.step[2] * k,
        ]
    }
}

/// What every row of one triangle's walk shares: its weights' change per sample along a row
/// and their reciprocals.
pub(crate) struct RowWalk {
    /// The weights' change per sample along a row.
    step: [f32; 3],
    /// The reciprocals of `step` (0 where a step is too small to invert).
    inv: [f32; 3],
}

impl Setup {
    /// The sample rows of `y0..y1` the triangle may cover, each with its span of samples.
    pub(crate) fn row_spans(&self, y0: usize, y1: usize) -> impl Iterator<Item = RowSpan> + '_ {
        let walk = self.row_walk();
        self.rows(y0, y1)
            .filter_map(move |y| self.row_span(&walk, y))
    }

    /// The sample rows of `y0..y1` within the triangle's bounds.
    #[inline]
    pub(crate) fn rows(&self, y0: usize, y1: usize) -> std::ops::Range<usize> {
        (self.min[1] as usize).max(y0)..(self.max[1] as usize + 1).min(y1)
    }

    /// What [`Setup::row_span`] needs of the triangle for every row.
    #[inline]
    pub(crate) fn row_walk(&self) -> RowWalk {
        let step = [
            -(self.y[2] - self.y[1]) * self.inv_area,
            -(self.y[0] - self.y[2]) * self.inv_area,
            -(self.y[1] - self.y[0]) * self.inv_area,
        ];
        // Reciprocals once a triangle rather than a division per edge and row; steps this small
        // bound nothing within an image.
        let inv = step.map(|s| if s.abs() >= 1e-30 { 1.0 / s } else { 0.0 });
        RowWalk { step, inv }
    }

    /// Sample row `y`'s span, `None` when the triangle covers no sample of it.
    #[inline(always)]
    pub(crate) fn row_span(&self, walk: &RowWalk, y: usize) -> Option<RowSpan> {
        let x0 = self.min[0] as usize;
        let start = self.weights(x0 as f32 + 0.5, y as f32 + 0.5);
        let (first, last) = row_span(start, walk.step, walk.inv, self.max[0] as usize - x0)?;
        Some(RowSpan {
            y,
            first: x0 + first,
            last: x0 + last,
            x0,
            start,
            step: walk.step,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::software::sampling::Trilinear;

    /// A row's span holds every sample the weights put inside the triangle, and at most one
    /// more at either end, for triangles of every shape and size (slivers, nearly flat rows,
    /// far outside the target).
    #[test]
    fn row_spans_hold_every_inside_sample() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = |range: f32| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 * range
        };
        let (sw, sh) = (96.0f32, 64.0f32);
        let (mut inside, mut tight) = (0, 0);
        for k in 0..3000 {
            let scale = [2.0, 30.0, 400.0][k % 3];
            let mut x = [0.0f32; 3].map(|_| next(scale) - scale / 2.0 + 48.0);
            let mut y = [0.0f32; 3].map(|_| next(scale) - scale / 2.0 + 32.0);
            if k % 7 == 0 {
                y[1] = y[0] + 1e-3; // a nearly flat edge
            }
            let area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
            if area.abs() < 1e-6 {
                continue;
            }
            if area < 0.0 {
                x.swap(1, 2);
                y.swap(1, 2);
            }
            let min = [
                ((x.iter().copied().fold(f32::INFINITY, f32::min) - 0.5).ceil()).max(0.0),
                ((y.iter().copied().fold(f32::INFINITY, f32::min) - 0.5).ceil()).max(0.0),
            ];
            let max = [
                ((x.iter().copied().fold(f32::NEG_INFINITY, f32::max) - 0.5).floor()).min(sw - 1.0),
                ((y.iter().copied().fold(f32::NEG_INFINITY, f32::max) - 0.5).floor()).min(sh - 1.0),
            ];
            if min[0] > max[0] || min[1] > max[1] {
                continue;
            }
            let t = Setup {
                x,
                y,
                z: [0.0; 3],
                q: [1.0; 3],
                uq: [[0.0; 2]; 3],
                inv_area: 1.0 / area.abs(),
                material: 0,
                lit: false,
                back: false,
                lod: Trilinear::default(),
                min: [min[0] as i32, min[1] as i32],
                max: [max[0] as i32, max[1] as i32],
            };
            let spans: Vec<RowSpan> = t.row_spans(0, sh as usize).collect();
            for sy in min[1] as usize..=max[1] as usize {
                let span = spans.iter().find(|s| s.y == sy);
                let mut held = None::<(usize, usize)>;
                for sx in min[0] as usize..=max[0] as usize {
                    // Inside by the weights from scratch, or as a span steps them along the
                    // row (which the renderers test).
                    let b = t.weights(sx as f32 + 0.5, sy as f32 + 0.5);
                    let stepped = span.map(|s| {
                        let k = sx as f32 - s.x0 as f32;
                        [0, 1, 2].map(|e| s.start[e] + s.step[e] * k)
                    });
                    let all = |b: [f32; 3]| b.iter().all(|&w| w >= 0.0);
                    if all(b) || stepped.is_some_and(all) {
                        inside += 1;
                        assert!(
                            span.is_some_and(|s| (s.first..=s.last).contains(&sx)),
                            "triangle {x:?} {y:?}: sample ({sx}, {sy}) outside its row's span"
                        );
                        held = Some(held.map_or((sx, sx), |(a, _)| (a, sx)));
                    }
                }
                // Tight: at most a sample past the inside ones at either end.
                if let (Some(s), Some((a, b))) = (span, held) {
                    assert!(
                        s.first + 1 >= a && s.last <= b + 1,
                        "triangle {x:?} {y:?}: row {sy} spans {}..={} for {a}..={b}",
                        s.first,
                        s.last
                    );
                    tight += 1;
                }
            }
        }
        assert!(inside > 100_000, "{inside} inside samples");
        assert!(tight > 10_000, "{tight} rows");
    }
}
