//! Data parameters, input checks and the averaged clamped knot vector.

use crate::{BSplineError, Parametrization, DEGREE};
use glam::DVec3;

/// Removes consecutive points closer than `tol` to the previously kept point (and, when
/// `closed`, a last point within `tol` of the first). Returns the kept points and, for each
/// kept point, its index in the input.
pub fn dedup_consecutive(points: &[DVec3], tol: f64, closed: bool) -> (Vec<DVec3>, Vec<usize>) {
    let mut out: Vec<DVec3> = Vec::with_capacity(points.len());
    let mut idx = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        if let Some(&q) = out.last() {
            if p.distance(q) <= tol {
                continue;
            }
        }
        out.push(p);
        idx.push(i);
    }
    if closed {
        while out.len() > 1 && out[out.len() - 1].distance(out[0]) <= tol {
            out.pop();
            idx.pop();
        }
    }
    (out, idx)
}

/// Data parameters of a polyline (chord length or centripetal), normalised to `[0, 1]` for open
/// curves, `[0, 1)` for closed ones (closing chord included).
pub fn data_params(
    points: &[DVec3],
    closed: bool,
    parametrization: Parametrization,
) -> Result<Vec<f64>, BSplineError> {
    check_points(points, closed, 2)?;
    let e = parametrization.exponent();
    let n = points.len();
    let mut acc = Vec::with_capacity(n);
    let mut s = 0.0;
    acc.push(0.0);
    for k in 1..n {
        s += chord(points[k - 1], points[k]).powf(e);
        acc.push(s);
    }
    let total = if closed {
        s + chord(points[n - 1], points[0]).powf(e)
    } else {
        s
    };
    if total.is_nan() || total <= 0.0 {
        return Err(BSplineError::CoincidentPoints { index: 1, prev: 0 });
    }
    for a in acc.iter_mut() {
        *a /= total;
    }
    if !closed {
        acc[n - 1] = 1.0;
    }
    Ok(acc)
}

fn chord(a: DVec3, b: DVec3) -> f64 {
    a.distance(b)
}

pub(crate) fn check_points(
    points: &[DVec3],
    closed: bool,
    need: usize,
) -> Result<(), BSplineError> {
    if points.len() < need {
        return Err(BSplineError::TooFewPoints {
            got: points.len(),
            need,
        });
    }
    for (i, p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(BSplineError::NonFinite {
                index: i,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
    }
    // Scale-relative coincidence test.
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let tol = 1e-14 * (hi - lo).length().max(f64::MIN_POSITIVE);
    for i in 1..points.len() {
        if points[i].distance(points[i - 1]) <= tol {
            return Err(BSplineError::CoincidentPoints {
                index: i,
                prev: i - 1,
            });
        }
    }
    if closed && points[0].distance(points[points.len() - 1]) <= tol {
        return Err(BSplineError::CoincidentPoints {
            index: 0,
            prev: points.len() - 1,
        });
    }
    Ok(())
}

/// Clamped knot vector by averaging (algorithms.md §3.3): `n+1 = nc` control points, `m+1` data
/// parameters.
pub(crate) fn averaged_knots(params: &[f64], nc: usize) -> Vec<f64> {
    let p = DEGREE;
    let n = nc - 1;
    let m = params.len() - 1;
    let mut knots = vec![0.0; nc + p + 1];
    let (lo, hi) = (params[0].min(0.0), params[m].max(1.0));
    for k in knots.iter_mut().take(p + 1) {
        *k = lo;
    }
    for k in knots.iter_mut().skip(n + 1) {
        *k = hi;
    }
    let d = (m + 1) as f64 / (n - p + 1) as f64;
    for j in 1..=(n - p) {
        let jd = j as f64 * d;
        let i = (jd.floor() as usize).clamp(1, m);
        let alpha = jd - i as f64;
        knots[p + j] = (1.0 - alpha) * params[i - 1] + alpha * params[i];
    }
    knots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knots_are_clamped_and_nondecreasing() {
        let params: Vec<f64> = (0..30).map(|i| i as f64 / 29.0).collect();
        for nc in 4..=30 {
            let k = averaged_knots(&params, nc);
            assert_eq!(k.len(), nc + 4);
            assert!(k[..4].iter().all(|&x| x == 0.0));
            assert!(k[nc..].iter().all(|&x| x == 1.0));
            assert!(k.windows(2).all(|w| w[0] <= w[1]), "{k:?}");
            // Every span contains a data parameter (Schoenberg-Whitney).
            for s in 3..nc {
                if k[s + 1] > k[s] {
                    assert!(params.iter().any(|&u| u >= k[s] && u <= k[s + 1]));
                }
            }
        }
    }
}
