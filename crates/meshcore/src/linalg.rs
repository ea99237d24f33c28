//! Small dense linear algebra shared by the workspace: symmetric eigen-solvers (cyclic
//! Jacobi), a robust 3x3 SVD, the two closed-form rotation fits (Kabsch with the reflection
//! guard, Horn's quaternions), the one weighted rigid fit of paired points ([`fit_rigid`]),
//! and a small dense solver.
//!
//! glam has no SVD or eigen-solver; these are tiny, allocation-free and accurate to a few ulps
//! relative to the matrix norm. Rigid motions are [`glam::DAffine3`] with an orthonormal
//! `matrix3`.

#![allow(clippy::needless_range_loop)] // index loops read best in small dense linear algebra

use glam::{DAffine3, DMat3, DQuat, DVec3};

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
/// elimination with partial pivoting; returns `None` when singular (a pivot at most
/// `1e-14` times the largest entry). See [`solve_sym_tol`].
pub fn solve_sym<const N: usize>(a: [[f64; N]; N], b: [f64; N]) -> Option<[f64; N]> {
    solve_sym_tol(a, b, 1e-14)
}

/// [`solve_sym`] with the singularity threshold `rel_pivot`: `None` when a pivot is at most
/// `rel_pivot` times the largest absolute entry of `A` (for a positive semi-definite `A`, the
/// largest diagonal entry), or when `A` is zero or not finite.
pub fn solve_sym_tol<const N: usize>(
    a: [[f64; N]; N],
    b: [f64; N],
    rel_pivot: f64,
) -> Option<[f64; N]> {
    let mut m = a;
    let mut r = b;
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return None;
    }
    for c in 0..N {
        let piv = (c..N).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if m[piv][c].abs() <= scale * rel_pivot {
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

/// The inverse of a rigid motion (`matrix3` orthonormal): `x -> R^T (x - t)`, with the
/// transpose instead of a general inverse.
pub fn rigid_inverse(m: &DAffine3) -> DAffine3 {
    let rt = m.matrix3.transpose();
    DAffine3::from_mat3_translation(rt, -(rt * m.translation))
}

/// Least-squares rigid motion `x -> R x + t` (proper rotation, `det R = +1`) mapping `src[i]`
/// onto `dst[i]`, minimising `sum w_i |R src_i + t - dst_i|^2`: the weighted centroids are
/// matched and `R` is the Kabsch rotation of the centred cross-covariance
/// `K = sum w_i (dst_i - c_dst)(src_i - c_src)^T` ([`kabsch_rotation`], reflection guard
/// included, so a mirror image is never returned).
///
/// `None` when the slices are empty or of different lengths, when `weights` has another
/// length, a negative or non-finite weight or a zero total, or when the input is not finite.
/// With fewer than three non-collinear points the rotation is not unique; one of the optimal
/// rotations is returned.
pub fn fit_rigid(src: &[DVec3], dst: &[DVec3], weights: Option<&[f64]>) -> Option<DAffine3> {
    let n = src.len();
    if n == 0 || dst.len() != n || weights.is_some_and(|w| w.len() != n) {
        return None;
    }
    if weights.is_some_and(|w| w.iter().any(|x| !(x.is_finite() && *x >= 0.0))) {
        return None;
    }
    let wt = |i: usize| weights.map_or(1.0, |w| w[i]);
    let sw: f64 = (0..n).map(wt).sum();
    if !(sw > 0.0 && sw.is_finite()) {
        return None;
    }
    let cs = (0..n).map(|i| src[i] * wt(i)).sum::<DVec3>() / sw;
    let cd = (0..n).map(|i| dst[i] * wt(i)).sum::<DVec3>() / sw;
    let k = (0..n).fold(DMat3::ZERO, |k, i| {
        let (a, b) = ((dst[i] - cd) * wt(i), src[i] - cs);
        k + DMat3::from_cols(a * b.x, a * b.y, a * b.z)
    });
    if !k.is_finite() || !cs.is_finite() || !cd.is_finite() {
        return None;
    }
    let (r, _) = kabsch_rotation(k);
    r.is_finite()
        .then(|| DAffine3::from_mat3_translation(r, cd - r * cs))
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

    #[test]
    fn rigid_inverse_undoes_the_motion() {
        let m = DAffine3::from_mat3_translation(
            rot(DVec3::new(0.2, -1.0, 0.4), 2.2),
            DVec3::new(3.0, -1.0, 0.5),
        );
        let p = DVec3::new(0.3, 0.7, -2.0);
        let back = rigid_inverse(&m).transform_point3(m.transform_point3(p));
        assert!((back - p).length() < 1e-14);
    }

    #[test]
    fn fit_rigid_rejects_bad_input() {
        let p = [DVec3::X, DVec3::Y, DVec3::Z];
        assert!(fit_rigid(&[], &[], None).is_none());
        assert!(fit_rigid(&p, &p[..2], None).is_none());
        assert!(fit_rigid(&p, &p, Some(&[1.0, 1.0])).is_none());
        assert!(fit_rigid(&p, &p, Some(&[1.0, -1.0, 1.0])).is_none());
        assert!(fit_rigid(&p, &p, Some(&[0.0, 0.0, 0.0])).is_none());
        assert!(fit_rigid(&p, &[DVec3::X, DVec3::Y, DVec3::NAN], None).is_none());
    }

    mod props {
        use super::super::*;
        use proptest::prelude::*;

        fn vec3() -> impl Strategy<Value = DVec3> {
            (-10.0..10.0f64, -10.0..10.0f64, -10.0..10.0f64)
                .prop_map(|(x, y, z)| DVec3::new(x, y, z))
        }

        fn motion() -> impl Strategy<Value = DAffine3> {
            (vec3(), 0.0..std::f64::consts::PI, vec3()).prop_filter_map("axis", |(ax, ang, t)| {
                (ax.length() > 1e-3)
                    .then(|| DAffine3::from_mat3_translation(axis_angle(ax, ang), t * 10.0))
            })
        }

        /// Points spread in 3D (a tetrahedron plus random points).
        fn cloud() -> impl Strategy<Value = Vec<DVec3>> {
            proptest::collection::vec(vec3(), 0..20).prop_map(|mut v| {
                v.extend([
                    DVec3::new(4.0, 0.0, 0.0),
                    DVec3::new(0.0, 5.0, 0.0),
                    DVec3::new(0.0, 0.0, 6.0),
                    DVec3::new(-3.0, -3.0, -3.0),
                ]);
                v
            })
        }

        fn close(a: &DAffine3, b: &DAffine3, tol: f64) -> bool {
            rotation_angle_between(a.matrix3, b.matrix3) < tol
                && (a.translation - b.translation).length() < tol * (1.0 + b.translation.length())
        }

        proptest! {
            #[test]
            fn fit_rigid_recovers_a_random_motion(m in motion(), pts in cloud()) {
                let dst: Vec<DVec3> = pts.iter().map(|p| m.transform_point3(*p)).collect();
                let f = fit_rigid(&pts, &dst, None).unwrap();
                prop_assert!(close(&f, &m, 1e-9), "{f:?} vs {m:?}");
                prop_assert!((f.matrix3.determinant() - 1.0).abs() < 1e-12);
            }

            #[test]
            fn fit_rigid_never_returns_a_reflection(pts in cloud(), axis in 0usize..3) {
                // The mirror image of a cloud has no proper rigid fit; the result must still
                // be a rotation.
                let mut flip = DVec3::ONE;
                flip[axis] = -1.0;
                let dst: Vec<DVec3> = pts.iter().map(|p| *p * flip).collect();
                let f = fit_rigid(&pts, &dst, None).unwrap();
                prop_assert!((f.matrix3.determinant() - 1.0).abs() < 1e-12);
                let rtr = f.matrix3.transpose() * f.matrix3;
                prop_assert!(rtr.abs_diff_eq(DMat3::IDENTITY, 1e-12));
            }

            #[test]
            fn fit_rigid_weights_select_the_pairs(
                m in motion(),
                other in motion(),
                pts in cloud(),
                w in proptest::collection::vec(0.1..3.0f64, 24),
            ) {
                // Inliers follow `m`, outliers (weight 0) follow `other`: the weighted fit is
                // `m`; scaling all weights changes nothing.
                let n_in = 4.min(pts.len());
                let k = pts.len() - n_in;
                let dst: Vec<DVec3> = pts
                    .iter()
                    .enumerate()
                    .map(|(i, p)| if i < k { other.transform_point3(*p) } else { m.transform_point3(*p) })
                    .collect();
                let wts: Vec<f64> = (0..pts.len()).map(|i| if i < k { 0.0 } else { w[i] }).collect();
                let f = fit_rigid(&pts, &dst, Some(&wts)).unwrap();
                prop_assert!(close(&f, &m, 1e-8), "{f:?} vs {m:?}");
                let w2: Vec<f64> = wts.iter().map(|x| x * 4.0).collect();
                let g = fit_rigid(&pts, &dst, Some(&w2)).unwrap();
                prop_assert!(close(&f, &g, 1e-12));
            }
        }
    }
}
