use crate::solver::{seeds, Field, Item};
use crate::{GeodesicError, Method, Source, TriMesh};
use glam::DVec3;
use std::collections::BinaryHeap;

/// Dijkstra's shortest paths on the edge graph, the paper's approximation.
///
/// Its error does not shrink with refinement (it measures paths along edges). A surface-point
/// source starts from the three corners of its face with their straight-line distances.
#[derive(Debug, Clone)]
pub struct Dijkstra {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    offsets: Vec<u32>,
    neighbors: Vec<(u32, f64)>,
}

impl Dijkstra {
    /// Builds the edge graph of `mesh`.
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let topo = meshcore::Topology::new(mesh);
        let n = mesh.n_vertices();
        let mut deg = vec![0u32; n + 1];
        for e in topo.edges() {
            deg[e.v[0] as usize + 1] += 1;
            deg[e.v[1] as usize + 1] += 1;
        }
        for i in 0..n {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut neighbors = vec![(0u32, 0.0f64); deg[n] as usize];
        for e in topo.edges() {
            let (a, b) = (e.v[0], e.v[1]);
            let l = (mesh.position(a) - mesh.position(b)).length();
            neighbors[fill[a as usize] as usize] = (b, l);
            fill[a as usize] += 1;
            neighbors[fill[b as usize] as usize] = (a, l);
            fill[b as usize] += 1;
        }
        Ok(Self {
            positions: mesh.positions().to_vec(),
            triangles: mesh.triangles().to_vec(),
            offsets: deg,
            neighbors,
        })
    }
}

impl Field for Dijkstra {
    const METHOD: Method = Method::Dijkstra;
    fn positions(&self) -> &[DVec3] {
        &self.positions
    }
    fn field(&self, sources: &[Source], cut: f64) -> Result<Vec<f64>, GeodesicError> {
        let mut dist = vec![f64::INFINITY; self.positions.len()];
        let mut heap = BinaryHeap::new();
        for (v, d) in seeds(&self.positions, &self.triangles, sources)? {
            if d < dist[v as usize] {
                dist[v as usize] = d;
                heap.push(Item(d, v));
            }
        }
        while let Some(Item(d, v)) = heap.pop() {
            if d > dist[v as usize] || d > cut {
                continue;
            }
            let (a, b) = (
                self.offsets[v as usize] as usize,
                self.offsets[v as usize + 1] as usize,
            );
            for &(w, l) in &self.neighbors[a..b] {
                let nd = d + l;
                if nd < dist[w as usize] {
                    dist[w as usize] = nd;
                    heap.push(Item(nd, w));
                }
            }
        }
        Ok(dist)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GeodesicSolver, SolveOptions};

    #[test]
    fn path_graph_distances() {
        let m = TriMesh::new(
            vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(9.0, 9.0, 9.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let d = Dijkstra::new(&m).unwrap();
        let f = d
            .distances(&[Source::Vertex(0)], &SolveOptions::default())
            .unwrap();
        assert_eq!(f[0], 0.0);
        assert!((f[1] - 1.0).abs() < 1e-15);
        assert!((f[2] - 2f64.sqrt()).abs() < 1e-15);
        assert!(f[3].is_infinite());
        assert!(d
            .distances(&[Source::Vertex(7)], &SolveOptions::default())
            .is_err());
        assert!(d.distances(&[], &SolveOptions::default()).is_err());
    }
}
