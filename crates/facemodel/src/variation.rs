//! Faces beyond the span of a face model: expressions past full strength or mixed, and smooth
//! random non-rigid warps (test faces the model cannot make); and things that are not faces
//! ([`non_faces`]), for a detector to refuse.

use crate::{FaceModel, FaceModelError};
use meshcore::{DAffine3, DQuat, DVec3, TriMesh};
use rand::Rng;

impl FaceModel {
    /// Expression weights beyond the model's span: a random recipe at 1.5-2 times its full
    /// strength, or (half of the time) two random recipes at 0.7-1.2 each, added. Returns the
    /// weights and a label (`happiness x1.73`, `anger x0.91 + fear x1.05`). Errors when the
    /// model has no recipes.
    pub fn strong_expression<R: Rng>(
        &self,
        rng: &mut R,
    ) -> Result<(Vec<f64>, String), FaceModelError> {
        let recipes: Vec<&str> = self.recipe_names().collect();
        if recipes.is_empty() {
            return Err(FaceModelError::UnknownRecipe {
                name: "any (the model has no expression recipes)".into(),
            });
        }
        let pick = |rng: &mut R| recipes[rng.random_range(0..recipes.len())];
        if rng.random::<f64>() < 0.5 {
            let (r, k) = (pick(rng), rng.random_range(1.5..2.0));
            Ok((self.recipe_weights(r, k)?, format!("{r} x{k:.2}")))
        } else {
            let (a, b) = (pick(rng), pick(rng));
            let (ka, kb) = (rng.random_range(0.7..1.2), rng.random_range(0.7..1.2));
            let wa = self.recipe_weights(a, ka)?;
            let wb = self.recipe_weights(b, kb)?;
            let w = wa.iter().zip(&wb).map(|(x, y)| x + y).collect();
            Ok((w, format!("{a} x{ka:.2} + {b} x{kb:.2}")))
        }
    }
}

/// A warped face of [`random_warp`].
#[derive(Debug, Clone)]
pub struct Warp {
    /// The warped face (same topology as the input).
    pub mesh: TriMesh,
    /// The largest displacement of a vertex, mm.
    pub size_mm: f64,
    /// What each part of the warp does (`eyes wider (left side)`, `brows higher`, `nose
    /// longer`, `random bump`).
    pub parts: Vec<String>,
}

/// A face frame from the five landmarks: origin at the nose tip, `x` from the right to the left
/// outer eye corner, `y` up, `z` out of the face.
fn frame(lm: &[DVec3; 5]) -> (DVec3, [DVec3; 3]) {
    let x = (lm[3] - lm[0]).normalize();
    let eyes = (lm[0] + lm[1] + lm[2] + lm[3]) / 4.0;
    let up = eyes - lm[4];
    let y = (up - x * up.dot(x)).normalize();
    (lm[4], [x, y, x.cross(y)])
}

/// A Gaussian bump of the displacement field: centre, width and displacement at the centre.
struct Bump {
    centre: DVec3,
    sigma: f64,
    shift: DVec3,
}

/// Warps a face in mm, whose landmarks `lm` are in [`crate::LANDMARK_NAMES`] order, by a sum of
/// 3-5 smooth Gaussian bumps (widths 0.4-0.6 of the inner-eye distance) scaled to a largest
/// displacement of 2-6 mm: outer eye corners moved out or in (eyes wider or narrower), brows
/// up, the nose longer, random bumps; each eye or brow bump on one side only two times in
/// three (asymmetric faces). The landmarks move with the surface: read them again on the
/// result (e.g. [`FaceModel::landmark_positions`]). A field that moves nothing (not met with
/// a face) leaves the face as it is.
pub fn random_warp<R: Rng>(
    face: &TriMesh,
    lm: &[DVec3; 5],
    rng: &mut R,
) -> Result<Warp, FaceModelError> {
    let (o, [x, y, z]) = frame(lm);
    let d = (lm[2] - lm[1]).length(); // inner-eye distance, about 33 mm
    let mut bumps = Vec::new();
    let mut parts = Vec::new();
    for _ in 0..rng.random_range(3..=5) {
        // The subject's right (-1) or left (+1) side, or both.
        let sides: Vec<f64> = match rng.random_range(0..3) {
            0 => vec![-1.0],
            1 => vec![1.0],
            _ => vec![-1.0, 1.0],
        };
        let amp = rng.random_range(0.5..1.0);
        let outer = |s: f64| if s < 0.0 { lm[0] } else { lm[3] };
        let brow = |s: f64| {
            let eye = if s < 0.0 {
                lm[0] + lm[1]
            } else {
                lm[2] + lm[3]
            };
            eye / 2.0 + y * 0.45 * d
        };
        let kind = rng.random_range(0..5);
        let label = [
            "eyes wider",
            "eyes narrower",
            "brows higher",
            "nose longer",
            "random bump",
        ][kind];
        match kind {
            0..=2 => {
                for &s in &sides {
                    let (centre, shift, sigma) = match kind {
                        0 => (outer(s), x * s, 0.4 * d),
                        1 => (outer(s), -x * s, 0.4 * d),
                        _ => (brow(s), y, 0.5 * d),
                    };
                    bumps.push(Bump {
                        centre,
                        sigma,
                        shift: shift * amp,
                    });
                }
                let side = match sides.as_slice() {
                    [s] if *s < 0.0 => " (right side)",
                    [_] => " (left side)",
                    _ => "",
                };
                parts.push(format!("{label}{side}"));
            }
            3 => {
                bumps.push(Bump {
                    centre: o,
                    sigma: 0.6 * d,
                    shift: (z * 0.8 - y * 0.6) * amp,
                });
                parts.push(label.to_string());
            }
            _ => {
                let centre =
                    o + x * rng.random_range(-1.6..1.6) * d + y * rng.random_range(-1.0..1.8) * d;
                let dir = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize_or_zero();
                bumps.push(Bump {
                    centre,
                    sigma: 0.5 * d,
                    shift: dir * amp,
                });
                parts.push(label.to_string());
            }
        }
    }
    let field = |p: DVec3| -> DVec3 {
        bumps
            .iter()
            .map(|b| b.shift * (-(p - b.centre).length_squared() / (2.0 * b.sigma * b.sigma)).exp())
            .sum()
    };
    let raw: Vec<DVec3> = face.positions().iter().map(|&p| field(p)).collect();
    let largest = raw.iter().map(|v| v.length()).fold(0.0, f64::max);
    let size_mm = rng.random_range(2.0..6.0);
    let k = if largest > 0.0 {
        size_mm / largest
    } else {
        0.0
    };
    let pos: Vec<DVec3> = face
        .positions()
        .iter()
        .zip(&raw)
        .map(|(p, v)| *p + *v * k)
        .collect();
    Ok(Warp {
        mesh: TriMesh::new(pos, face.triangles().to_vec())?,
        size_mm: if largest > 0.0 { size_mm } else { 0.0 },
        parts,
    })
}

/// Things that are not faces, in mm, named, each turned about the origin by a rotation drawn
/// from `rng`: a sphere of radius 80, a 200 x 200 mm plane of 2 mm cells with 1 mm Gaussian
/// noise along its normal, the back of a head (an ellipsoid cap 150 x 190 x 60 mm) and a face
/// seen from behind: the mesh `face` makes (in mm, from the same stream, after the plane's
/// noise) with every triangle's orientation reversed, so its normals point into the head.
pub fn non_faces<R: Rng>(
    rng: &mut R,
    face: impl FnOnce(&mut R) -> Result<TriMesh, FaceModelError>,
) -> Result<Vec<(String, TriMesh)>, FaceModelError> {
    use meshcore::shapes::{grid, uv_sphere, Diagonals::Alternating};
    let sphere = uv_sphere(60, 120).transformed(&DAffine3::from_scale(DVec3::splat(80.0)));
    let plane = grid(100, 100, Alternating, |i, j| {
        DVec3::new(2.0 * i as f64, 2.0 * j as f64, 0.0)
    })?;
    let noisy: Vec<DVec3> = plane
        .positions()
        .iter()
        .map(|p| *p + DVec3::Z * crate::standard_normal(rng))
        .collect();
    let plane = TriMesh::new(noisy, plane.triangles().to_vec())?;
    let back = grid(90, 90, Alternating, |i, j| {
        let (u, v) = (i as f64 / 90.0 * 2.0 - 1.0, j as f64 / 90.0 * 2.0 - 1.0);
        let r2 = (u * u + v * v).min(1.0);
        DVec3::new(75.0 * u, 95.0 * v, 60.0 * (1.0 - r2).sqrt())
    })?;
    let face = face(rng)?;
    let reversed = face.triangles().iter().map(|t| [t[0], t[2], t[1]]);
    let behind = TriMesh::new(face.positions().to_vec(), reversed.collect())?;
    let named = [
        ("sphere r=80 mm", sphere),
        ("plane with 1 mm noise", plane),
        ("back of a head (ellipsoid cap)", back),
        ("face seen from behind", behind),
    ];
    Ok(named
        .into_iter()
        .map(|(name, m)| {
            let axis = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                1.0,
            );
            let angle = rng.random_range(0.0..std::f64::consts::TAU);
            let t = DAffine3::from_rotation_translation(
                DQuat::from_axis_angle(axis.normalize(), angle),
                DVec3::ZERO,
            );
            (name.to_string(), m.transformed(&t))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn non_faces_are_turned_shapes_and_a_face_inside_out() {
        let face = meshcore::shapes::icosphere(2);
        let make = |seed| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            non_faces(&mut rng, |_| Ok(face.clone())).unwrap()
        };
        let shapes = make(1);
        let names: Vec<&str> = shapes.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names[0], "sphere r=80 mm");
        assert_eq!(names[3], "face seen from behind");
        // Rotations about the origin keep every sphere vertex 80 mm from it.
        assert!(shapes[0]
            .1
            .positions()
            .iter()
            .all(|p| (p.length() - 80.0).abs() < 1e-9));
        // The plane's noise: its points scatter about 1 mm off the plane through them.
        let plane = &shapes[1].1;
        let n = (0..plane.n_faces() as u32)
            .map(|f| plane.face_cross(f))
            .sum::<DVec3>()
            .normalize();
        let c = plane.positions().iter().sum::<DVec3>() / plane.n_vertices() as f64;
        let sd = (plane
            .positions()
            .iter()
            .map(|p| (*p - c).dot(n).powi(2))
            .sum::<f64>()
            / plane.n_vertices() as f64)
            .sqrt();
        assert!((0.8..1.5).contains(&sd), "{sd}");
        // The face seen from behind is the face turned, its orientation reversed: the signed
        // volume of the closed icosphere changes sign.
        let volume = |m: &TriMesh| -> f64 {
            (0..m.n_faces() as u32)
                .map(|f| {
                    let [a, b, c] = m.face_corners(f);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum()
        };
        let behind = &shapes[3].1;
        assert!((volume(behind) + volume(&face)).abs() < 1e-9 * volume(&face).abs());
        // The same stream makes the same shapes; another stream turns them otherwise.
        assert_eq!(make(1)[2].1.positions(), shapes[2].1.positions());
        assert_ne!(make(2)[2].1.positions(), shapes[2].1.positions());
    }

    #[test]
    fn moves_the_face_by_2_to_6_mm_smoothly() {
        // A 200 x 200 mm plane of 2 mm cells with face-like landmarks (inner eyes 33 mm apart).
        let plane = meshcore::shapes::grid(
            100,
            100,
            meshcore::shapes::Diagonals::Alternating,
            |i, j| DVec3::new(2.0 * i as f64 - 100.0, 2.0 * j as f64 - 100.0, 0.0),
        )
        .unwrap();
        let lm = [
            DVec3::new(-45.0, 30.0, 0.0),
            DVec3::new(-16.5, 30.0, 0.0),
            DVec3::new(16.5, 30.0, 0.0),
            DVec3::new(45.0, 30.0, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
        ];
        for seed in 0..5 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let w = random_warp(&plane, &lm, &mut rng).unwrap();
            assert!((2.0..6.0).contains(&w.size_mm));
            assert!((3..=5).contains(&w.parts.len()), "{:?}", w.parts);
            let moved: Vec<f64> = plane
                .positions()
                .iter()
                .zip(w.mesh.positions())
                .map(|(a, b)| (*b - *a).length())
                .collect();
            let largest = moved.iter().copied().fold(0.0, f64::max);
            assert!(
                (largest - w.size_mm).abs() < 1e-9,
                "{largest} {}",
                w.size_mm
            );
            // Smooth: along an edge the displacement changes by less than half the edge's
            // length (a Gaussian of width 13 mm scaled to 6 mm changes by at most 0.28 mm per
            // mm).
            for t in plane.triangles() {
                let (a, b) = (t[0] as usize, t[1] as usize);
                let edge = (plane.position(t[0]) - plane.position(t[1])).length();
                assert!((moved[a] - moved[b]).abs() < 0.5 * edge, "{a} {b}");
            }
            // The corners of the plane, 100 mm and more from every bump, stay.
            assert!(moved[0] < 1e-3);
        }
    }
}
