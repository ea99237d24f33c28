//! Cubic B-spline basis functions: clamped (knot vector) and uniform periodic.

use crate::DEGREE;

/// Non-zero basis functions and their first two derivatives at `u` in knot span `span`
/// (NURBS Book A2.3, p = 3, n = 2). Returns `[values, first, second]`, each for basis
/// `span-3 ..= span`.
pub(crate) fn ders_basis(knots: &[f64], span: usize, u: f64) -> [[f64; 4]; 3] {
    const P: usize = DEGREE;
    let mut ndu = [[0.0f64; P + 1]; P + 1];
    let mut left = [0.0f64; P + 1];
    let mut right = [0.0f64; P + 1];
    ndu[0][0] = 1.0;
    for j in 1..=P {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = if ndu[j][r] != 0.0 {
                ndu[r][j - 1] / ndu[j][r]
            } else {
                0.0
            };
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    let mut ders = [[0.0f64; P + 1]; 3];
    for j in 0..=P {
        ders[0][j] = ndu[j][P];
    }
    let mut a = [[0.0f64; P + 1]; 2];
    for r in 0..=P {
        let (mut s1, mut s2) = (0usize, 1usize);
        a[0][0] = 1.0;
        for k in 1..=2usize {
            let mut d = 0.0;
            let rk = r as isize - k as isize;
            let pk = P - k;
            if r >= k {
                let rk = rk as usize;
                let den = ndu[pk + 1][rk];
                a[s2][0] = if den != 0.0 { a[s1][0] / den } else { 0.0 };
                d = a[s2][0] * ndu[rk][pk];
            }
            let j1: usize = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2: usize = if (r as isize - 1) <= pk as isize {
                k - 1
            } else {
                P - r
            };
            for j in j1..=j2 {
                let col = (rk + j as isize) as usize;
                let den = ndu[pk + 1][col];
                a[s2][j] = if den != 0.0 {
                    (a[s1][j] - a[s1][j - 1]) / den
                } else {
                    0.0
                };
                d += a[s2][j] * ndu[col][pk];
            }
            if r as isize <= pk as isize {
                let col = r;
                let den = ndu[pk + 1][col];
                a[s2][k] = if den != 0.0 { -a[s1][k - 1] / den } else { 0.0 };
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut fac = P as f64;
    for (k, row) in ders.iter_mut().enumerate().skip(1) {
        for v in row.iter_mut() {
            *v *= fac;
        }
        fac *= (P - k) as f64;
    }
    ders
}

/// Knot span index for `u` on a clamped knot vector with `n_ctrl` control points (A2.1); at the
/// right end returns the last non-empty span.
pub(crate) fn find_span(knots: &[f64], n_ctrl: usize, u: f64) -> usize {
    let n = n_ctrl - 1;
    if u >= knots[n + 1] {
        return n;
    }
    if u <= knots[DEGREE] {
        return DEGREE;
    }
    // Largest i in [p, n] with knots[i] <= u.
    let (mut lo, mut hi) = (DEGREE, n + 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if u < knots[mid] {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

/// Uniform periodic cubic basis at local parameter t ∈ [0,1): values, first and second
/// derivatives with respect to t.
pub(crate) fn periodic_basis(t: f64) -> [[f64; 4]; 3] {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    [
        [
            s * s * s / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ],
        [
            -s * s / 2.0,
            (3.0 * t2 - 4.0 * t) / 2.0,
            (-3.0 * t2 + 2.0 * t + 1.0) / 2.0,
            t2 / 2.0,
        ],
        [s, 3.0 * t - 2.0, -3.0 * t + 1.0, t],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::averaged_knots;

    #[test]
    fn partition_of_unity_open_and_closed() {
        let params: Vec<f64> = (0..20).map(|i| (i as f64 / 19.0).powf(1.3)).collect();
        let knots = averaged_knots(&params, 9);
        for i in 0..=200 {
            let u = i as f64 / 200.0;
            let span = find_span(&knots, 9, u);
            let b = ders_basis(&knots, span, u);
            assert!((b[0].iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(b[1].iter().sum::<f64>().abs() < 1e-9);
            assert!(b[2].iter().sum::<f64>().abs() < 1e-7);
            let pb = periodic_basis(u);
            assert!((pb[0].iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(pb[1].iter().sum::<f64>().abs() < 1e-12);
            assert!(pb[2].iter().sum::<f64>().abs() < 1e-12);
        }
    }
}
