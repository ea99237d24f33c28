//! The bipolar descriptor of a face from one pole pair: on the static area (within D of both
//! poles, above the nose tip's horizontal plane) or on the whole face. The one place where a
//! pole pair's fields become `bipolar::DescriptorOptions`: matching's three pole pairs, the
//! moved poles of its search and the experiments' descriptors all go through it.

use facemodel::{static_mask, FaceFrame};
use meshcore::{DVec3, Surface, TriMesh};

/// The reference configuration of a bipolar descriptor on a face: the two poles' geodesic
/// fields, D, the poles' places, and the nose tip and landmark frame that bound the static
/// area. For the outer eye corners' pair the poles are r (right) and q (left); a side pair's
/// poles stand in their places (an outer eye corner as r, the nose tip as q).
#[derive(Debug, Clone)]
pub struct PoleRefs {
    /// Geodesic distance from the first pole r, per vertex.
    pub ur: Vec<f64>,
    /// Geodesic distance from the second pole q, per vertex.
    pub uq: Vec<f64>,
    /// D: the geodesic distance between the poles (the level step is D / N).
    pub d: f64,
    /// Place of the first pole.
    pub r: DVec3,
    /// Place of the second pole.
    pub q: DVec3,
    /// Place of the nose tip (the static area lies above its horizontal plane).
    pub nose: DVec3,
    /// The landmark frame whose `up` sets that plane ([`facemodel::face_frame`]).
    pub frame: FaceFrame,
}

/// Which part of a face a descriptor covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Area {
    /// The static area ([`facemodel::static_mask`]): within D of both poles and above the nose
    /// tip's horizontal plane, levels up to N.
    Static,
    /// Levels up to 2N of both fields, no mask: nearly the whole face.
    Whole,
}

impl PoleRefs {
    /// The references of poles at `r` and `q` with fields `ur`, `uq` and distance `d`, the
    /// nose tip at `nose` and the frame of these three points on `mesh`
    /// ([`facemodel::face_frame`]).
    pub fn new(mesh: &TriMesh, [ur, uq]: [Vec<f64>; 2], d: f64, [r, q, nose]: [DVec3; 3]) -> Self {
        let frame = facemodel::face_frame(mesh, r, q, nose);
        Self {
            ur,
            uq,
            d,
            r,
            q,
            nose,
            frame,
        }
    }

    /// The static area of these references on `mesh` (the fields' mesh), a vertex mask:
    /// [`facemodel::static_mask`] with D, the nose tip and the frame.
    pub fn static_area(&self, mesh: &TriMesh) -> Vec<bool> {
        static_mask(mesh, &self.ur, &self.uq, self.d, &self.frame, self.nose)
    }

    /// The bipolar descriptor of these references on `surface` (the fields' mesh) with `n`
    /// levels between the poles (step D / n) over `area`, only on the vertices `kept` when
    /// given (with the static area, both must hold). `base` gives every other option (rule,
    /// tangents, boundary margin); its `levels`, `max_level` and `vertex_mask` are replaced.
    ///
    /// # Errors
    /// Whatever [`bipolar::describe`] refuses (fields of the wrong length, a non-positive D,
    /// no intersection in the area).
    pub fn descriptor(
        &self,
        surface: &Surface,
        n: u32,
        area: Area,
        kept: Option<&[bool]>,
        base: bipolar::DescriptorOptions,
    ) -> Result<bipolar::Descriptor, bipolar::BipolarError> {
        let (max_level, mask) = match area {
            Area::Static => {
                let mask = self.static_area(surface.mesh());
                let mask = match kept {
                    Some(k) => mask.iter().zip(k).map(|(&a, &b)| a && b).collect(),
                    None => mask,
                };
                (n, Some(mask))
            }
            Area::Whole => (2 * n, kept.map(<[bool]>::to_vec)),
        };
        let opts = bipolar::DescriptorOptions {
            levels: bipolar::LevelSpec::Step(self.d / f64::from(n)),
            max_level: Some(max_level),
            vertex_mask: mask,
            ..base
        };
        bipolar::describe(
            surface,
            bipolar::Fields::Precomputed {
                fields: &[self.ur.clone(), self.uq.clone()],
                references: None,
            },
            &opts,
        )
    }
}

/// `bipolar`'s options with the selection rule `All` (every intersection of the two level
/// families, keys `(i, j, side)`: the grid reading), the rule face matching describes with.
pub fn grid_rule() -> bipolar::DescriptorOptions {
    bipolar::DescriptorOptions {
        rule: bipolar::SelectionRule::All,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use facemodel::face_frame;

    /// A 60 x 40 mm sheet of 2 mm squares bulging toward +z around (30, 20), poles 40 mm
    /// apart on y = 24, the nose tip at (30, 14); the Euclidean distances stand in for the
    /// geodesic fields (the sheet is nearly flat), D their separation.
    fn sheet() -> (Surface, PoleRefs) {
        let m = meshcore::shapes::grid(30, 20, meshcore::shapes::Diagonals::Alternating, |i, j| {
            let (x, y) = (2.0 * i as f64, 2.0 * j as f64);
            let z = 3.0 * (-((x - 30.0).powi(2) + (y - 20.0).powi(2)) / 400.0).exp();
            DVec3::new(x, y, z)
        })
        .unwrap();
        let (r, q, nose) = (
            DVec3::new(10.0, 24.0, 0.0),
            DVec3::new(50.0, 24.0, 0.0),
            DVec3::new(30.0, 14.0, 0.0),
        );
        let dist = |m: &TriMesh, p: DVec3| -> Vec<f64> {
            m.positions().iter().map(|x| (*x - p).length()).collect()
        };
        let refs = PoleRefs::new(&m, [dist(&m, r), dist(&m, q)], 40.0, [r, q, nose]);
        assert_eq!(refs.frame, face_frame(&m, r, q, nose));
        (Surface::new(m), refs)
    }

    #[test]
    fn the_static_area_keeps_the_lens_above_the_nose_and_the_kept_vertices() {
        let (surface, refs) = sheet();
        let all = refs
            .descriptor(&surface, 8, Area::Static, None, grid_rule())
            .unwrap();
        assert!(!all.points.is_empty());
        let mesh = surface.mesh();
        let area = refs.static_area(mesh);
        // The frame's up is the sheet's +y (toward the poles from the nose tip).
        assert!(
            (refs.frame.up - DVec3::Y).length() < 1e-6,
            "{}",
            refs.frame.up
        );
        let inside = |p: DVec3| {
            let within = |c: DVec3| (p - c).length() <= refs.d;
            within(refs.r) && within(refs.q) && (p - refs.nose).dot(refs.frame.up) >= 0.0
        };
        assert!(mesh
            .positions()
            .iter()
            .zip(&area)
            .all(|(p, &a)| a == inside(*p)));
        assert!(area.iter().any(|&a| a) && area.iter().any(|&a| !a));
        for p in &all.points {
            let x = p.position;
            // Within D (and a face's width: the crossings lie on edges of kept vertices) of both
            // poles, not below the nose tip's plane by more than one edge.
            assert!((x - refs.r).length() <= refs.d + 3.0, "{x}");
            assert!((x - refs.q).length() <= refs.d + 3.0, "{x}");
            assert!(x.y >= refs.nose.y - 2.0, "{x}");
        }
        // The whole face reaches farther: levels up to 2N, below the nose tip too.
        let whole = refs
            .descriptor(&surface, 8, Area::Whole, None, grid_rule())
            .unwrap();
        assert!(whole.points.len() > all.points.len());
        assert!(whole
            .points
            .iter()
            .any(|p| p.position.y < refs.nose.y - 2.0));
        // Only the left half kept: no point right of the middle beyond an edge.
        let left: Vec<bool> = mesh.positions().iter().map(|p| p.x <= 30.0).collect();
        let half = refs
            .descriptor(&surface, 8, Area::Static, Some(&left), grid_rule())
            .unwrap();
        assert!(!half.points.is_empty() && half.points.len() < all.points.len());
        assert!(half.points.iter().all(|p| p.position.x <= 32.0));
        // `base` decides the rule: the iso-angle rule gives other keys.
        let iso = refs
            .descriptor(&surface, 8, Area::Static, None, Default::default())
            .unwrap();
        assert_ne!(
            iso.points.iter().map(|p| p.key).collect::<Vec<_>>(),
            all.points.iter().map(|p| p.key).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_field_of_the_wrong_length_is_an_error() {
        let (surface, mut refs) = sheet();
        refs.uq.pop();
        assert!(refs
            .descriptor(&surface, 8, Area::Whole, None, grid_rule())
            .is_err());
    }
}
