//! Frequency bins (spec animated-billboard-clouds §4.10): k-means on the frequency axis, with
//! each bin's centroid the amplitude-weighted mean frequency over all given spectra, so that
//! `sin 4t` and `sin 5t` share a bin and average to about `sin 4.5t` instead of sharing nothing.

use serde::Serialize;

/// A partition of the frequencies 1..=K into contiguous bins.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrequencyBins {
    /// Per bin, the amplitude indices (frequency k = index + 1) it holds, ascending.
    pub bins: Vec<Vec<usize>>,
    /// Per bin, the amplitude-weighted mean frequency (cycles per loop).
    pub centroids: Vec<f32>,
    /// Per bin, the average over the spectra of their total amplitude in the bin (Ā).
    pub amplitudes: Vec<f32>,
}

impl FrequencyBins {
    /// Σ over bins of |a's total amplitude in the bin − b's|: the amplitude distance of two
    /// spectra under this one partition (no re-binning, no allocation).
    pub fn distance(&self, a: &[f32], b: &[f32]) -> f32 {
        self.bins
            .iter()
            .map(|bin| {
                let (mut sa, mut sb) = (0.0f32, 0.0f32);
                for &i in bin {
                    sa += a.get(i).copied().unwrap_or(0.0);
                    sb += b.get(i).copied().unwrap_or(0.0);
                }
                (sa - sb).abs()
            })
            .sum()
    }

    /// Per bin, the DFT frequency nearest the centroid (what an averaged spectrum uses).
    pub fn rounded_frequencies(&self) -> Vec<usize> {
        self.centroids
            .iter()
            .map(|c| c.round().max(1.0) as usize)
            .collect()
    }
}

/// Bins the frequencies of `spectra` (amplitude arrays of equal length K, index i = frequency
/// i + 1) into at most `k` bins: start with K div k frequencies per bin (the last takes the
/// rest), then alternate centroid (amplitude-weighted mean frequency over every spectrum) and
/// nearest-centroid assignment until nothing moves. Bins that end empty are removed. Ties go
/// to the lower bin, so the result is deterministic.
pub fn frequency_bins(spectra: &[&[f32]], k: usize) -> FrequencyBins {
    let len = spectra.iter().map(|s| s.len()).min().unwrap_or(0);
    let k = k.clamp(1, len.max(1));
    if len == 0 {
        return FrequencyBins {
            bins: Vec::new(),
            centroids: Vec::new(),
            amplitudes: Vec::new(),
        };
    }
    // Total amplitude per frequency over all spectra.
    let total: Vec<f64> = (0..len)
        .map(|i| spectra.iter().map(|s| f64::from(s[i])).sum())
        .collect();
    let per = len / k;
    let mut assign: Vec<usize> = (0..len).map(|i| (i / per.max(1)).min(k - 1)).collect();
    let centroid = |assign: &[usize], b: usize| -> f64 {
        let (mut wsum, mut fsum, mut count, mut plain) = (0.0, 0.0, 0usize, 0.0);
        for (i, &a) in assign.iter().enumerate() {
            if a == b {
                let f = (i + 1) as f64;
                wsum += total[i];
                fsum += total[i] * f;
                count += 1;
                plain += f;
            }
        }
        if wsum > 0.0 {
            fsum / wsum
        } else if count > 0 {
            plain / count as f64
        } else {
            f64::NAN
        }
    };
    for _ in 0..100 {
        let c: Vec<f64> = (0..k).map(|b| centroid(&assign, b)).collect();
        let next: Vec<usize> = (0..len)
            .map(|i| {
                let f = (i + 1) as f64;
                (0..k)
                    .filter(|&b| c[b].is_finite())
                    .min_by(|&a, &b| {
                        (f - c[a])
                            .abs()
                            .total_cmp(&(f - c[b]).abs())
                            .then(a.cmp(&b))
                    })
                    .unwrap_or(assign[i])
            })
            .collect();
        if next == assign {
            break;
        }
        assign = next;
    }
    let m = spectra.len().max(1) as f64;
    let mut out = FrequencyBins {
        bins: Vec::new(),
        centroids: Vec::new(),
        amplitudes: Vec::new(),
    };
    let mut order: Vec<(f64, usize)> = (0..k).map(|b| (centroid(&assign, b), b)).collect();
    order.retain(|(c, _)| c.is_finite());
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (c, b) in order {
        let members: Vec<usize> = (0..len).filter(|&i| assign[i] == b).collect();
        let amp: f64 = members.iter().map(|&i| total[i]).sum::<f64>() / m;
        out.bins.push(members);
        out.centroids.push(c as f32);
        out.amplitudes.push(amp as f32);
    }
    out
}

/// Amplitude distance of two spectra over shared frequency bins (§4.10, last paragraph, used
/// by the dominating-axis metrics of §5.5): bin both spectra together into `k` bins and sum,
/// over bins, the absolute difference of their total amplitude in the bin. With `k` = the
/// number of frequencies it is the plain Σ_ω |A₁(ω) − A₂(ω)|.
pub fn amplitude_distance(a: &[f32], b: &[f32], k: usize) -> f32 {
    let bins = frequency_bins(&[a, b], k);
    bins.bins
        .iter()
        .map(|bin| {
            let sa: f32 = bin.iter().map(|&i| a[i]).sum();
            let sb: f32 = bin.iter().map(|&i| b[i]).sum();
            (sa - sb).abs()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pure(len: usize, freq: usize, amp: f32) -> Vec<f32> {
        (0..len)
            .map(|i| if i + 1 == freq { amp } else { 0.0 })
            .collect()
    }

    #[test]
    fn sin4_and_sin5_average_to_4_5() {
        // The thesis' example: x = sin 4t, y = sin 5t, one bin → ω̄ = 4.5, Ā = 1.
        let (x, y) = (pure(16, 4, 1.0), pure(16, 5, 1.0));
        let b = frequency_bins(&[&x, &y], 1);
        assert_eq!(b.bins.len(), 1);
        assert!((b.centroids[0] - 4.5).abs() < 1e-6);
        assert!((b.amplitudes[0] - 1.0).abs() < 1e-6);
        // Apart they share no frequency; binned coarsely they are close, and far from sin 15t.
        assert_eq!(amplitude_distance(&x, &y, 16), 2.0);
        assert!(amplitude_distance(&x, &y, 2) < 1e-6);
        let z = pure(16, 15, 1.0);
        assert!(amplitude_distance(&x, &z, 2) > 1.9);
    }

    #[test]
    fn bins_are_contiguous_sorted_and_cover_everything() {
        let a: Vec<f32> = (0..32).map(|i| ((i * 7) % 5) as f32).collect();
        let b: Vec<f32> = (0..32).map(|i| ((i * 3) % 4) as f32 * 0.5).collect();
        let bins = frequency_bins(&[&a, &b], 4);
        let mut all: Vec<usize> = bins.bins.iter().flatten().copied().collect();
        all.sort_unstable();
        assert_eq!(all, (0..32).collect::<Vec<_>>());
        for w in bins.centroids.windows(2) {
            assert!(w[0] < w[1]);
        }
        for bin in &bins.bins {
            assert!(
                bin.windows(2).all(|w| w[1] == w[0] + 1),
                "contiguous: {bin:?}"
            );
        }
        assert_eq!(frequency_bins(&[&a, &b], 4), bins, "deterministic");
        assert!(frequency_bins(&[], 3).bins.is_empty());
    }

    #[test]
    fn equal_spectra_have_zero_distance() {
        let a: Vec<f32> = (0..20).map(|i| 1.0 / (i + 1) as f32).collect();
        for k in [1, 3, 8, 20] {
            assert_eq!(amplitude_distance(&a, &a, k), 0.0);
        }
    }
}
