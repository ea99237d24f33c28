//! The landmark-derived face frame and the static (upper) face area.
//!
//! Choice (documented in `docs/experiments.md`): a vertex is static when it lies within the
//! geodesic distance `D` (between the outer eye corners) of **both** corners and **above the
//! horizontal plane through the nose tip**. "Horizontal" is built from the landmarks and the
//! mesh only (so it moves with the face): `x` = the eye line `q - r`, `forward` = the mean face
//! normal made orthogonal to `x`, `up` = `forward x x` oriented towards the eyes. The lens
//! within D of both corners keeps the eyes, the area between them, the upper nose and the lower
//! forehead (the method notes found this region the most stable); the plane drops the mouth and
//! the lower cheeks, which move most with expressions.

use meshcore::{DVec3, TriMesh};

/// Landmark-derived frame of a face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceFrame {
    /// Unit eye-line direction (r to q).
    pub x: DVec3,
    /// Unit up direction.
    pub up: DVec3,
    /// Unit forward direction (out of the face).
    pub forward: DVec3,
}

/// Builds the frame from the two outer eye corners `r`, `q` and the nose tip. Degenerate input
/// (coincident corners, a mean normal along the eye line) gives zero vectors, never a panic.
pub fn face_frame(mesh: &TriMesh, r: DVec3, q: DVec3, nose: DVec3) -> FaceFrame {
    let x = (q - r).normalize_or_zero();
    let mut n = DVec3::ZERO;
    for f in 0..mesh.n_faces() as u32 {
        n += mesh.face_cross(f);
    }
    let mut forward = (n - n.dot(x) * x).normalize_or_zero();
    let mut up = forward.cross(x).normalize_or_zero();
    if up.dot(0.5 * (r + q) - nose) < 0.0 {
        up = -up;
    }
    // Keep the frame right-handed with forward pointing out of the face (towards the nose tip).
    if forward.dot(nose - 0.5 * (r + q)) < 0.0 {
        forward = -forward;
    }
    FaceFrame { x, up, forward }
}

/// The static-area vertex mask (see the module doc). `ur`, `uq`: distances from the two
/// corners (one per vertex; missing entries count as outside); `d`: the distance between them.
pub fn static_mask(
    mesh: &TriMesh,
    ur: &[f64],
    uq: &[f64],
    d: f64,
    frame: &FaceFrame,
    nose: DVec3,
) -> Vec<bool> {
    mesh.positions()
        .iter()
        .enumerate()
        .map(|(v, p)| {
            let within = |u: &[f64]| u.get(v).is_some_and(|&u| u <= d);
            within(ur) && within(uq) && (*p - nose).dot(frame.up) >= 0.0
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random_rigid_motion;
    use meshcore::shapes::{grid, Diagonals};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The shared jittered unit plane ([`testsupport::jittered_unit_plane`]).
    fn plane(n: usize, jitter: f64, seed: u64) -> TriMesh {
        testsupport::jittered_unit_plane(n, jitter, seed)
    }

    fn assert_orthonormal(f: &FaceFrame) {
        for (a, b) in [(f.x, f.up), (f.x, f.forward), (f.up, f.forward)] {
            assert!(a.dot(b).abs() < 1e-12, "{f:?}");
        }
        for v in [f.x, f.up, f.forward] {
            assert!((v.length() - 1.0).abs() < 1e-12, "{f:?}");
        }
    }

    #[test]
    fn plane_mask_is_the_upper_half_of_the_lens() {
        let m = plane(40, 0.2, 8);
        let (r, q, nose) = (
            DVec3::new(0.3, 0.6, 0.0),
            DVec3::new(0.7, 0.6, 0.0),
            DVec3::new(0.5, 0.4, 0.1),
        );
        let ur: Vec<f64> = m.positions().iter().map(|p| (*p - r).length()).collect();
        let uq: Vec<f64> = m.positions().iter().map(|p| (*p - q).length()).collect();
        let fr = face_frame(&m, r, q, nose);
        assert!((fr.up - DVec3::Y).length() < 1e-12);
        assert!((fr.forward - DVec3::Z).length() < 1e-12);
        let mask = static_mask(&m, &ur, &uq, 0.4, &fr, nose);
        for (v, p) in m.positions().iter().enumerate() {
            let expect = (*p - r).length() <= 0.4 && (*p - q).length() <= 0.4 && p.y >= 0.4;
            assert_eq!(mask[v], expect);
        }
        let n = mask.iter().filter(|x| **x).count();
        assert!(n > 100 && n < m.n_vertices() / 2);
        // Upside-down face (eyes below the nose): up flips with it.
        let fr2 = face_frame(
            &m,
            DVec3::new(0.3, 0.2, 0.0),
            DVec3::new(0.7, 0.2, 0.0),
            nose,
        );
        assert!((fr2.up + DVec3::Y).length() < 1e-12);
    }

    /// A face-like height field: a nose bump on a forehead-to-chin slope, cm-sized.
    fn face_like() -> (TriMesh, DVec3, DVec3, DVec3) {
        let z =
            |x: f64, y: f64| 2.0 * (-(x * x + (y + 0.5) * (y + 0.5)) / 2.0).exp() - 0.03 * x * x;
        let n = 60;
        let m = grid(n, n, Diagonals::Alternating, |i, j| {
            let (x, y) = (
                -6.0 + 12.0 * i as f64 / n as f64,
                -7.0 + 12.0 * j as f64 / n as f64,
            );
            DVec3::new(x, y, z(x, y))
        })
        .unwrap();
        let at = |x: f64, y: f64| DVec3::new(x, y, z(x, y));
        (m, at(-3.03, 2.01), at(3.03, 2.01), at(0.0, -0.49))
    }

    #[test]
    fn frame_is_orthonormal_and_mask_follows_the_face_under_rigid_motions() {
        let (m, r, q, nose) = face_like();
        let d = (q - r).length();
        let fr = face_frame(&m, r, q, nose);
        assert_orthonormal(&fr);
        assert!((fr.x - DVec3::X).length() < 1e-12);
        assert!(fr.up.y > 0.99 && fr.forward.z > 0.99, "{fr:?}");
        let dist = |m: &TriMesh, c: DVec3| -> Vec<f64> {
            m.positions().iter().map(|p| (*p - c).length()).collect()
        };
        let mask = static_mask(&m, &dist(&m, r), &dist(&m, q), d, &fr, nose);
        let n = mask.iter().filter(|x| **x).count();
        assert!(
            n > 100 && n < m.n_vertices() / 2,
            "{n} of {}",
            m.n_vertices()
        );
        // Vertices whose three criteria are not within rounding of their thresholds.
        let clear: Vec<bool> = m
            .positions()
            .iter()
            .map(|p| {
                ((*p - r).length() - d).abs() > 1e-9
                    && ((*p - q).length() - d).abs() > 1e-9
                    && (*p - nose).dot(fr.up).abs() > 1e-9
            })
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..20 {
            let t = random_rigid_motion(&mut rng, 10.0);
            let mm = m.transformed(&t);
            let (rr, qq, nn) = (
                t.transform_point3(r),
                t.transform_point3(q),
                t.transform_point3(nose),
            );
            let f2 = face_frame(&mm, rr, qq, nn);
            assert_orthonormal(&f2);
            for (a, b) in [(fr.x, f2.x), (fr.up, f2.up), (fr.forward, f2.forward)] {
                assert!((t.transform_vector3(a) - b).length() < 1e-9);
            }
            let m2 = static_mask(&mm, &dist(&mm, rr), &dist(&mm, qq), d, &f2, nn);
            for v in 0..m.n_vertices() {
                if clear[v] {
                    assert_eq!(mask[v], m2[v], "vertex {v}");
                }
            }
        }
    }
}
