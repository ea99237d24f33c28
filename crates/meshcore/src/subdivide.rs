//! Midpoint subdivision.

use crate::{DVec3, MeshError, TriMesh};
use std::collections::HashMap;

/// One step of midpoint subdivision: every triangle `[a, b, c]` becomes four
/// (`[a, ab, ca]`, `[ab, b, bc]`, `[ca, bc, c]`, `[ab, bc, ca]`) with a new vertex at the
/// middle of each edge, shared by the edge's two triangles. The surface is unchanged (the new
/// vertices lie on the old edges) and the edges are halved; the old vertices keep their ids,
/// the midpoints follow in order of first use. Errors only when the result exceeds the `u32`
/// vertex ids of [`TriMesh`].
pub fn subdivide_midpoint(mesh: &TriMesh) -> Result<TriMesh, MeshError> {
    let mut pos: Vec<DVec3> = mesh.positions().to_vec();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut at = |a: u32, b: u32, pos: &mut Vec<DVec3>| -> u32 {
        let key = (a.min(b), a.max(b));
        *mid.entry(key).or_insert_with(|| {
            pos.push((pos[a as usize] + pos[b as usize]) / 2.0);
            (pos.len() - 1) as u32
        })
    };
    let mut tri = Vec::with_capacity(4 * mesh.n_faces());
    for t in mesh.triangles() {
        let [a, b, c] = *t;
        let (ab, bc, ca) = (at(a, b, &mut pos), at(b, c, &mut pos), at(c, a, &mut pos));
        tri.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    TriMesh::new(pos, tri)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_the_edges_and_keeps_the_surface() {
        let m = crate::shapes::icosphere(1);
        let s = subdivide_midpoint(&m).unwrap();
        assert_eq!(s.n_faces(), 4 * m.n_faces());
        // Euler: every edge gets one midpoint.
        let edges = 3 * m.n_faces() / 2;
        assert_eq!(s.n_vertices(), m.n_vertices() + edges);
        assert!((s.mean_edge_length() - m.mean_edge_length() / 2.0).abs() < 1e-12);
        assert_eq!(&s.positions()[..m.n_vertices()], m.positions());
        assert!((s.area() - m.area()).abs() < 1e-9 * m.area());
    }
}
