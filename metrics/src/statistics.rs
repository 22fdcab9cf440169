//! Run statistics (spec animated-billboard-clouds §5.8, thesis §8.3): mean, minimum, maximum and
//! the average absolute deviation `(1/n) Σ |x_i − x̄|` of repeated runs, and the Pareto front
//! of a two-objective trade-off (both minimised).

use serde::{Deserialize, Serialize};

/// Mean, min, max and average absolute deviation of a sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Number of values.
    pub n: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// `(1/n) Σ |x_i − mean|`.
    pub avg_abs_dev: f64,
    /// `avg_abs_dev / |mean|` (0 when the mean is 0), the thesis's "relative" column.
    pub relative: f64,
}

impl Spread {
    /// The spread of the finite values of `xs`; None when there are none.
    pub fn of(xs: &[f64]) -> Option<Spread> {
        let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let aad = v.iter().map(|x| (x - mean).abs()).sum::<f64>() / n as f64;
        Some(Spread {
            n,
            mean,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            avg_abs_dev: aad,
            relative: if mean == 0.0 { 0.0 } else { aad / mean.abs() },
        })
    }
}

/// Indices of the points not dominated by any other (both coordinates minimised): no other
/// point is at least as good in both and better in one. Sorted by the first coordinate; points
/// with a non-finite coordinate are never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    let mut best_y = f64::INFINITY;
    for i in idx {
        // Sorted by x then y: a point joins when it beats every cheaper point's y.
        if points[i].1 < best_y {
            best_y = points[i].1;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_known_values() {
        let s = Spread::of(&[1.0, 2.0, 3.0, 6.0]).unwrap();
        assert_eq!(s.n, 4);
        assert_eq!(s.mean, 3.0);
        assert_eq!((s.min, s.max), (1.0, 6.0));
        // |1-3| + |2-3| + |3-3| + |6-3| = 6, / 4.
        assert_eq!(s.avg_abs_dev, 1.5);
        assert_eq!(s.relative, 0.5);
        let c = Spread::of(&[0.25; 5]).unwrap();
        assert_eq!((c.avg_abs_dev, c.relative), (0.0, 0.0));
        assert_eq!(Spread::of(&[f64::NAN, 2.0]).unwrap().n, 1);
        assert!(Spread::of(&[f64::NAN]).is_none());
        assert!(Spread::of(&[]).is_none());
    }

    #[test]
    fn pareto_front_keeps_undominated_points() {
        // (time, error): 0 and 2 and 4 are undominated; 1 is beaten by 0, 3 by 2, 5 is NaN.
        let p = [
            (1.0, 0.5),
            (2.0, 0.6),
            (3.0, 0.2),
            (4.0, 0.2),
            (5.0, 0.1),
            (0.5, f64::NAN),
        ];
        assert_eq!(pareto_front(&p), vec![0, 2, 4]);
        // Equal points: only the first counts.
        assert_eq!(pareto_front(&[(1.0, 1.0), (1.0, 1.0)]), vec![0]);
        assert!(pareto_front(&[]).is_empty());
    }
}
