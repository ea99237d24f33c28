//! Small dense linear algebra: 3x3 symmetric eigen-decomposition and the Kabsch residual.

use glam::DVec3;

/// Eigenvalues (descending) and unit eigenvectors of a symmetric 3x3 matrix (cyclic Jacobi).
pub fn sym_eigen3(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m;
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-15 * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A <- J^T A J with the rotation in the (p, q) plane.
            for k in 0..3 {
                let akp = a[k][p];
                let akq = a[k][q];
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[p][k];
                let aqk = a[q][k];
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&x, &y| a[y][y].total_cmp(&a[x][x]));
    let vals = idx.map(|i| a[i][i]);
    let vecs = idx.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]).normalize_or_zero());
    (vals, vecs)
}

/// Normalised keyed L2 shape distance `min_R ||A - R B|| / sqrt(||A||^2 + ||B||^2)` over
/// rotations `R` (reflections excluded), after centring both sets; rows are paired.
///
/// Returns `None` for fewer than 3 pairs, mismatched lengths or two zero-size sets.
pub fn kabsch_distance(a: &[DVec3], b: &[DVec3]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 3 {
        return None;
    }
    let ca = a.iter().copied().sum::<DVec3>() / a.len() as f64;
    let cb = b.iter().copied().sum::<DVec3>() / b.len() as f64;
    let mut h = [[0.0; 3]; 3];
    let (mut na, mut nb) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (x, y) = (*p - ca, *q - cb);
        na += x.length_squared();
        nb += y.length_squared();
        for r in 0..3 {
            for s in 0..3 {
                h[r][s] += y[r] * x[s];
            }
        }
    }
    if na + nb <= 0.0 {
        return None;
    }
    // Singular values of H from the eigenvalues of H^T H; the sign of det H decides the
    // reflection guard.
    let mut hth = [[0.0; 3]; 3];
    for r in 0..3 {
        for s in 0..3 {
            hth[r][s] = (0..3).map(|k| h[k][r] * h[k][s]).sum();
        }
    }
    let (ev, _) = sym_eigen3(hth);
    let sv = ev.map(|e| e.max(0.0).sqrt());
    let det = h[0][0] * (h[1][1] * h[2][2] - h[1][2] * h[2][1])
        - h[0][1] * (h[1][0] * h[2][2] - h[1][2] * h[2][0])
        + h[0][2] * (h[1][0] * h[2][1] - h[1][1] * h[2][0]);
    let tr = sv[0] + sv[1] + if det < 0.0 { -sv[2] } else { sv[2] };
    let d2 = (na + nb - 2.0 * tr).max(0.0);
    Some((d2 / (na + nb)).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_reconstructs() {
        let m = [[4.0, 1.0, -2.0], [1.0, 2.0, 0.5], [-2.0, 0.5, 3.0]];
        let (vals, vecs) = sym_eigen3(m);
        assert!(vals[0] >= vals[1] && vals[1] >= vals[2]);
        for k in 0..3 {
            let v = vecs[k];
            let mv = DVec3::new(
                m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
            );
            assert!((mv - vals[k] * v).length() < 1e-12);
        }
    }

    #[test]
    fn kabsch_zero_for_rotated_copy_positive_for_mirror() {
        let a: Vec<DVec3> = (0..20)
            .map(|i| {
                let t = i as f64;
                DVec3::new(t.sin() * 3.0, (t * 0.7).cos(), (t * 1.3).sin() + 0.1 * t)
            })
            .collect();
        let q = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 1.1);
        let b: Vec<DVec3> = a
            .iter()
            .map(|p| q * *p + DVec3::new(5.0, -1.0, 2.0))
            .collect();
        assert!(kabsch_distance(&a, &b).unwrap() < 1e-7);
        let m: Vec<DVec3> = a.iter().map(|p| DVec3::new(-p.x, p.y, p.z)).collect();
        assert!(kabsch_distance(&a, &m).unwrap() > 1e-2);
        assert!(kabsch_distance(&a[..2], &b[..2]).is_none());
    }
}
