//! Animation description types (spec animated-billboard-clouds §4.1, §4.6–4.10): what a leaf's
//! looping motion is reduced to, how far two such descriptions are apart, their average (the
//! centroid of a cluster and the motion of a billboard), and the motion an average gives back.
//!
//! Every type describes the *motion* of a trajectory: the DC bin (the rest position) is kept
//! apart by the caller (spec §4.5 \[ENG\]), `apply` returns the zero-mean offset per sample.
//! Frequency bins (§4.10) are used in deviation and average: two spectra whose energy sits at
//! neighbouring frequencies (sin 4t, sin 5t) are close, and average to one component at the
//! amplitude-weighted mean frequency rather than to two half-amplitude ones.

use glam::{Mat3, Vec3};

use crate::dominating_axis::dominating_axis;
use std::sync::Arc;

use crate::frequency_bins::{FrequencyBins, amplitude_distance, frequency_bins};
use crate::normalise::{angle_average, angle_difference, nep};
use crate::spectrum::Spectrum;

/// How deviations bin frequencies (spec §4.10).
#[derive(Clone, Debug)]
pub enum Bins {
    /// Each comparison bins its two spectra together into this many bins, as §4.10 describes
    /// (a small k-means over frequencies per pair: exact to the text, but costly per comparison).
    PerPair(usize),
    /// One partition for every comparison, made once from all leaves' spectra (the tree's
    /// inherent frequencies): the deviation becomes a fixed L1 distance over bins, far faster
    /// and the same for every pair, which k-means over 100k leaves needs.
    Shared(Arc<FrequencyBins>),
}

impl Bins {
    /// A shared partition of `spectra`'s frequencies into at most `k` bins.
    pub fn shared(spectra: &[&[f32]], k: usize) -> Bins {
        Bins::Shared(Arc::new(frequency_bins(spectra, k)))
    }
    /// The number of bins averages use.
    pub fn count(&self) -> usize {
        match self {
            Bins::PerPair(k) => *k,
            Bins::Shared(p) => p.bins.len().max(1),
        }
    }
    /// Amplitude distance of two spectra.
    pub fn distance(&self, a: &[f32], b: &[f32]) -> f32 {
        match self {
            Bins::PerPair(k) => amplitude_distance(a, b, *k),
            Bins::Shared(p) => p.distance(a, b),
        }
    }
}

/// The interface of spec §4.1: description, deviation, average, apply.
pub trait DescriptionType: Sync {
    /// One trajectory's description.
    type Desc: Clone + Send + Sync;
    /// The type with frequency bins `bins`.
    fn with_bins(bins: Bins) -> Self
    where
        Self: Sized;
    /// The amplitude spectra of a description (one per axis it keeps), for shared bins.
    fn amplitude_spectra<'a>(&self, d: &'a Self::Desc) -> Vec<&'a [f32]>;
    /// The description of a trajectory (one loop, uniform samples; the last sample does not
    /// repeat the first).
    fn describe(&self, trajectory: &[Vec3]) -> Self::Desc;
    /// Dissimilarity ≥ 0; 0 for descriptions the type cannot tell apart.
    fn deviation(&self, a: &Self::Desc, b: &Self::Desc) -> f32;
    /// Weighted average (weights ≥ 0, not all 0); the centroid of k-means and a billboard's
    /// motion. An empty input gives the description of no motion.
    fn average(&self, ds: &[&Self::Desc], weights: &[f32]) -> Self::Desc;
    /// The motion the description stands for as one cosine series per world axis (what the
    /// runtime shader evaluates, spec §4.11 "runtime").
    fn components(&self, d: &Self::Desc) -> [Components; 3];
    /// The loop samples the description was made from (its components' time unit).
    fn samples(&self, d: &Self::Desc) -> usize;
    /// The zero-mean motion the description stands for, at `n` uniform samples of the loop.
    fn apply(&self, d: &Self::Desc, n: usize) -> Vec<Vec3> {
        sample_axes(&self.components(d), self.samples(d), n)
    }
}

/// The DFT of each coordinate of a trajectory.
fn axis_spectra(trajectory: &[Vec3]) -> [Spectrum; 3] {
    [0, 1, 2].map(|c| Spectrum::of(&trajectory.iter().map(|p| p[c]).collect::<Vec<f32>>()))
}

/// One binned spectrum: per bin a DFT frequency (cycles per loop), an amplitude and a phase.
#[derive(Clone, Debug, PartialEq)]
pub struct Components {
    /// Frequencies, cycles per loop (≥ 1).
    pub frequencies: Vec<usize>,
    /// Amplitude of each frequency, world units (`frequencies[i]` has `amplitudes[i]`).
    pub amplitudes: Vec<f32>,
    /// Phase of each frequency, radians (the spectrum's cosine convention).
    pub phases: Vec<f32>,
}

impl Components {
    /// No motion.
    pub fn none() -> Self {
        Components {
            frequencies: Vec::new(),
            amplitudes: Vec::new(),
            phases: Vec::new(),
        }
    }

    /// The non-zero bins of dense per-frequency arrays (index i = frequency i + 1), as they are.
    pub fn from_dense(amplitudes: &[f32], phases: &[f32]) -> Self {
        let mut c = Components::none();
        for (i, (&a, &p)) in amplitudes.iter().zip(phases).enumerate() {
            if a > 0.0 {
                c.frequencies.push(Spectrum::frequency(i));
                c.amplitudes.push(a);
                c.phases.push(p);
            }
        }
        c
    }

    /// The value at fractional sample `s` of `n`.
    pub fn value_at(&self, s: f32, n: usize) -> f32 {
        let n = n.max(1) as f64;
        let mut v = 0.0f64;
        for ((&f, &a), &p) in self
            .frequencies
            .iter()
            .zip(&self.amplitudes)
            .zip(&self.phases)
        {
            v += f64::from(a)
                * (std::f64::consts::TAU * f as f64 * f64::from(s) / n + f64::from(p)).cos();
        }
        v as f32
    }

    /// As a dense amplitude array over frequencies 1..=len (for amplitude distances).
    pub fn dense(&self, len: usize) -> Vec<f32> {
        let mut d = vec![0.0; len];
        for (&f, &a) in self.frequencies.iter().zip(&self.amplitudes) {
            if (1..=len).contains(&f) {
                d[f - 1] += a;
            }
        }
        d
    }
}

/// An angle wrapped into (−π, π].
fn wrap(a: f32) -> f32 {
    let t = std::f32::consts::TAU;
    let w = a - t * (a / t).round();
    if w <= -std::f32::consts::PI { w + t } else { w }
}

/// The motion of three per-axis component sets at `n` uniform samples of a loop the
/// description was made with `samples` samples of (the same loop fractions).
fn sample_axes(comps: &[Components; 3], samples: usize, n: usize) -> Vec<Vec3> {
    let scale = samples.max(1) as f32 / n.max(1) as f32;
    (0..n)
        .map(|s| {
            let t = s as f32 * scale;
            Vec3::new(
                comps[0].value_at(t, samples),
                comps[1].value_at(t, samples),
                comps[2].value_at(t, samples),
            )
        })
        .collect()
}

/// The frequency-binned weighted average of spectra (§4.10): bins over every member's
/// amplitudes; per bin the frequency nearest its centroid, the weighted mean of the members'
/// total amplitude in the bin, and their amplitude-weighted cyclic mean phase (a member's
/// phases shifted by `flip[i]` radians first, e.g. π for a reversed axis).
pub fn binned_average(
    spectra: &[(&[f32], &[f32])],
    weights: &[f32],
    bins: usize,
    flip: &[f32],
) -> Components {
    let len = spectra.iter().map(|(a, _)| a.len()).min().unwrap_or(0);
    let total_w: f32 = weights.iter().sum();
    if len == 0 || total_w <= 0.0 {
        return Components::none();
    }
    // Weight each member's amplitudes in the binning so heavy members shape the bins.
    let scaled: Vec<Vec<f32>> = spectra
        .iter()
        .zip(weights)
        .map(|((a, _), w)| a[..len].iter().map(|x| x * w).collect())
        .collect();
    let refs: Vec<&[f32]> = scaled.iter().map(|v| v.as_slice()).collect();
    let b = frequency_bins(&refs, bins.clamp(1, len));
    let mut out = Components::none();
    for (members, freq) in b.bins.iter().zip(b.rounded_frequencies()) {
        let mut amp = 0.0f32;
        let (mut angles, mut ws) = (Vec::new(), Vec::new());
        for (m, ((a, p), w)) in spectra.iter().zip(weights).enumerate() {
            for &i in members {
                amp += a[i] * w;
                angles.push(p[i] + flip.get(m).copied().unwrap_or(0.0));
                ws.push(a[i] * w);
            }
        }
        let amp = amp / total_w;
        if amp <= 0.0 {
            continue;
        }
        out.frequencies.push(freq.min(len));
        out.amplitudes.push(amp);
        // Cancelled phases (opposite motions of equal weight) leave no defined phase: 0.
        out.phases.push(angle_average(&angles, &ws).unwrap_or(0.0));
    }
    out
}

/// Amplitude-weighted phase difference of two phase arrays (spec §4.7, [ENG] weighted by the
/// amplitudes so a frequency with no energy, whose phase is noise, adds nothing): per
/// frequency, both phases' distance to their amplitude-weighted mean, weighted by amplitude,
/// over the total amplitude.
fn weighted_phase_difference(a: (&[f32], &[f32]), b: (&[f32], &[f32])) -> f32 {
    let len = a.0.len().min(b.0.len());
    let total: f32 = (0..len).map(|i| a.0[i] + b.0[i]).sum();
    if total <= 0.0 {
        return 0.0;
    }
    // Skip the trigonometry of frequencies that each carry under 0.1 % of the weight (most of
    // a leaf's spectrum is such noise); each would add under 0.1 % · π.
    let floor = 1e-3 * total;
    let mut sum = 0.0f32;
    for i in 0..len {
        let (wa, wb) = (a.0[i], b.0[i]);
        if wa + wb <= floor {
            continue;
        }
        // The weighted circular mean of two angles in closed form: it lies θ from a towards
        // b, θ = atan2(w_b sin d, w_a + w_b cos d) with d the wrapped b − a.
        let d = wrap(b.1[i] - a.1[i]);
        let theta = (wb * d.sin()).atan2(wa + wb * d.cos());
        sum += wa * theta.abs() + wb * wrap(d - theta).abs();
    }
    sum / total
}

/// The naive spectral type (§4.7): the three coordinate spectra, amplitude and phase.
/// Deviation `NEP(A, P)`: A the binned amplitude distance summed over axes, P the
/// amplitude-weighted phase difference summed over axes. Average: binned mean amplitudes and
/// amplitude-weighted cyclic mean phases per axis. Lossless, but time offsets count as
/// differences and opposite lines average to a circle (the thesis's flaws, kept on purpose).
#[derive(Clone, Debug)]
pub struct Naive {
    /// Frequency bins of deviation and average.
    pub bins: Bins,
}

/// A naive description: per axis the amplitude and phase of every frequency.
#[derive(Clone, Debug, PartialEq)]
pub struct NaiveDesc {
    /// Per axis (x, y, z), the amplitude of every frequency (index i is frequency i + 1
    /// cycles per loop).
    pub amplitudes: [Vec<f32>; 3],
    /// Per axis, the phase of every frequency, radians.
    pub phases: [Vec<f32>; 3],
    /// Samples of the loop the spectra came from.
    pub samples: usize,
    /// The average's binned components (None for a described trajectory, which applies its
    /// own full spectrum).
    pub components: Option<[Components; 3]>,
}

impl DescriptionType for Naive {
    type Desc = NaiveDesc;

    fn with_bins(bins: Bins) -> Self {
        Naive { bins }
    }

    fn amplitude_spectra<'a>(&self, d: &'a NaiveDesc) -> Vec<&'a [f32]> {
        d.amplitudes.iter().map(|a| a.as_slice()).collect()
    }

    fn describe(&self, trajectory: &[Vec3]) -> NaiveDesc {
        let s = axis_spectra(trajectory);
        NaiveDesc {
            amplitudes: [0, 1, 2].map(|c| s[c].amplitudes.clone()),
            phases: [0, 1, 2].map(|c| s[c].phases.clone()),
            samples: trajectory.len(),
            components: None,
        }
    }

    fn deviation(&self, a: &NaiveDesc, b: &NaiveDesc) -> f32 {
        let (mut amp, mut phase) = (0.0, 0.0);
        for c in 0..3 {
            amp += self.bins.distance(&a.amplitudes[c], &b.amplitudes[c]);
            phase += weighted_phase_difference(
                (&a.amplitudes[c], &a.phases[c]),
                (&b.amplitudes[c], &b.phases[c]),
            );
        }
        nep(amp, phase)
    }

    fn average(&self, ds: &[&NaiveDesc], weights: &[f32]) -> NaiveDesc {
        let samples = ds.first().map_or(0, |d| d.samples);
        let comps = [0, 1, 2].map(|c| {
            let spectra: Vec<(&[f32], &[f32])> = ds
                .iter()
                .map(|d| (d.amplitudes[c].as_slice(), d.phases[c].as_slice()))
                .collect();
            binned_average(&spectra, weights, self.bins.count(), &[])
        });
        let len = ds.iter().map(|d| d.amplitudes[0].len()).min().unwrap_or(0);
        NaiveDesc {
            amplitudes: [0, 1, 2].map(|c| comps[c].dense(len)),
            phases: [0, 1, 2].map(|c| {
                let mut p = vec![0.0; len];
                for (&f, &ph) in comps[c].frequencies.iter().zip(&comps[c].phases) {
                    if (1..=len).contains(&f) {
                        p[f - 1] = ph;
                    }
                }
                p
            }),
            samples,
            components: Some(comps),
        }
    }

    fn components(&self, d: &NaiveDesc) -> [Components; 3] {
        d.components.clone().unwrap_or_else(|| {
            [0, 1, 2].map(|c| Components::from_dense(&d.amplitudes[c], &d.phases[c]))
        })
    }

    fn samples(&self, d: &NaiveDesc) -> usize {
        d.samples
    }
}

/// The dominating-axis type (§4.8): the axis through the two samples farthest apart and the
/// spectrum of the motion along it. Deviation with the erratum fixed:
/// `NEP(1 − |a₁·a₂|, ampDist(X₁, X₂))` (0 only when both the lines and the spectra agree);
/// phase is ignored, so time offsets cost nothing. Average: the principal eigenvector of
/// `Σ w a aᵀ` as the axis, binned amplitudes and cyclic phases (members whose axis points
/// against it have their phase turned by π). Circular motion has no dominating axis: the
/// brute-force pair search still returns one (the first farthest pair), never NaN.
#[derive(Clone, Debug)]
pub struct DominatingAxisType {
    /// Frequency bins of deviation and average.
    pub bins: Bins,
}

/// A dominating-axis description.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisDesc {
    /// Unit axis; zero for no motion.
    pub axis: Vec3,
    /// Amplitude of the motion along the axis at every frequency (index i is frequency
    /// i + 1 cycles per loop).
    pub amplitudes: Vec<f32>,
    /// Phase of every frequency, radians.
    pub phases: Vec<f32>,
    /// Samples of the loop the spectrum came from.
    pub samples: usize,
    /// The average's binned components (None for a described trajectory, which applies
    /// its own full spectrum).
    pub components: Option<Components>,
}

/// Principal eigenvector of a symmetric 3×3 matrix by power iteration from the largest column
/// (deterministic; the matrices here are sums of outer products, positive semi-definite).
pub fn principal_axis(m: Mat3) -> Vec3 {
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let mut v = cols
        .iter()
        .copied()
        .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
        .unwrap_or(Vec3::X)
        .normalize_or_zero();
    if v == Vec3::ZERO {
        return Vec3::ZERO;
    }
    for _ in 0..64 {
        let next = (m * v).normalize_or_zero();
        if next == Vec3::ZERO {
            break;
        }
        v = next;
    }
    v
}

impl DescriptionType for DominatingAxisType {
    type Desc = AxisDesc;

    fn with_bins(bins: Bins) -> Self {
        DominatingAxisType { bins }
    }

    fn amplitude_spectra<'a>(&self, d: &'a AxisDesc) -> Vec<&'a [f32]> {
        vec![d.amplitudes.as_slice()]
    }

    fn describe(&self, trajectory: &[Vec3]) -> AxisDesc {
        let d = dominating_axis(trajectory);
        let s = Spectrum::of(&d.motion);
        AxisDesc {
            axis: d.axis,
            amplitudes: s.amplitudes,
            phases: s.phases,
            samples: trajectory.len(),
            components: None,
        }
    }

    fn deviation(&self, a: &AxisDesc, b: &AxisDesc) -> f32 {
        // No motion on one side: the axes do not matter, only the amplitudes.
        let axis = if a.axis == Vec3::ZERO || b.axis == Vec3::ZERO {
            0.0
        } else {
            (1.0 - a.axis.dot(b.axis).abs()).max(0.0)
        };
        nep(axis, self.bins.distance(&a.amplitudes, &b.amplitudes))
    }

    fn average(&self, ds: &[&AxisDesc], weights: &[f32]) -> AxisDesc {
        let samples = ds.first().map_or(0, |d| d.samples);
        let mut m = Mat3::ZERO;
        for (d, &w) in ds.iter().zip(weights) {
            // Weighted by motion too: a still leaf's arbitrary axis must not steer the mean.
            let energy: f32 = d.amplitudes.iter().sum();
            let a = d.axis;
            m += Mat3::from_cols(a * a.x, a * a.y, a * a.z) * (w * energy);
        }
        let mut axis = principal_axis(m);
        // The same sign rule as `dominating_axis`: largest component positive.
        let largest = axis
            .to_array()
            .into_iter()
            .fold(0.0f32, |l, c| if c.abs() > l.abs() { c } else { l });
        if largest < 0.0 {
            axis = -axis;
        }
        let flip: Vec<f32> = ds
            .iter()
            .map(|d| {
                if d.axis.dot(axis) < 0.0 {
                    std::f32::consts::PI
                } else {
                    0.0
                }
            })
            .collect();
        // Project each member's motion on the average axis: |a·ā| of its amplitude survives.
        let scaled: Vec<Vec<f32>> = ds
            .iter()
            .map(|d| {
                let c = d.axis.dot(axis).abs();
                d.amplitudes.iter().map(|x| x * c).collect()
            })
            .collect();
        let spectra: Vec<(&[f32], &[f32])> = ds
            .iter()
            .zip(&scaled)
            .map(|(d, a)| (a.as_slice(), d.phases.as_slice()))
            .collect();
        let comps = binned_average(&spectra, weights, self.bins.count(), &flip);
        let len = ds.iter().map(|d| d.amplitudes.len()).min().unwrap_or(0);
        let mut phases = vec![0.0; len];
        for (&f, &p) in comps.frequencies.iter().zip(&comps.phases) {
            if (1..=len).contains(&f) {
                phases[f - 1] = p;
            }
        }
        AxisDesc {
            axis: if comps.amplitudes.is_empty() {
                Vec3::ZERO
            } else {
                axis
            },
            amplitudes: comps.dense(len),
            phases,
            samples,
            components: Some(comps),
        }
    }

    fn components(&self, d: &AxisDesc) -> [Components; 3] {
        let comps = d
            .components
            .clone()
            .unwrap_or_else(|| Components::from_dense(&d.amplitudes, &d.phases));
        // The motion along the axis, projected on each world axis: a negative component is
        // the same cosine turned by π.
        [0, 1, 2].map(|c| {
            let k = d.axis[c];
            let mut out = Components::none();
            if k == 0.0 {
                return out;
            }
            for ((&f, &a), &p) in comps
                .frequencies
                .iter()
                .zip(&comps.amplitudes)
                .zip(&comps.phases)
            {
                out.frequencies.push(f);
                out.amplitudes.push(a * k.abs());
                out.phases.push(if k < 0.0 {
                    wrap(p + std::f32::consts::PI)
                } else {
                    p
                });
            }
            out
        })
    }

    fn samples(&self, d: &AxisDesc) -> usize {
        d.samples
    }
}

/// The axis-phase type (§4.9): the three amplitude spectra and, per frequency, the phase
/// relationships `φ_xy = φ_x − φ_y`, `φ_xz = φ_x − φ_z`, which a time offset leaves unchanged.
/// Deviation `NEP(A, P)`, P weighting each relationship's cyclic difference by the pair's mean
/// of `relation_weight` `√(A_x·A_y)` (resp. `√(A_x·A_z)`). Average: mean amplitudes, weighted cyclic means of the
/// relationships. Apply: instead of the thesis's random `φ_x` (§4.9) the members' own
/// amplitude-weighted mean `φ_x`, so billboards whose leaves swing together keep their timing;
/// where the members disagree the mean is as arbitrary as a random pick. Lossy: inter-frequency
/// phase offsets are not kept (the thesis's counterexample; see the tests).
#[derive(Clone, Debug)]
pub struct AxisPhase {
    /// Frequency bins of deviation and average.
    pub bins: Bins,
}

/// An axis-phase description.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisPhaseDesc {
    /// Per axis (x, y, z), the amplitude of every frequency (index i is frequency i + 1
    /// cycles per loop).
    pub amplitudes: [Vec<f32>; 3],
    /// φ_x − φ_y per frequency.
    pub phase_xy: Vec<f32>,
    /// φ_x − φ_z per frequency.
    pub phase_xz: Vec<f32>,
    /// φ_x per frequency (used only by `apply`, never by deviation).
    pub phase_x: Vec<f32>,
    /// Samples of the loop the spectra came from.
    pub samples: usize,
}

/// How much the relationship of x with axis `c` (1 = y, 2 = z) at frequency index `i` means:
/// `√(A_x·A_c)`. The spec's suggested `A_x + A_c` [ENG] weights a relationship fully when one
/// axis has no energy at that frequency, whose phase is then rounding noise: a leaf swinging in
/// x alone would differ from its own time offset. The geometric mean vanishes then.
fn relation_weight(d: &AxisPhaseDesc, c: usize, i: usize) -> f32 {
    (d.amplitudes[0][i] * d.amplitudes[c][i]).max(0.0).sqrt()
}

impl DescriptionType for AxisPhase {
    type Desc = AxisPhaseDesc;

    fn with_bins(bins: Bins) -> Self {
        AxisPhase { bins }
    }

    fn amplitude_spectra<'a>(&self, d: &'a AxisPhaseDesc) -> Vec<&'a [f32]> {
        d.amplitudes.iter().map(|a| a.as_slice()).collect()
    }

    fn describe(&self, trajectory: &[Vec3]) -> AxisPhaseDesc {
        let s = axis_spectra(trajectory);
        let len = s[0].amplitudes.len();
        AxisPhaseDesc {
            amplitudes: [0, 1, 2].map(|c| s[c].amplitudes.clone()),
            phase_xy: (0..len).map(|i| s[0].phases[i] - s[1].phases[i]).collect(),
            phase_xz: (0..len).map(|i| s[0].phases[i] - s[2].phases[i]).collect(),
            phase_x: s[0].phases.clone(),
            samples: trajectory.len(),
        }
    }

    fn deviation(&self, a: &AxisPhaseDesc, b: &AxisPhaseDesc) -> f32 {
        let amp: f32 = (0..3)
            .map(|c| self.bins.distance(&a.amplitudes[c], &b.amplitudes[c]))
            .sum();
        let len = a.phase_xy.len().min(b.phase_xy.len());
        let mut phase = 0.0f32;
        let weights: Vec<[f32; 2]> = (0..len)
            .map(|i| {
                let w = |d: &AxisPhaseDesc, c: usize| relation_weight(d, c, i);
                [0.5 * (w(a, 1) + w(b, 1)), 0.5 * (w(a, 2) + w(b, 2))]
            })
            .collect();
        // As in the naive deviation: relations that each carry under 0.1 % of the weight are
        // skipped.
        let floor = 1e-3 * weights.iter().map(|w| w[0] + w[1]).sum::<f32>();
        for (i, w) in weights.iter().enumerate() {
            if w[0] > floor {
                phase += w[0] * angle_difference(a.phase_xy[i], b.phase_xy[i]);
            }
            if w[1] > floor {
                phase += w[1] * angle_difference(a.phase_xz[i], b.phase_xz[i]);
            }
        }
        nep(amp, phase)
    }

    fn average(&self, ds: &[&AxisPhaseDesc], weights: &[f32]) -> AxisPhaseDesc {
        let len = ds.iter().map(|d| d.phase_xy.len()).min().unwrap_or(0);
        let total: f32 = weights.iter().sum();
        let samples = ds.first().map_or(0, |d| d.samples);
        let mean_amp = |c: usize, i: usize| -> f32 {
            if total <= 0.0 {
                return 0.0;
            }
            ds.iter()
                .zip(weights)
                .map(|(d, w)| d.amplitudes[c][i] * w)
                .sum::<f32>()
                / total
        };
        let cyclic = |f: &dyn Fn(&AxisPhaseDesc) -> f32, wf: &dyn Fn(&AxisPhaseDesc) -> f32| {
            let angles: Vec<f32> = ds.iter().map(|d| f(d)).collect();
            let ws: Vec<f32> = ds.iter().zip(weights).map(|(d, w)| wf(d) * w).collect();
            angle_average(&angles, &ws).unwrap_or(0.0)
        };
        AxisPhaseDesc {
            amplitudes: [0, 1, 2].map(|c| (0..len).map(|i| mean_amp(c, i)).collect()),
            phase_xy: (0..len)
                .map(|i| cyclic(&|d| d.phase_xy[i], &|d| relation_weight(d, 1, i)))
                .collect(),
            phase_xz: (0..len)
                .map(|i| cyclic(&|d| d.phase_xz[i], &|d| relation_weight(d, 2, i)))
                .collect(),
            phase_x: (0..len)
                .map(|i| cyclic(&|d| d.phase_x[i], &|d| d.amplitudes[0][i]))
                .collect(),
            samples,
        }
    }

    fn components(&self, d: &AxisPhaseDesc) -> [Components; 3] {
        let phases: [Vec<f32>; 3] = [0, 1, 2].map(|c| {
            (0..d.phase_xy.len())
                .map(|i| match c {
                    0 => d.phase_x[i],
                    1 => wrap(d.phase_x[i] - d.phase_xy[i]),
                    _ => wrap(d.phase_x[i] - d.phase_xz[i]),
                })
                .collect()
        });
        [0, 1, 2].map(|c| Components::from_dense(&d.amplitudes[c], &phases[c]))
    }

    fn samples(&self, d: &AxisPhaseDesc) -> usize {
        d.samples
    }
}

/// The three description types by name, for command lines and reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpectralKind {
    /// [`Naive`]: per-axis amplitudes and phases.
    Naive,
    /// [`DominatingAxisType`]: one axis and the spectrum along it.
    DominatingAxis,
    /// [`AxisPhase`]: amplitudes and phase relationships between the axes.
    AxisPhase,
}

impl SpectralKind {
    /// Every kind, in the spec's order.
    pub const ALL: [SpectralKind; 3] = [
        SpectralKind::Naive,
        SpectralKind::DominatingAxis,
        SpectralKind::AxisPhase,
    ];
    /// `naive`, `dominating-axis` or `axis-phase`.
    pub fn name(self) -> &'static str {
        match self {
            SpectralKind::Naive => "naive",
            SpectralKind::DominatingAxis => "dominating-axis",
            SpectralKind::AxisPhase => "axis-phase",
        }
    }
    /// The kind named `s` ([`Self::name`]).
    pub fn parse(s: &str) -> Option<SpectralKind> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}
