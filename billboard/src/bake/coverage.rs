//! Coverage-preserving alpha ([`BakeParams::preserve_coverage`](crate::BakeParams::preserve_coverage)):
//! per cell, the alpha-test threshold moved so that as many texels pass as the cell's
//! summed coverage, scaled by its quad's [`foreshortening`].

use rayon::prelude::*;

use crate::bake::baked::Cell;
use crate::bake::finish::{CellTexels, band_parts, padded_rect, row_bands};
use crate::bake::texels::Downsampled;

/// Re-thresholds the alpha of each cell whose foliage the plain alpha test would thin out or
/// thicken, so that the number of texels passing the 0.5 test equals the cell's summed
/// coverage in texels times its `scales` entry (its quad's [`foreshortening`]), rounded with
/// the remainder carried to the next such cell; where that is more texels than its leaves
/// touch, the rest are grown beside them ([`grown_texels`], returned: the caller makes them
/// opaque once dilation has coloured them)
/// ([`BakeParams::preserve_coverage`]). A cell where the test at the cutoff (`needed` covered
/// samples of `total`) already passes its coverage within [`COVERAGE_TOLERANCE`] keeps its
/// graded alpha: its leaves are resolved at this density, and a billboard seen at its design
/// size should reproduce their outline, not a re-thresholded (speckled) one.
pub(super) fn preserve_coverage(
    out: &mut Downsampled,
    cells: &[Cell],
    scales: &[f64],
    total: u32,
    needed: u32,
) -> Vec<usize> {
    let thresholds = coverage_thresholds(out, cells, scales, total, needed);
    let rects: Vec<[usize; 4]> = (cells.iter())
        .map(|c| padded_rect(c, 0, out.width, out.height))
        .collect();
    let grown: Vec<usize> = (thresholds.par_iter().zip(&rects))
        .filter_map(|(t, &rect)| t.filter(|t| t.grow > 0).map(|t| (t.grow, rect)))
        .flat_map_iter(|(grow, rect)| grown_texels(out, rect, grow))
        .collect();
    let bands = row_bands(&rects);
    (band_parts(out, &bands).into_par_iter()).for_each(|(mut band, members)| {
        for &c in members {
            if let Some(t) = thresholds[c] {
                band.threshold(rects[c], t.threshold);
            }
        }
    });
    grown
}

/// Sets each covered texel's alpha to the fraction of it covered, scaled so that each cell
/// keeps its summed coverage times its `scales` entry ([`BakeParams::covered_fraction`](crate::BakeParams::covered_fraction)):
/// `α = min(1, s'·n/total)` with `s'` the scale at which the cell's alphas sum to `scale·Σn/total`
/// (bisected; `s' = scale` while no texel saturates). Where even every covered texel opaque
/// falls short, the rest is spread over uncovered texels beside them ([`grown_texels`]),
/// returned with their alpha for after dilation. Blended alpha composes as coverage does, and
/// box-filtered mips keep it at every level.
pub(super) fn covered_fractions(
    out: &mut Downsampled,
    cells: &[Cell],
    scales: &[f64],
    total: u32,
) -> Vec<(usize, u8)> {
    let w = out.width as usize;
    let total = f64::from(total.max(1));
    let rects: Vec<[usize; 4]> = (cells.iter())
        .map(|c| padded_rect(c, 0, out.width, out.height))
        .collect();
    // Per cell: its covered texels' fractions and the scale that keeps their sum.
    let plans: Vec<(f64, f64)> = (rects.par_iter().zip(scales))
        .map(|(&[x0, x1, y0, y1], &scale)| {
            let fractions: Vec<f64> = (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| y * w + x))
                .map(|i| f64::from(out.samples[i]) / total)
                .filter(|&f| f > 0.0)
                .collect();
            let want = scale * fractions.iter().sum::<f64>();
            (
                fitted_scale(&fractions, scale, want),
                want - fractions.len() as f64,
            )
        })
        .collect();
    let grown: Vec<(usize, u8)> = (plans.par_iter().zip(&rects))
        .filter(|((_, short), _)| *short >= 0.5)
        .flat_map_iter(|(&(_, short), &rect)| {
            let texels = grown_texels(out, rect, short.ceil() as usize);
            let alpha = round_alpha(short / texels.len().max(1) as f64);
            texels.into_iter().map(move |i| (i, alpha))
        })
        .collect();
    for (&[x0, x1, y0, y1], &(s, _)) in rects.iter().zip(&plans) {
        for y in y0..y1 {
            for i in (x0..x1).map(|x| y * w + x) {
                let n = out.samples[i];
                if n > 0 {
                    let alpha = round_alpha(s * f64::from(n) / total).max(1);
                    out.color[i * 4 + 3] = alpha;
                    out.normal[i * 4 + 3] = alpha;
                }
            }
        }
    }
    grown
}

/// The scale `s ≥ scale` at which `Σ min(1, s·f)` over `fractions` reaches `want` (its
/// largest useful value, where every fraction saturates, when it cannot).
fn fitted_scale(fractions: &[f64], scale: f64, want: f64) -> f64 {
    let sum = |s: f64| fractions.iter().map(|&f| (s * f).min(1.0)).sum::<f64>();
    let least = fractions.iter().copied().fold(f64::INFINITY, f64::min);
    if fractions.is_empty() || sum(scale) >= want {
        return scale;
    }
    let mut hi = (1.0 / least).max(scale);
    if sum(hi) <= want {
        return hi;
    }
    let mut lo = scale;
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if sum(mid) < want {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// A fraction 0..1 as an alpha byte, rounded.
fn round_alpha(f: f64) -> u8 {
    (f.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// How a cell's alpha is re-thresholded: its texels with at least `threshold` covered samples
/// pass, and `grow` uncovered ones beside them ([`grown_texels`]) when its coverage asks for
/// more texels than its leaves touch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Threshold {
    pub(super) threshold: u32,
    pub(super) grow: usize,
}

/// The `grow` uncovered texels of the cell `[x0, x1, y0, y1]` with the most covered samples
/// in the 5×5 texels around them (none with no covered neighbour): the texels that thicken
/// its covered area evenly, as a leaf seen edge-on from the quad's front still covers some of
/// the view from elsewhere. Atlas texel indices, in order.
fn grown_texels(out: &Downsampled, [x0, x1, y0, y1]: [usize; 4], grow: usize) -> Vec<usize> {
    let w = out.width as usize;
    let mut scored: Vec<(u32, usize)> = Vec::new();
    for y in y0..y1 {
        for x in x0..x1 {
            let i = y * w + x;
            if out.samples[i] > 0 {
                continue;
            }
            let mut score = 0u32;
            for ny in y.saturating_sub(2).max(y0)..(y + 3).min(y1) {
                for nx in x.saturating_sub(2).max(x0)..(x + 3).min(x1) {
                    score += u32::from(out.samples[ny * w + nx]);
                }
            }
            if score > 0 {
                scored.push((score, i));
            }
        }
    }
    scored.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut texels: Vec<usize> = scored.into_iter().take(grow).map(|(_, i)| i).collect();
    texels.sort_unstable();
    texels
}

/// Per cell, how its alpha is re-thresholded ([`Threshold`]), `None` where it keeps its
/// graded alpha. The cells' counts are gathered in parallel, the remainders then carried
/// from cell to cell in quad order.
pub(super) fn coverage_thresholds(
    out: &Downsampled,
    cells: &[Cell],
    scales: &[f64],
    total: u32,
    needed: u32,
) -> Vec<Option<Threshold>> {
    let w = out.width as usize;
    // Per cell with covered texels: its summed covered samples, its texels passing at the
    // cutoff, and how many texels have each count of covered samples (0 left out).
    let counts: Vec<Option<(u64, usize, Vec<usize>)>> = cells
        .par_iter()
        .map(|c| {
            let mut histogram = vec![0usize; total as usize + 1];
            for y in c.y as usize..(c.y + c.height) as usize {
                let row = &out.samples[y * w + c.x as usize..][..c.width as usize];
                for &n in row {
                    histogram[usize::from(n).min(total as usize)] += 1;
                }
            }
            histogram[0] = 0;
            let covered: usize = histogram.iter().sum();
            (covered > 0).then(|| {
                let sum = (histogram.iter().enumerate())
                    .map(|(n, &k)| n as u64 * k as u64)
                    .sum();
                let passing = histogram[needed as usize..].iter().sum();
                (sum, passing, histogram)
            })
        })
        .collect();
    // Rounding remainders carry over to the next cell (in quad order), so the whole atlas
    // keeps its coverage even when most cells hold less than one texel of it.
    let mut carry = 0.0f64;
    (counts.into_iter().zip(scales).zip(cells))
        .map(|((counts, &scale), cell)| {
            let (sum, passing, histogram) = counts?;
            let own = scale * sum as f64 / f64::from(total);
            let passing = passing as f64;
            if own >= 1.0 && (passing - own).abs() <= COVERAGE_TOLERANCE * own {
                return None;
            }
            let covered: usize = histogram.iter().sum();
            let texels = cell.width as usize * cell.height as usize;
            let want = own + carry;
            let keep = (want.round().max(0.0) as usize).min(texels);
            carry = want - keep as f64;
            if keep > covered {
                return Some(Threshold {
                    threshold: 1,
                    grow: keep - covered,
                });
            }
            // The `keep`-th largest count: texels with at least it pass; none when keep == 0.
            let mut seen = 0;
            let threshold = if keep == 0 {
                total + 1
            } else {
                (0..=total)
                    .rev()
                    .find(|&n| {
                        seen += histogram[n as usize];
                        seen >= keep
                    })
                    .unwrap_or(0)
            };
            Some(Threshold { threshold, grow: 0 })
        })
        .collect()
}

/// Relative difference between a cell's coverage (in texels) and the texels the plain alpha
/// test passes under which [`preserve_coverage`] leaves the cell alone. Chosen by measuring
/// the default chain of the shared trees at several screen heights (the figures are in the
/// commit that introduced it).
pub(super) const COVERAGE_TOLERANCE: f64 = 0.1;

impl CellTexels<'_> {
    /// Sets the alpha of the covered texels of the cell `[x0, x1, y0, y1]`: opaque from
    /// `threshold` covered samples, clear below ([`preserve_coverage`]: binary, so that
    /// bilinear magnification keeps an isolated passing texel, 61 % of its area, instead of
    /// eroding one that barely passes to nothing).
    pub(super) fn threshold(&mut self, [x0, x1, y0, y1]: [usize; 4], threshold: u32) {
        for y in y0..y1 {
            for x in x0..x1 {
                let i = self.at(x, y);
                let n = u32::from(self.samples[i]);
                if n > 0 {
                    let alpha = if n >= threshold { 255 } else { 0 };
                    self.color[i * 4 + 3] = alpha;
                    self.normal[i * 4 + 3] = alpha;
                }
            }
        }
    }
}

/// How much of its leaves' area a quad loses by flattening them onto its plane, seen from
/// every direction alike: `Σ area / Σ area·|n_leaf · n_quad|` over its triangles, at least 1.
/// A leaf of area A is seen with A/2 on average over the sphere of views, and so is its
/// projection onto the plane, A·|cos θ|, with A·|cos θ|/2: the quad keeps its leaves'
/// coverage over views when its alpha-tested area is its projected coverage times this.
pub fn foreshortening(soup: &crate::TriangleSoup, quad: &crate::Quad, triangles: &[usize]) -> f64 {
    let n = quad.plane.normal;
    let (mut area, mut projected) = (0.0f64, 0.0f64);
    for &t in triangles {
        let [a, b, c] = soup.positions[t];
        let cross = (b - a).cross(c - a);
        let a2 = f64::from(cross.length());
        area += a2;
        projected += f64::from(cross.dot(n).abs());
    }
    if projected > 0.0 {
        (area / projected).clamp(1.0, MAX_FORESHORTENING)
    } else {
        1.0
    }
}

/// The most [`foreshortening`] makes of a quad's coverage: leaves nearly edge-on to their quad
/// cover almost nothing of it, and scaling that up would only grow noise.
pub const MAX_FORESHORTENING: f64 = 4.0;
