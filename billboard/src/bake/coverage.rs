//! Coverage-preserving alpha ([`BakeParams::preserve_coverage`](crate::BakeParams::preserve_coverage)):
//! per cell, the alpha-test threshold moved so that as many texels pass as the cell's
//! summed coverage.

use rayon::prelude::*;

use crate::bake::baked::Cell;
use crate::bake::finish::{CellTexels, band_parts, padded_rect, row_bands};
use crate::bake::texels::Downsampled;

/// Re-thresholds the alpha of each cell whose foliage the plain alpha test would thin out or
/// thicken, so that the number of texels passing the 0.5 test equals the cell's summed
/// coverage in texels, rounded with the remainder carried to the next such cell
/// ([`BakeParams::preserve_coverage`]). A cell where the test at the cutoff (`needed` covered
/// samples of `total`) already passes its coverage within [`COVERAGE_TOLERANCE`] keeps its
/// graded alpha: its leaves are resolved at this density, and a billboard seen at its design
/// size should reproduce their outline, not a re-thresholded (speckled) one.
pub(super) fn preserve_coverage(out: &mut Downsampled, cells: &[Cell], total: u32, needed: u32) {
    let thresholds = coverage_thresholds(out, cells, total, needed);
    let rects: Vec<[usize; 4]> = (cells.iter())
        .map(|c| padded_rect(c, 0, out.width, out.height))
        .collect();
    let bands = row_bands(&rects);
    (band_parts(out, &bands).into_par_iter()).for_each(|(mut band, members)| {
        for &c in members {
            if let Some(threshold) = thresholds[c] {
                band.threshold(rects[c], threshold);
            }
        }
    });
}

/// Per cell, the covered samples from which its texels pass after [`preserve_coverage`]
/// (`total + 1`: none), `None` where it keeps its graded alpha. The cells' counts are
/// gathered in parallel, the remainders then carried from cell to cell in quad order.
pub(super) fn coverage_thresholds(
    out: &Downsampled,
    cells: &[Cell],
    total: u32,
    needed: u32,
) -> Vec<Option<u32>> {
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
    (counts.into_iter())
        .map(|counts| {
            let (sum, passing, histogram) = counts?;
            let own = sum as f64 / f64::from(total);
            let passing = passing as f64;
            if own >= 1.0 && (passing - own).abs() <= COVERAGE_TOLERANCE * own {
                return None;
            }
            let covered: usize = histogram.iter().sum();
            let want = own + carry;
            let keep = (want.round().max(0.0) as usize).min(covered);
            carry = want - keep as f64;
            // The `keep`-th largest count: texels with at least it pass; none when keep == 0.
            let mut seen = 0;
            Some(if keep == 0 {
                total + 1
            } else {
                (0..=total)
                    .rev()
                    .find(|&n| {
                        seen += histogram[n as usize];
                        seen >= keep
                    })
                    .unwrap_or(0)
            })
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
