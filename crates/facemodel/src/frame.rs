//! The static (upper) face area, derived from the landmarks.
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

/// Builds the frame from the two outer eye corners and the nose tip.
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
/// corners; `d`: the distance between them.
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
        .map(|(v, p)| ur[v] <= d && uq[v] <= d && (*p - nose).dot(frame.up) >= 0.0)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::walk::tests::plane;

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
}
