//! A mesh carried to another topology of a given edge length.

use crate::{decimate, ScanPrepError};
use meshcore::TriMesh;

/// Most midpoint subdivisions [`remesh`] makes before decimating (each multiplies the faces by
/// four).
pub const MAX_SUBDIVISIONS: usize = 6;

/// The surface of `mesh` on another topology with edges of about `edge` (the mesh's units):
/// midpoint-subdivided ([`meshcore::subdivide_midpoint`]) until its mean edge is at most
/// half of `edge`, then decimated to `edge` by shortest-edge collapse ([`decimate`]). The
/// vertices of the result are not those of the input (except where decimation kept one), and
/// the triangles follow the collapses, not the input's layout: a test face of another
/// topology. Errors when `edge` is not positive and finite, or when more than
/// [`MAX_SUBDIVISIONS`] subdivisions would be needed.
pub fn remesh(mesh: &TriMesh, edge: f64) -> Result<TriMesh, ScanPrepError> {
    if !(edge.is_finite() && edge > 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "remesh edge length {edge} (expected > 0)"
        )));
    }
    let mut m = meshcore::subdivide_midpoint(mesh)?;
    let mut levels = 1;
    while m.mean_edge_length() > 0.5 * edge {
        if levels == MAX_SUBDIVISIONS {
            return Err(ScanPrepError::InvalidOption(format!(
                "remesh edge length {edge}: the mesh's mean edge {} is more than {} times longer",
                mesh.mean_edge_length(),
                1usize << (MAX_SUBDIVISIONS + 1)
            )));
        }
        m = meshcore::subdivide_midpoint(&m)?;
        levels += 1;
    }
    Ok(decimate(&m, edge)?.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::DVec3;

    #[test]
    fn gives_another_topology_of_the_asked_edge_on_the_same_surface() {
        // A sphere of radius 50 with edges of about 10, remeshed to edges of 4.
        let m = meshcore::shapes::icosphere(3)
            .transformed(&meshcore::DAffine3::from_scale(DVec3::splat(50.0)));
        let r = remesh(&m, 4.0).unwrap();
        assert_ne!(r.n_vertices(), m.n_vertices());
        let e = r.mean_edge_length();
        assert!((3.0..5.4).contains(&e), "mean edge {e}");
        // Every vertex stays on the sphere (midpoints sink by at most about a sagitta).
        for p in r.positions() {
            assert!((p.length() - 50.0).abs() < 1.0, "{}", p.length());
        }
        assert!(remesh(&m, 0.0).is_err());
        assert!(remesh(&m, 1e-6).is_err());
    }
}
