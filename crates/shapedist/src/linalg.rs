//! Small dense linear algebra: symmetric eigen-solvers (cyclic Jacobi), a robust 3x3 SVD,
//! and the two closed-form rotation fits (Kabsch with the reflection guard, Horn's quaternions).
//!
//! glam has no SVD or eigen-solver; these are tiny, allocation-free and accurate to a few ulps
//! relative to the matrix norm.

#![allow(clippy::needless_range_loop)] // index loops read best in small dense linear algebra

use glam::{DMat3, DQuat, DVec3};

/// Eigen-decomposition of a symmetric `N x N` matrix by cyclic Jacobi rotations.
///
/// Returns the eigenvalues in descending order and the matching unit eigenvectors as the
/// columns of the second result (`vecs[row][col]`). Only the upper triangle needs to be
/// meaningful; the input is symmetrised first. Non-finite input yields non-finite output.
pub fn sym_eigen<const N: usize>(m: [[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
    let mut a = m;
    for p in 0..N {
        for q in (p + 1)..N {
            let s = 0.5 * (a[p][q] + a[q][p]);
            a[p][q] = s;
            a[q][p] = s;
        }
    }
    let mut v = [[0.0; N]; N];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let fro2: f64 = a.iter().flatten().map(|x| x * x).sum();
    if fro2 == 0.0 || !fro2.is_finite() {
        return finish(a, v);
    }
    for _sweep in 0..64 {
        let mut off = 0.0;
        for p in 0..N {
            for q in (p + 1)..N {
                off += a[p][q] * a[p][q];
            }
        }
        // Converged when the off-diagonal mass is at the rounding level of the matrix.
        if off <= fro2 * 1e-34 {
            break;
        }
        for p in 0..N {
            for q in (p + 1)..N {
                let apq = a[p][q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                let t = if theta.abs() > 1e150 {
                    0.5 / theta
                } else {
                    theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                for k in 0..N {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                a[p][q] = 0.0;
                a[q][p] = 0.0;
                for row in v.iter_mut() {
                    let (vkp, vkq) = (row[p], row[q]);
                    row[p] = c * vkp - s * vkq;
                    row[q] = s * vkp + c * vkq;
                }
            }
        }
    }
    finish(a, v)
}

fn finish<const N: usize>(a: [[f64; N]; N], v: [[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
    let mut order: [usize; N] = std::array::from_fn(|i| i);
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let vals = std::array::from_fn(|k| a[order[k]][order[k]]);
    let mut vecs = [[0.0; N]; N];
    for (k, &o) in order.iter().enumerate() {
        for r in 0..N {
            vecs[r][k] = v[r][o];
        }
    }
    (vals, vecs)
}

fn mat3_to_rows(m: DMat3) -> [[f64; 3]; 3] {
    let r = m.transpose();
    [
        r.x_axis.to_array(),
        r.y_axis.to_array(),
        r.z_axis.to_array(),
    ]
}

/// Eigen-decomposition of a symmetric 3x3 matrix: eigenvalues descending and the unit
/// eigenvectors (same order).
pub fn sym_eigen3(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let (vals, v) = sym_eigen::<3>(mat3_to_rows(m));
    let col = |k: usize| DVec3::new(v[0][k], v[1][k], v[2][k]);
    (vals, [col(0), col(1), col(2)])
}

/// Singular value decomposition `K = U diag(s) V^T` of a 3x3 matrix with `U` and `V` proper
/// rotations (determinant +1).
///
/// `s[0] >= s[1] >= |s[2]|`; the sign of `det K` is carried by `s[2]` (which is negative
/// when `K` is a reflection-like matrix). With `U` and `V` proper, `U V^T` is the rotation
/// maximising `tr(R^T K)` (the Kabsch solution, reflection guard included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Svd3 {
    /// Left factor (columns `u_i`), a rotation.
    pub u: DMat3,
    /// Singular values; the last one is signed.
    pub s: [f64; 3],
    /// Right factor (columns `v_i`), a rotation.
    pub v: DMat3,
}

/// Computes [`Svd3`] of `k` through the eigen-decomposition of `k^T k` (Jacobi) and
/// Gram-Schmidt on `k v_i`.
///
/// Robust for rank 2 and rank 1 (for rank < 2 the factors are still rotations but not unique).
pub fn svd3(k: DMat3) -> Svd3 {
    let (_, vs) = sym_eigen3(k.transpose() * k);
    let mut v1 = vs[0];
    let mut v2 = vs[1];
    let scale = k.to_cols_array().iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let tiny = scale * 1e-300_f64.max(f64::EPSILON * 1e-3);
    let kv1 = k * v1;
    let n1 = kv1.length();
    let u1 = if n1 > tiny { kv1 / n1 } else { DVec3::X };
    if n1 <= tiny {
        v1 = DVec3::X;
        v2 = DVec3::Y;
    }
    let kv2 = k * v2;
    let w = kv2 - u1 * u1.dot(kv2);
    let n2 = w.length();
    let u2 = if n2 > tiny * 1e3 {
        w / n2
    } else {
        u1.any_orthonormal_vector()
    };
    let u3 = u1.cross(u2);
    let v3 = v1.cross(v2);
    let s1 = u1.dot(kv1);
    let s2 = u2.dot(kv2);
    let s3 = u3.dot(k * v3);
    Svd3 {
        u: DMat3::from_cols(u1, u2, u3),
        s: [s1, s2, s3],
        v: DMat3::from_cols(v1, v2, v3),
    }
}

/// The rotation `R` maximising `tr(R^T K)` by the SVD (Kabsch with the reflection guard),
/// together with the maximum `s1 + s2 + s3` (signed `s3`).
pub fn kabsch_rotation(k: DMat3) -> (DMat3, f64) {
    let svd = svd3(k);
    let r = svd.u * svd.v.transpose();
    (orthonormalise(r), svd.s[0] + svd.s[1] + svd.s[2])
}

/// The rotation `R` maximising `tr(R^T K)` by Horn's unit-quaternion method (largest
/// eigenvector of a symmetric 4x4 matrix), with the maximum value (the largest eigenvalue).
///
/// `K = sum_i w_i a_i b_i^T` for the problem `min sum w_i |a_i - R b_i|^2`.
pub fn horn_rotation(k: DMat3) -> (DMat3, f64) {
    // Horn's S is sum b a^T = K^T, S_xy = sum b_x a_y.
    let s = mat3_to_rows(k.transpose());
    let (sxx, sxy, sxz) = (s[0][0], s[0][1], s[0][2]);
    let (syx, syy, syz) = (s[1][0], s[1][1], s[1][2]);
    let (szx, szy, szz) = (s[2][0], s[2][1], s[2][2]);
    let n = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (vals, vecs) = sym_eigen::<4>(n);
    let q = DQuat::from_xyzw(vecs[1][0], vecs[2][0], vecs[3][0], vecs[0][0]);
    let q = if q.length_squared() > 0.0 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    };
    (DMat3::from_quat(q), vals[0])
}

/// Projects an almost-orthonormal matrix back onto SO(3) (one Newton step of the polar
/// decomposition, enough after the closed forms above).
pub fn orthonormalise(r: DMat3) -> DMat3 {
    let inv_t = r.inverse().transpose();
    if !inv_t.is_finite() {
        return r;
    }
    (r + inv_t) * 0.5
}

/// Geodesic angle (radians) between two rotations.
pub fn rotation_angle_between(a: DMat3, b: DMat3) -> f64 {
    let m = a.transpose() * b;
    let tr = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    // acos is ill-conditioned near 0; use atan2 of |skew| and trace.
    let skew = DVec3::new(
        m.y_axis.z - m.z_axis.y,
        m.z_axis.x - m.x_axis.z,
        m.x_axis.y - m.y_axis.x,
    );
    (0.5 * skew.length()).atan2(0.5 * (tr - 1.0))
}

/// Rotation by `angle` radians about `axis` (normalised here; zero axis gives the identity).
pub fn axis_angle(axis: DVec3, angle: f64) -> DMat3 {
    let n = axis.length();
    if n == 0.0 || !n.is_finite() {
        return DMat3::IDENTITY;
    }
    DMat3::from_axis_angle(axis / n, angle)
}

/// Solves the symmetric positive (semi-)definite system `A x = b` (size `N`) by Gaussian
/// elimination with partial pivoting; returns `None` when singular.
pub fn solve_sym<const N: usize>(a: [[f64; N]; N], b: [f64; N]) -> Option<[f64; N]> {
    let mut m = a;
    let mut r = b;
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return None;
    }
    for c in 0..N {
        let piv = (c..N).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if m[piv][c].abs() <= scale * 1e-14 {
            return None;
        }
        m.swap(c, piv);
        r.swap(c, piv);
        for i in (c + 1)..N {
            let f = m[i][c] / m[c][c];
            for j in c..N {
                m[i][j] -= f * m[c][j];
            }
            r[i] -= f * r[c];
        }
    }
    let mut x = [0.0; N];
    for i in (0..N).rev() {
        let mut acc = r[i];
        for j in (i + 1)..N {
            acc -= m[i][j] * x[j];
        }
        x[i] = acc / m[i][i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot(ax: DVec3, ang: f64) -> DMat3 {
        axis_angle(ax, ang)
    }

    #[test]
    fn jacobi_reconstructs_a_symmetric_4x4() {
        let m = [
            [4.0, 1.0, -2.0, 0.5],
            [1.0, 3.0, 0.0, 1.5],
            [-2.0, 0.0, -1.0, 2.0],
            [0.5, 1.5, 2.0, 0.25],
        ];
        let (vals, v) = sym_eigen::<4>(m);
        assert!(vals.windows(2).all(|w| w[0] >= w[1]));
        for i in 0..4 {
            for j in 0..4 {
                let rec: f64 = (0..4).map(|k| v[i][k] * vals[k] * v[j][k]).sum();
                assert!((rec - m[i][j]).abs() < 1e-13, "{i} {j} {rec} {}", m[i][j]);
                let orth: f64 = (0..4).map(|k| v[k][i] * v[k][j]).sum();
                assert!((orth - f64::from(u8::from(i == j))).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn svd3_reconstructs_including_reflections_and_rank_deficiency() {
        let mats = [
            DMat3::from_cols_array(&[2.0, 0.3, -1.0, 0.1, 1.5, 0.7, -0.4, 0.2, 0.9]),
            // det < 0
            DMat3::from_cols_array(&[2.0, 0.3, -1.0, 0.1, 1.5, 0.7, 0.4, -0.2, -0.9]),
            // rank 2
            DMat3::from_cols(
                DVec3::new(1.0, 2.0, 3.0),
                DVec3::new(-1.0, 0.5, 2.0),
                DVec3::new(0.0, 2.5, 5.0),
            ),
            // rank 1
            DMat3::from_cols(
                DVec3::new(1.0, 2.0, 3.0),
                DVec3::new(2.0, 4.0, 6.0),
                DVec3::new(-1.0, -2.0, -3.0),
            ),
            DMat3::ZERO,
        ];
        for k in mats {
            let s = svd3(k);
            let rec = s.u * DMat3::from_diagonal(DVec3::from_array(s.s)) * s.v.transpose();
            assert!(rec.abs_diff_eq(k, 1e-12), "{k:?} -> {rec:?}");
            assert!((s.u.determinant() - 1.0).abs() < 1e-12);
            assert!((s.v.determinant() - 1.0).abs() < 1e-12);
            assert!(s.s[0] >= s.s[1] - 1e-12 && s.s[1] >= s.s[2].abs() - 1e-12);
        }
    }

    #[test]
    fn kabsch_and_horn_agree_and_recover_rotations() {
        let pts = [
            DVec3::new(1.0, 0.2, -0.3),
            DVec3::new(-0.5, 1.1, 0.4),
            DVec3::new(0.3, -0.8, 0.9),
            DVec3::new(-0.8, -0.5, -1.0),
        ];
        for (ax, ang) in [
            (DVec3::new(1.0, 2.0, 3.0), 0.3),
            (DVec3::new(-1.0, 0.0, 0.5), 2.0),
            (DVec3::new(0.0, 0.0, 1.0), std::f64::consts::PI),
            (DVec3::new(0.3, -0.7, 0.2), 3.1),
        ] {
            let r = rot(ax, ang);
            // K = sum a b^T with a = R b.
            let k = pts
                .iter()
                .fold(DMat3::ZERO, |acc, &b| acc + outer(r * b, b));
            let (rk, _) = kabsch_rotation(k);
            let (rh, _) = horn_rotation(k);
            assert!(rotation_angle_between(rk, r) < 1e-12);
            assert!(rotation_angle_between(rh, r) < 1e-12);
            assert!((rk.determinant() - 1.0).abs() < 1e-13);
        }
    }

    fn outer(a: DVec3, b: DVec3) -> DMat3 {
        DMat3::from_cols(a * b.x, a * b.y, a * b.z)
    }

    #[test]
    fn solve_sym_solves_and_detects_singular() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = [1.0, -2.0, 0.5];
        let b: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum());
        let y = solve_sym(a, b).unwrap();
        for i in 0..3 {
            assert!((y[i] - x[i]).abs() < 1e-14);
        }
        assert!(solve_sym([[1.0, 1.0], [1.0, 1.0]], [1.0, 2.0]).is_none());
    }
}
