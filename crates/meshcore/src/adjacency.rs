//! Vertex adjacency (the one-ring of every vertex) from a mesh's triangles.

use crate::TriMesh;

/// Vertex adjacency of a mesh's triangle edges in CSR form (neighbours sorted, unique): the
/// one-ring of the curvature fits, the spike test and Taubin smoothing.
#[derive(Debug, Clone)]
pub struct VertexAdjacency {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl VertexAdjacency {
    /// Builds the adjacency of the triangle edges of `mesh`.
    pub fn new(mesh: &TriMesh) -> Self {
        let n = mesh.n_vertices();
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n];
        for t in mesh.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b {
                    lists[a as usize].push(b);
                    lists[b as usize].push(a);
                }
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut neighbours = Vec::new();
        offsets.push(0);
        for mut l in lists {
            l.sort_unstable();
            l.dedup();
            neighbours.extend_from_slice(&l);
            offsets.push(neighbours.len() as u32);
        }
        Self {
            offsets,
            neighbours,
        }
    }

    /// Neighbours of vertex `v`.
    pub fn neighbours(&self, v: u32) -> &[u32] {
        let a = self.offsets[v as usize] as usize;
        let b = self.offsets[v as usize + 1] as usize;
        &self.neighbours[a..b]
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The neighbours of every vertex, in vertex order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.offsets
            .windows(2)
            .map(|w| &self.neighbours[w[0] as usize..w[1] as usize])
    }
}
