//! The independent implementation of the bipolar grid descriptor and the keyed distance, kept
//! as a test oracle (not used by any experiment): `crates/bipolar/tests/oracle.rs` checks that
//! `bipolar`'s `SelectionRule::All` descriptor equals [`bipolar_grid`] on faces of the paper
//! set, and the shape-distance tests can compare `shapedist::keyed_distance` with
//! [`keyed_distance`].
//!
//! The descriptor is the grid reading of the paper (selection rule A without angle filter:
//! every intersection of level `i` of `U_r` with level `j` of `U_q`, key `(i, j, side)`, one
//! 2x2 solve per face), and the distance is the keyed L2 distance after the optimal rotation
//! (the singular values of the correlation matrix in closed form: no Horn or Kabsch
//! solver), normalised to [0, 1]:
//! `d = sqrt((|A|^2 + |B|^2 - 2 max_R sum a.Rb) / (|A|^2 + |B|^2))` on centred paired points.
//! Written apart from the crates on purpose: it shares no code with `bipolar`, `levelcurves`
//! or `shapedist`.

use meshcore::{DVec3, TriMesh};

/// A descriptor: points with keys (sorted by key), and which keys are ambiguous.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyedPoints {
    /// Packed keys, ascending.
    pub keys: Vec<u64>,
    /// Positions.
    pub points: Vec<DVec3>,
    /// True where a key occurs at several distinct places (such keys are not paired).
    pub ambiguous: Vec<bool>,
}

impl KeyedPoints {
    /// Builds a keyed set from unsorted `(key, point)` pairs: duplicates of a key closer than
    /// `tol` are merged (points found from two faces), farther ones make the key ambiguous.
    pub fn from_pairs(mut pairs: Vec<(u64, DVec3)>, tol: f64) -> Self {
        pairs.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(a.1.x.total_cmp(&b.1.x))
                .then(a.1.y.total_cmp(&b.1.y))
                .then(a.1.z.total_cmp(&b.1.z))
        });
        let mut out = KeyedPoints::default();
        let mut i = 0;
        while i < pairs.len() {
            let mut j = i + 1;
            while j < pairs.len() && pairs[j].0 == pairs[i].0 {
                j += 1;
            }
            let first = pairs[i].1;
            let ambiguous = pairs[i..j].iter().any(|p| (p.1 - first).length() > tol);
            out.keys.push(pairs[i].0);
            out.points.push(first);
            out.ambiguous.push(ambiguous);
            i = j;
        }
        out
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// True if there is no point.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// Unambiguous keys and points (for distances).
    pub fn unambiguous(&self) -> (Vec<u64>, Vec<DVec3>) {
        let mut k = Vec::new();
        let mut p = Vec::new();
        for i in 0..self.len() {
            if !self.ambiguous[i] {
                k.push(self.keys[i]);
                p.push(self.points[i]);
            }
        }
        (k, p)
    }
}

/// Packs a grid key `(i, j, side)`.
pub fn grid_key(i: u32, j: u32, side: bool) -> u64 {
    (u64::from(i) << 33) | (u64::from(j) << 1) | u64::from(side)
}

/// Unpacks a grid key.
pub fn grid_key_parts(k: u64) -> (u32, u32, bool) {
    (
        (k >> 33) as u32,
        ((k >> 1) & 0xffff_ffff) as u32,
        k & 1 == 1,
    )
}

/// Options of [`bipolar_grid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridOptions {
    /// Geodesic step between levels (`D / N` for N levels between the references).
    pub step: f64,
    /// Largest level index kept, for both fields (`M`; `M = N` keeps points within D of both).
    pub max_level: u32,
}

/// Intersections of the level curves `U_r = i*step` and `U_q = j*step` (1 <= i, j <= M), one
/// 2x2 solve per face and level pair, keyed `(i, j, side)` with side = sign of
/// `<n, grad U_r x grad U_q>`. Faces with a masked-out vertex are skipped when `mask` is given.
pub fn bipolar_grid(
    mesh: &TriMesh,
    ur: &[f64],
    uq: &[f64],
    opts: &GridOptions,
    mask: Option<&[bool]>,
) -> KeyedPoints {
    let tol = 1e-9 * mesh.bbox().diagonal();
    let mut pairs = Vec::new();
    #[allow(clippy::reversed_empty_ranges)]
    let levels = |a: f64, b: f64, c: f64| -> std::ops::RangeInclusive<u32> {
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        if !(lo.is_finite() && hi.is_finite()) {
            return 1..=0; // empty: a face with an unreachable vertex has no level
        }
        let i0 = ((lo / opts.step).ceil().max(1.0)) as u32;
        let i1 = ((hi / opts.step).floor().min(f64::from(opts.max_level))) as u32;
        i0..=i1
    };
    for (f, t) in mesh.triangles().iter().enumerate() {
        if let Some(m) = mask {
            if t.iter().any(|&v| !m[v as usize]) {
                continue;
            }
        }
        let [v0, v1, v2] = t.map(|v| v as usize);
        let (r0, r1, r2) = (ur[v0], ur[v1], ur[v2]);
        let (q0, q1, q2) = (uq[v0], uq[v1], uq[v2]);
        let det = (r1 - r0) * (q2 - q0) - (r2 - r0) * (q1 - q0);
        let scale = ((r1 - r0).abs() + (r2 - r0).abs()) * ((q1 - q0).abs() + (q2 - q0).abs());
        if det.abs().is_nan() || det.abs() <= 1e-12 * scale {
            continue;
        }
        let side = det > 0.0;
        let [p0, p1, p2] = mesh.face_corners(f as u32);
        for i in levels(r0, r1, r2) {
            let a = f64::from(i) * opts.step;
            for j in levels(q0, q1, q2) {
                let b = f64::from(j) * opts.step;
                let b1 = ((a - r0) * (q2 - q0) - (r2 - r0) * (b - q0)) / det;
                let b2 = ((r1 - r0) * (b - q0) - (a - r0) * (q1 - q0)) / det;
                let b0 = 1.0 - b1 - b2;
                if b0 >= -1e-10 && b1 >= -1e-10 && b2 >= -1e-10 {
                    pairs.push((grid_key(i, j, side), b0 * p0 + b1 * p1 + b2 * p2));
                }
            }
        }
    }
    KeyedPoints::from_pairs(pairs, tol)
}

/// Straight isoline pieces of the PL field `u` at each level (one segment per crossed face),
/// for renders. A vertex counts as above a level when `u >= level`.
pub fn isoline_segments(mesh: &TriMesh, u: &[f64], levels: &[f64]) -> Vec<Vec<[DVec3; 2]>> {
    levels
        .iter()
        .map(|&c| {
            let mut segs = Vec::new();
            for t in mesh.triangles() {
                let val = t.map(|v| u[v as usize]);
                if val.iter().any(|x| !x.is_finite()) {
                    continue;
                }
                let mut pts = Vec::with_capacity(2);
                for k in 0..3 {
                    let (a, b) = (k, (k + 1) % 3);
                    if (val[a] >= c) != (val[b] >= c) {
                        let s = (c - val[a]) / (val[b] - val[a]);
                        let pa = mesh.position(t[a]);
                        let pb = mesh.position(t[b]);
                        pts.push(pa + s * (pb - pa));
                    }
                }
                if pts.len() == 2 {
                    segs.push([pts[0], pts[1]]);
                }
            }
            segs
        })
        .collect()
}

/// Result of a keyed distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyedDistance {
    /// Normalised distance in [0, 1].
    pub distance: f64,
    /// Number of paired (shared, unambiguous) keys.
    pub shared: usize,
    /// Unambiguous points of the first set.
    pub n_a: usize,
    /// Unambiguous points of the second set.
    pub n_b: usize,
}

/// Keyed closed-form distance (see the module doc); `None` with fewer than 3 shared keys.
pub fn keyed_distance(a: &KeyedPoints, b: &KeyedPoints) -> Option<KeyedDistance> {
    let (ka, pa) = a.unambiguous();
    let (kb, pb) = b.unambiguous();
    let mut xa = Vec::new();
    let mut xb = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < ka.len() && j < kb.len() {
        match ka[i].cmp(&kb[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                xa.push(pa[i]);
                xb.push(pb[j]);
                i += 1;
                j += 1;
            }
        }
    }
    let d = paired_distance(&xa, &xb)?;
    Some(KeyedDistance {
        distance: d,
        shared: xa.len(),
        n_a: ka.len(),
        n_b: kb.len(),
    })
}

/// Normalised L2 distance between paired point sets after centring and the optimal rotation.
pub fn paired_distance(a: &[DVec3], b: &[DVec3]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 3 {
        return None;
    }
    let n = a.len() as f64;
    let ca = a.iter().copied().sum::<DVec3>() / n;
    let cb = b.iter().copied().sum::<DVec3>() / n;
    let mut s = [[0.0f64; 3]; 3];
    let (mut na, mut nb) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (x, y) = (*p - ca, *q - cb);
        na += x.length_squared();
        nb += y.length_squared();
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] += y[r] * x[c];
            }
        }
    }
    if na + nb <= 0.0 {
        return Some(0.0);
    }
    let lmax = max_rotation_correlation(&s);
    Some(((na + nb - 2.0 * lmax).max(0.0) / (na + nb)).sqrt())
}

/// `max_R sum a_i . R b_i` over rotations, from `S = sum b_i a_i^T`: `s1 + s2 + sign(det S) s3`
/// with `s1 >= s2 >= s3` the singular values of `S` (Umeyama's reflection-guarded trace).
///
/// Independent of the library's Horn and Kabsch solvers (both Jacobi iterations): `s1^2`, `s2^2`
/// are the two largest eigenvalues of `S^T S` in closed form (the trigonometric solution of its
/// characteristic cubic), and the signed `s3` is `det S / (s1 s2)`, which keeps it accurate when
/// it is small (planar point sets). Near rank 1 (`s2` tiny) the result loses precision
/// (`sqrt(eps) s1`), which no test here relies on.
fn max_rotation_correlation(s: &[[f64; 3]; 3]) -> f64 {
    let mut sts = [[0.0f64; 3]; 3];
    for (r, row) in sts.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| s[k][r] * s[k][c]).sum();
        }
    }
    let [l1, l2, _] = sym3_eigenvalues(&sts);
    let (s1, s2) = (l1.max(0.0).sqrt(), l2.max(0.0).sqrt());
    if s1 * s2 <= 0.0 {
        return s1;
    }
    s1 + s2 + det3(s) / (s1 * s2)
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Eigenvalues of a symmetric 3x3 matrix, descending, in closed form: with `q = tr(A) / 3`,
/// `p^2 = |A - qI|_F^2 / 6` and `B = (A - qI) / p`, they are `q + 2p cos(phi + 2 pi k / 3)`,
/// `phi = acos(det(B) / 2) / 3` (Smith, CACM 1961).
fn sym3_eigenvalues(a: &[[f64; 3]; 3]) -> [f64; 3] {
    let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let d = [a[0][0] - q, a[1][1] - q, a[2][2] - q];
    let p2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + 2.0 * off;
    if p2 <= 0.0 {
        return [q; 3];
    }
    let p = (p2 / 6.0).sqrt();
    let mut b = *a;
    for (i, row) in b.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (*v - if i == j { q } else { 0.0 }) / p;
        }
    }
    let phi = (0.5 * det3(&b)).clamp(-1.0, 1.0).acos() / 3.0;
    let third = 2.0 * std::f64::consts::PI / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + third).cos();
    [hi, 3.0 * q - hi - lo, lo]
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::shapes::grid_plane;
    use meshcore::{DMat3, DQuat};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Unit square of `n x n` cells, interior vertices jittered by up to `jitter * h`.
    fn plane(n: usize, jitter: f64, seed: u64) -> TriMesh {
        grid_plane(n, 1.0 / n as f64, 0.0, 2.0 * jitter, seed, |_| false)
    }

    fn random_set(n: usize, seed: u64) -> Vec<DVec3> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * 4.0 - 2.0)
            .collect()
    }

    #[test]
    fn rotated_copy_is_at_zero_and_reflection_is_not() {
        let a = random_set(50, 1);
        let r = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(1.0, 2.0, -0.5).normalize(),
            2.7,
        ));
        let b: Vec<DVec3> = a
            .iter()
            .map(|p| r * *p + DVec3::new(3.0, -1.0, 7.0))
            .collect();
        assert!(paired_distance(&a, &b).unwrap() < 1e-7);
        let m: Vec<DVec3> = a.iter().map(|p| DVec3::new(-p.x, p.y, p.z)).collect();
        assert!(paired_distance(&a, &m).unwrap() > 0.1);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let noisy: Vec<DVec3> = a
            .iter()
            .map(|p| *p + 0.05 * DVec3::new(rng.random(), rng.random(), rng.random()))
            .collect();
        let d = paired_distance(&a, &noisy).unwrap();
        assert!(d > 1e-4 && d < 0.05, "{d}");
        let d2 = paired_distance(&noisy, &a).unwrap();
        assert!((d - d2).abs() < 1e-12);
    }

    /// The closed form agrees with the library's Horn and Kabsch solvers on the maximum, for
    /// rotations, reflections (negative determinant) and rank-2 (planar) correlations.
    #[test]
    fn rotation_maximum_matches_horn_and_kabsch() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for case in 0..40 {
            let mut s = [[0.0f64; 3]; 3];
            for row in s.iter_mut() {
                for v in row.iter_mut() {
                    *v = rng.random::<f64>() * 2.0 - 1.0;
                }
            }
            if case % 4 == 3 {
                // Rank 2: the third row a combination of the first two.
                s[2] = [0, 1, 2].map(|c| 0.3 * s[0][c] - 0.7 * s[1][c]);
            }
            let ours = max_rotation_correlation(&s);
            // The library's K = sum a b^T is S^T.
            let k = DMat3::from_cols_array_2d(&s);
            for (what, theirs) in [
                ("kabsch", meshcore::linalg::kabsch_rotation(k).1),
                ("horn", meshcore::linalg::horn_rotation(k).1),
            ] {
                assert!(
                    (ours - theirs).abs() < 1e-9 * (1.0 + theirs.abs()),
                    "case {case}: {what} {theirs} vs {ours}"
                );
            }
        }
    }

    #[test]
    fn keyed_distance_pairs_by_key_and_skips_ambiguous() {
        let a = random_set(20, 2);
        let mut pa: Vec<(u64, DVec3)> = a.iter().enumerate().map(|(i, p)| (i as u64, *p)).collect();
        // Shuffle order and a duplicate far away for key 5 (ambiguous).
        pa.reverse();
        pa.push((5, DVec3::splat(100.0)));
        let ka = KeyedPoints::from_pairs(pa, 1e-9);
        assert!(ka.ambiguous[5]);
        // b: same points for keys 0..15 only, plus a wild point at key 5 (ignored: ambiguous in a).
        let pb: Vec<(u64, DVec3)> = a
            .iter()
            .enumerate()
            .take(15)
            .map(|(i, p)| (i as u64, if i == 5 { DVec3::splat(-50.0) } else { *p }))
            .collect();
        let kb = KeyedPoints::from_pairs(pb, 1e-9);
        let d = keyed_distance(&ka, &kb).unwrap();
        assert_eq!(d.shared, 14);
        assert!(d.distance < 1e-7);
        assert!(
            keyed_distance(&ka, &KeyedPoints::from_pairs(vec![(0, DVec3::ZERO)], 1e-9)).is_none()
        );
    }

    #[test]
    fn grid_on_a_plane_follows_the_law_of_cosines() {
        let m = plane(40, 0.3, 9);
        let (r, q) = (DVec3::new(0.3, 0.5, 0.0), DVec3::new(0.7, 0.5, 0.0));
        let ur: Vec<f64> = m.positions().iter().map(|p| (*p - r).length()).collect();
        let uq: Vec<f64> = m.positions().iter().map(|p| (*p - q).length()).collect();
        let g = bipolar_grid(
            &m,
            &ur,
            &uq,
            &GridOptions {
                step: 0.1,
                max_level: 4,
            },
            None,
        );
        assert!(!g.is_empty());
        for k in 0..g.len() {
            let (i, j, side) = grid_key_parts(g.keys[k]);
            let p = g.points[k];
            // Exact circle intersection of radii i/10 and j/10.
            let (a, b, d) = (f64::from(i) * 0.1, f64::from(j) * 0.1, 0.4);
            let x = (a * a - b * b + d * d) / (2.0 * d);
            let y = (a * a - x * x).max(0.0).sqrt();
            let expect_y = if side { 0.5 + y } else { 0.5 - y };
            // PL interpolation of the distance: error O(h^2 / R).
            assert!(
                (p.x - (0.3 + x)).abs() < 0.01 && (p.y - expect_y).abs() < 0.01,
                "{i} {j} {side} {p:?}"
            );
            assert!(!g.ambiguous[k]);
        }
        // Both sides present and symmetric in number.
        let n_side = g.keys.iter().filter(|k| *k & 1 == 1).count();
        assert_eq!(2 * n_side, g.len());
    }

    #[test]
    fn isolines_cross_each_face_once() {
        let m = plane(10, 0.2, 4);
        let u: Vec<f64> = m.positions().iter().map(|p| p.x).collect();
        let s = isoline_segments(&m, &u, &[0.55]);
        assert_eq!(s[0].len(), 20);
        for seg in &s[0] {
            assert!((seg[0].x - 0.55).abs() < 1e-12 && (seg[1].x - 0.55).abs() < 1e-12);
        }
    }
}
