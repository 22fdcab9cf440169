//! The DFT of one uniformly sampled, looping 1-D signal, with the conventions the thesis leaves
//! open decided here once (spec animated-billboard-clouds §4.5 \[ENG\]):
//! - the DC bin (k = 0) is kept apart as the mean value, not part of the spectrum;
//! - real input is conjugate-symmetric, so only k = 1..=⌊N/2⌋ are kept;
//! - amplitudes are scaled so a component reads as its real amplitude: `2|X_k|/N`, and `|X_k|/N`
//!   at the Nyquist bin of an even N;
//! - phases are `atan2(im, re)` of the cosine form, so
//!   `x(t_n) = mean + Σ_k A_k cos(2π k n / N + φ_k)`; `10 cos t` has φ₁ = 0 and `10 sin t`
//!   φ₁ = −π/2.

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;
use serde::Serialize;

/// One signal's spectrum (frequencies in cycles per loop: index i holds k = i + 1).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Spectrum {
    /// Mean of the signal (the DC bin).
    pub mean: f32,
    /// Amplitude per frequency k = 1..=⌊N/2⌋.
    pub amplitudes: Vec<f32>,
    /// Phase per frequency (radians, cosine form).
    pub phases: Vec<f32>,
    /// Number of samples N the signal had.
    pub samples: usize,
}

impl Spectrum {
    /// The spectrum of `signal` (one loop, uniformly sampled, last sample not repeating the
    /// first). An empty signal gives an empty spectrum.
    pub fn of(signal: &[f32]) -> Spectrum {
        let n = signal.len();
        if n == 0 {
            return Spectrum {
                mean: 0.0,
                amplitudes: Vec::new(),
                phases: Vec::new(),
                samples: 0,
            };
        }
        let mut planner = RealFftPlanner::<f64>::new();
        let fft = planner.plan_fft_forward(n);
        let mut input: Vec<f64> = signal.iter().map(|&x| f64::from(x)).collect();
        let mut output = vec![Complex::new(0.0, 0.0); n / 2 + 1];
        // Lengths match the plan, so this cannot fail.
        if fft.process(&mut input, &mut output).is_err() {
            return Spectrum::of(&[]);
        }
        let nf = n as f64;
        let mut amplitudes = Vec::with_capacity(n / 2);
        let mut phases = Vec::with_capacity(n / 2);
        for (k, c) in output.iter().enumerate().skip(1) {
            let scale = if n.is_multiple_of(2) && k == n / 2 {
                1.0 / nf
            } else {
                2.0 / nf
            };
            amplitudes.push((c.norm() * scale) as f32);
            phases.push(c.im.atan2(c.re) as f32);
        }
        Spectrum {
            mean: (output[0].re / nf) as f32,
            amplitudes,
            phases,
            samples: n,
        }
    }

    /// The signal back at its N samples (inverse DFT of the kept bins).
    pub fn signal(&self) -> Vec<f32> {
        (0..self.samples).map(|n| self.value_at(n as f32)).collect()
    }

    /// The signal at fractional sample position `s` (the loop is periodic in N).
    pub fn value_at(&self, s: f32) -> f32 {
        let n = self.samples.max(1) as f64;
        let mut v = f64::from(self.mean);
        for (i, (a, p)) in self.amplitudes.iter().zip(&self.phases).enumerate() {
            let k = (i + 1) as f64;
            v += f64::from(*a)
                * (std::f64::consts::TAU * k * f64::from(s) / n + f64::from(*p)).cos();
        }
        v as f32
    }

    /// Frequency (cycles per loop) of amplitude index `i`.
    pub fn frequency(i: usize) -> usize {
        i + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::{FRAC_PI_2, TAU};

    fn sampled(n: usize, f: impl Fn(f32) -> f32) -> Vec<f32> {
        (0..n).map(|i| f(TAU * i as f32 / n as f32)).collect()
    }

    #[test]
    fn thesis_worked_example() {
        // p_x = 10 sin(t + π/2) = 10 cos t; p_y = 10 sin t + sin 30t (spec §4.5).
        let x = Spectrum::of(&sampled(128, |t| 10.0 * (t + FRAC_PI_2).sin()));
        assert!((x.amplitudes[0] - 10.0).abs() < 1e-4);
        assert!(x.phases[0].abs() < 1e-4, "cosine phase 0");
        assert!(x.amplitudes[1..].iter().all(|a| *a < 1e-4));
        let y = Spectrum::of(&sampled(128, |t| 10.0 * t.sin() + (30.0 * t).sin()));
        assert!((y.amplitudes[0] - 10.0).abs() < 1e-4);
        assert!((y.amplitudes[29] - 1.0).abs() < 1e-4);
        assert!(
            (y.phases[0] + FRAC_PI_2).abs() < 1e-4,
            "sine = cosine at −π/2"
        );
        let others: f32 = y
            .amplitudes
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != 0 && *i != 29)
            .map(|(_, a)| a)
            .sum();
        assert!(others < 1e-3);
    }

    #[test]
    fn mean_nyquist_and_round_trip() {
        let sig: Vec<f32> = (0..16)
            .map(|i| 3.0 + if i % 2 == 0 { 1.0 } else { -1.0 } + (i as f32 * 0.7).sin())
            .collect();
        let s = Spectrum::of(&sig);
        assert_eq!(s.amplitudes.len(), 8);
        let back = s.signal();
        for (a, b) in sig.iter().zip(&back) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        // The alternating ±1 sits at Nyquist with amplitude 1.
        let pure = Spectrum::of(
            &(0..16)
                .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
                .collect::<Vec<_>>(),
        );
        assert!((pure.amplitudes[7] - 1.0).abs() < 1e-5);
        assert!(pure.mean.abs() < 1e-6);
        // Odd lengths work too.
        let odd = sampled(15, |t| 2.0 * (3.0 * t).cos() + 1.0);
        let so = Spectrum::of(&odd);
        assert!((so.amplitudes[2] - 2.0).abs() < 1e-4 && (so.mean - 1.0).abs() < 1e-5);
        assert_eq!(Spectrum::of(&[]).amplitudes.len(), 0);
    }

    #[test]
    fn time_offset_changes_only_the_phase() {
        let a = Spectrum::of(&sampled(64, |t| (2.0 * t).sin() + 0.5 * (5.0 * t).cos()));
        let b = Spectrum::of(&sampled(64, |t| {
            (2.0 * (t + 0.3)).sin() + 0.5 * (5.0 * (t + 0.3)).cos()
        }));
        for (x, y) in a.amplitudes.iter().zip(&b.amplitudes) {
            assert!((x - y).abs() < 1e-4);
        }
        assert!((a.phases[1] - b.phases[1]).abs() > 0.1);
    }
}
