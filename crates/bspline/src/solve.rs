//! The least-squares system: banded Cholesky solve and the second-difference penalty.

use crate::BSplineError;
use glam::DVec3;

/// Cholesky factorisation (in place, lower triangle) of a symmetric positive definite matrix
/// stored densely (row-major, `n × n`) whose non-zeros lie within `bw` of the diagonal (pass
/// `n - 1` for a full matrix); then solves for three right-hand sides.
pub(crate) fn cholesky_solve(
    a: &mut [f64],
    n: usize,
    bw: usize,
    rhs: &mut [DVec3],
) -> Result<(), BSplineError> {
    // Relative pivot threshold against the largest diagonal entry.
    let max_diag = (0..n).map(|i| a[i * n + i]).fold(0.0f64, f64::max);
    let tiny = max_diag * 1e-14;
    for j in 0..n {
        let j0 = j.saturating_sub(bw);
        let mut d = a[j * n + j];
        for k in j0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= tiny {
            return Err(BSplineError::Singular { pivot: j });
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        let i_end = (j + bw + 1).min(n);
        for i in j + 1..i_end {
            let i0 = i.saturating_sub(bw).max(j0);
            let mut s = a[i * n + j];
            for k in i0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    // Forward: L y = b.
    for i in 0..n {
        let i0 = i.saturating_sub(bw);
        let mut s = rhs[i];
        for k in i0..i {
            s -= a[i * n + k] * rhs[k];
        }
        rhs[i] = s / a[i * n + i];
    }
    // Backward: Lᵀ x = y.
    for i in (0..n).rev() {
        let i_end = (i + bw + 1).min(n);
        let mut s = rhs[i];
        for k in i + 1..i_end {
            s -= a[k * n + i] * rhs[k];
        }
        rhs[i] = s / a[i * n + i];
    }
    Ok(())
}

/// Rows of the second-difference penalty matrix `D`: control indices and weights.
///
/// Closed (uniform knots): `P_i − 2P_{i+1} + P_{i+2}` (indices mod n). Open: second *divided*
/// differences with respect to the Greville abscissae `ξ_i` (the knot averages), scaled by the
/// mean abscissa spacing, so that the penalty vanishes exactly on curves that are linear in
/// `u` (with uniform knots this is the usual P-spline second difference).
pub(crate) fn penalty_rows(knots: &[f64], n: usize, closed: bool) -> Vec<([usize; 3], [f64; 3])> {
    if closed {
        return (0..n)
            .map(|i| ([i % n, (i + 1) % n, (i + 2) % n], [1.0, -2.0, 1.0]))
            .collect();
    }
    if n < 3 {
        return Vec::new();
    }
    let xi: Vec<f64> = (0..n)
        .map(|i| (knots[i + 1] + knots[i + 2] + knots[i + 3]) / 3.0)
        .collect();
    let mean = (xi[n - 1] - xi[0]) / (n - 1) as f64;
    let tiny = mean * 1e-9;
    (0..n - 2)
        .map(|i| {
            let d0 = (xi[i + 1] - xi[i]).max(tiny);
            let d1 = (xi[i + 2] - xi[i + 1]).max(tiny);
            let w0 = mean / d0;
            let w1 = mean / d1;
            ([i, i + 1, i + 2], [w0, -(w0 + w1), w1])
        })
        .collect()
}

/// Adds `λ DᵀD` to the dense `n × n` matrix `a`.
pub(crate) fn add_penalty(a: &mut [f64], n: usize, lambda: f64, rows: &[([usize; 3], [f64; 3])]) {
    for (idx, w) in rows {
        for r in 0..3 {
            for c in 0..3 {
                a[idx[r] * n + idx[c]] += lambda * w[r] * w[c];
            }
        }
    }
}

/// `trace(DᵀD)`: the sum of squared weights.
pub(crate) fn penalty_trace(rows: &[([usize; 3], [f64; 3])]) -> f64 {
    rows.iter()
        .map(|(_, w)| w.iter().map(|x| x * x).sum::<f64>())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_banded_and_full() {
        // SPD tridiagonal-ish 6x6.
        let n = 6;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i * n + i] = 4.0;
            if i + 1 < n {
                a[i * n + i + 1] = 1.0;
                a[(i + 1) * n + i] = 1.0;
            }
        }
        let x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(i as f64, 1.0 - i as f64, 0.5 * i as f64))
            .collect();
        let b: Vec<DVec3> = (0..n)
            .map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum())
            .collect();
        for bw in [1, 3, n - 1] {
            let mut m = a.clone();
            let mut r = b.clone();
            cholesky_solve(&mut m, n, bw, &mut r).unwrap();
            for i in 0..n {
                assert!((r[i] - x[i]).length() < 1e-12);
            }
        }
        let mut sing = vec![0.0; 4];
        let mut r = vec![DVec3::ONE; 2];
        assert!(matches!(
            cholesky_solve(&mut sing, 2, 1, &mut r),
            Err(BSplineError::Singular { pivot: 0 })
        ));
    }
}
