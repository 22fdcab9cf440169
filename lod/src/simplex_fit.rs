//! Least squares over skin weights: minimise `xᵀHx − 2cᵀx` with `x` split into blocks, each
//! block non-negative and summing to one (one vertex's weights over its candidate joints), the
//! weight step of smooth skinning decomposition (Le & Deng 2012, "Smooth Skinning
//! Decomposition with Rigid Bones", §3.2: per vertex, bone transforms fixed). Both the trimmed
//! cards' skins and the joint budget's fitted weights solve it.
//!
//! Written here rather than taken from a crate: the problems are tiny (a few blocks of at most
//! a few dozen weights) and solved thousands of times a LOD, where a general quadratic-program
//! crate's set-up costs more than the solve; accelerated projected gradient (FISTA, Beck &
//! Teboulle 2009) on the product of simplices is a few lines and needs no factorisation, and
//! one simplex of a few weights is solved exactly by an active set.

/// Solves `min xᵀHx − 2cᵀx` over `x` in the product of simplices of `block` weights each,
/// starting from `x` (already on them), in `iterations` accelerated projected-gradient steps.
/// `h` is the `n × n` Gram matrix row by row (`n = x.len()`, a multiple of `block`).
pub fn fit_on_simplices(h: &[f64], c: &[f64], x: &mut [f64], block: usize, iterations: usize) {
    let n = x.len();
    if n == 0 || block == 0 || h.len() != n * n || c.len() != n {
        return;
    }
    // The Frobenius norm bounds the largest eigenvalue: a safe step.
    let lipschitz = h.iter().map(|v| v * v).sum::<f64>().sqrt();
    if lipschitz.is_nan() || lipschitz <= 0.0 {
        return;
    }
    let (mut y, mut previous, mut momentum) = (x.to_vec(), x.to_vec(), 1.0f64);
    for _ in 0..iterations {
        for a in 0..n {
            let row = &h[a * n..(a + 1) * n];
            let g: f64 = row.iter().zip(&y).map(|(h, y)| h * y).sum::<f64>() - c[a];
            x[a] = y[a] - g / lipschitz;
        }
        for b in x.chunks_mut(block) {
            project_to_simplex(b);
        }
        let next = 0.5 * (1.0 + (1.0 + 4.0 * momentum * momentum).sqrt());
        for a in 0..n {
            y[a] = x[a] + (momentum - 1.0) / next * (x[a] - previous[a]);
        }
        momentum = next;
        previous.copy_from_slice(x);
    }
}

/// Solves `min xᵀHx − 2cᵀx` over one simplex (`x ≥ 0`, `Σx = 1`) exactly, by the primal
/// active-set method (Nocedal & Wright, "Numerical Optimization", §16.5): the equality-
/// constrained minimum over the weights left free, a step back to the simplex where it
/// leaves it, and a weight freed where its multiplier says the objective falls. Starts from
/// `x` (on the simplex). For the few weights of one vertex it ends in a handful of small
/// solves at the exact minimum, where projected gradient needs an iteration count and a step
/// from a bound on the largest eigenvalue. A tiny ridge keeps joints with identical paths
/// solvable.
pub fn solve_on_simplex(h: &[f64], c: &[f64], x: &mut [f64]) {
    let n = x.len();
    if n == 0 || h.len() != n * n || c.len() != n {
        return;
    }
    let ridge = 1e-12 * (0..n).map(|i| h[i * n + i].abs()).sum::<f64>().max(1e-300);
    let mut free: Vec<bool> = x.iter().map(|&v| v > 0.0).collect();
    for _ in 0..(4 * n + 8) {
        let Some(p) = equality_minimum(h, c, &free, ridge) else {
            return;
        };
        // Step towards p as far as the simplex allows.
        let mut step = 1.0f64;
        let mut blocking = None;
        for i in (0..n).filter(|&i| free[i] && p[i] < x[i]) {
            let t = x[i] / (x[i] - p[i]);
            if t < step {
                step = t;
                blocking = Some(i);
            }
        }
        for i in 0..n {
            x[i] += step * (p[i] - x[i]);
        }
        if let Some(i) = blocking {
            x[i] = 0.0;
            free[i] = false;
            continue;
        }
        // At the free set's minimum: free the fixed weight whose multiplier is most negative.
        let gradient: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| h[i * n + j] * x[j]).sum::<f64>() - c[i])
            .collect();
        let Some(level) = (0..n)
            .filter(|&i| free[i])
            .map(|i| gradient[i])
            .reduce(f64::min)
        else {
            return;
        };
        let entering = (0..n)
            .filter(|&i| !free[i] && gradient[i] < level - 1e-12 * level.abs().max(1e-300))
            .min_by(|&a, &b| gradient[a].total_cmp(&gradient[b]));
        match entering {
            Some(i) => free[i] = true,
            None => break,
        }
    }
    let total: f64 = x.iter().map(|v| v.max(0.0)).sum();
    if total > 0.0 {
        x.iter_mut().for_each(|v| *v = v.max(0.0) / total);
    }
}

/// The minimum of `xᵀ(H + ridge)x − 2cᵀx` with `Σx = 1` over the weights `free` marks, the
/// others zero (the KKT system by Gaussian elimination); None when it is singular.
fn equality_minimum(h: &[f64], c: &[f64], free: &[bool], ridge: f64) -> Option<Vec<f64>> {
    let n = free.len();
    let idx: Vec<usize> = (0..n).filter(|&i| free[i]).collect();
    let m = idx.len() + 1;
    let mut a = vec![0.0f64; m * (m + 1)];
    for (r, &i) in idx.iter().enumerate() {
        for (k, &j) in idx.iter().enumerate() {
            a[r * (m + 1) + k] = h[i * n + j] + if i == j { ridge } else { 0.0 };
        }
        a[r * (m + 1) + m - 1] = 1.0;
        a[r * (m + 1) + m] = c[i];
        a[(m - 1) * (m + 1) + r] = 1.0;
    }
    a[(m - 1) * (m + 1) + m] = 1.0;
    let solution = gauss_solve(&mut a, m)?;
    let mut p = vec![0.0f64; n];
    for (r, &i) in idx.iter().enumerate() {
        p[i] = solution[r];
    }
    Some(p)
}

/// Solves the `m × m` system whose augmented rows are `a` (`m + 1` values each) by Gaussian
/// elimination with partial pivoting; None when a pivot vanishes.
fn gauss_solve(a: &mut [f64], m: usize) -> Option<Vec<f64>> {
    let w = m + 1;
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs())).max(1e-300);
    for col in 0..m {
        let pivot =
            (col..m).max_by(|&r, &s| a[r * w + col].abs().total_cmp(&a[s * w + col].abs()))?;
        if a[pivot * w + col].abs() <= 1e-14 * scale {
            return None;
        }
        if pivot != col {
            for k in 0..w {
                a.swap(pivot * w + k, col * w + k);
            }
        }
        for r in (col + 1)..m {
            let f = a[r * w + col] / a[col * w + col];
            if f != 0.0 {
                for k in col..w {
                    a[r * w + k] -= f * a[col * w + k];
                }
            }
        }
    }
    let mut x = vec![0.0f64; m];
    for r in (0..m).rev() {
        let s: f64 = ((r + 1)..m).map(|k| a[r * w + k] * x[k]).sum();
        x[r] = (a[r * w + m] - s) / a[r * w + r];
    }
    Some(x)
}

/// `xᵀHx − 2cᵀx`: the objective [`fit_on_simplices`] lowers (add the targets' squared norm for
/// the residual).
pub fn objective(h: &[f64], c: &[f64], x: &[f64]) -> f64 {
    let n = x.len();
    (0..n)
        .map(|a| {
            let row = &h[a * n..(a + 1) * n];
            x[a] * (row.iter().zip(x).map(|(h, x)| h * x).sum::<f64>() - 2.0 * c[a])
        })
        .sum()
}

/// `x` replaced by its nearest point of the probability simplex (non-negative, summing to 1):
/// the sort-and-threshold projection.
pub fn project_to_simplex(x: &mut [f64]) {
    let mut sorted: Vec<f64> = x.to_vec();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let mut sum = 0.0;
    let mut theta = 0.0;
    for (k, &v) in sorted.iter().enumerate() {
        sum += v;
        let t = (sum - 1.0) / (k + 1) as f64;
        if v - t > 0.0 {
            theta = t;
        }
    }
    x.iter_mut().for_each(|v| *v = (*v - theta).max(0.0));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_lands_on_the_simplex() {
        let mut x = [0.7, 0.6, -0.2];
        project_to_simplex(&mut x);
        assert!((x.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((x[0] - 0.55).abs() < 1e-12 && (x[1] - 0.45).abs() < 1e-12 && x[2] == 0.0);
    }

    #[test]
    fn the_fit_finds_a_known_blend() {
        // Columns d₀ = (1, 0), d₁ = (0, 1) and target (0.25, 0.75): weights ¼, ¾.
        let h = [1.0, 0.0, 0.0, 1.0];
        let c = [0.25, 0.75];
        let mut x = [1.0, 0.0];
        fit_on_simplices(&h, &c, &mut x, 2, 500);
        assert!(
            (x[0] - 0.25).abs() < 1e-6 && (x[1] - 0.75).abs() < 1e-6,
            "{x:?}"
        );
        // A target off the simplex's reach: the nearest blend, all on one column.
        let c = [2.0, -1.0];
        let mut x = [0.5, 0.5];
        fit_on_simplices(&h, &c, &mut x, 2, 500);
        assert!((x[0] - 1.0).abs() < 1e-9 && x[1].abs() < 1e-9, "{x:?}");
        assert!(objective(&h, &c, &x) <= objective(&h, &c, &[0.5, 0.5]));
    }

    #[test]
    fn the_active_set_solve_is_exact_where_two_columns_nearly_agree() {
        // Columns (1, 0) and (−1, 0.2), nearly opposite, and a third of zeros; the target is
        // their mean (0, 0.1): weights ½, ½, 0 exactly, from the far corner.
        let d = [[1.0, 0.0], [-1.0, 0.2], [0.0, 0.0]];
        let t = [0.0, 0.1];
        let dot = |a: &[f64; 2], b: &[f64; 2]| a[0] * b[0] + a[1] * b[1];
        let h: Vec<f64> = (0..9).map(|k| dot(&d[k / 3], &d[k % 3])).collect();
        let c: Vec<f64> = (0..3).map(|k| dot(&d[k], &t)).collect();
        let mut x = [0.0, 0.0, 1.0];
        solve_on_simplex(&h, &c, &mut x);
        assert!(
            (x[0] - 0.5).abs() < 1e-9 && (x[1] - 0.5).abs() < 1e-9 && x[2].abs() < 1e-9,
            "{x:?}"
        );
        // A target outside every blend: the nearest vertex of the simplex.
        let c = [3.0, -1.0, 0.0];
        let mut x = [0.2, 0.3, 0.5];
        solve_on_simplex(&h, &c, &mut x);
        assert!((x[0] - 1.0).abs() < 1e-9, "{x:?}");
    }
}
