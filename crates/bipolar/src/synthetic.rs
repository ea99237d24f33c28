//! Synthetic meshes for tests, benchmarks and validation (the generators of
//! `meshcore::shapes`; their analytic distance fields are `testsupport::fields`).

pub use meshcore::shapes::{grid_plane, icosphere, uv_sphere};

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::Topology;

    #[test]
    fn spheres_are_closed_and_outward() {
        for m in [icosphere(2), uv_sphere(8, 12)] {
            let t = Topology::new(&m);
            assert!(t.boundary_loops().is_empty());
            assert!(t.inconsistent_edges().is_empty());
            // Outward: every face normal points away from the centre.
            for f in 0..m.n_faces() as u32 {
                let [a, b, c] = m.face_corners(f);
                assert!(m.face_normal(f).dot((a + b + c) / 3.0) > 0.0);
            }
            assert_eq!(t.n_components(), 1);
        }
        assert_eq!(icosphere(2).n_vertices(), 162);
    }

    #[test]
    fn grid_with_hole_has_two_loops() {
        let m = grid_plane(10, 0.1, -0.5, 0.2, 1, |c| c.length() < 0.2);
        let t = Topology::new(&m);
        assert_eq!(t.boundary_loops().len(), 2);
        assert_eq!(t.isolated_vertices(), 0);
    }
}
