use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source, TriMesh};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Dijkstra's shortest paths on the edge graph, the paper's approximation.
///
/// Its error does not shrink with refinement (it measures paths along edges). A surface-point
/// source starts from the three corners of its face with their straight-line distances.
#[derive(Debug, Clone)]
pub struct Dijkstra {
    positions: Vec<glam::DVec3>,
    triangles: Vec<[u32; 3]>,
    offsets: Vec<u32>,
    neighbors: Vec<(u32, f64)>,
}

#[derive(PartialEq)]
struct Item(f64, u32);
impl Eq for Item {}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then_with(|| o.1.cmp(&self.1))
    }
}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
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

/// Validates sources and turns them into (vertex, initial distance) seeds.
pub(crate) fn seeds(
    positions: &[glam::DVec3],
    triangles: &[[u32; 3]],
    sources: &[Source],
) -> Result<Vec<(u32, f64)>, GeodesicError> {
    if sources.is_empty() {
        return Err(GeodesicError::NoSource);
    }
    let mut out = Vec::new();
    for s in sources {
        match *s {
            Source::Vertex(v) => {
                if v as usize >= positions.len() {
                    return Err(GeodesicError::SourceOutOfRange {
                        vertex: v,
                        vertices: positions.len(),
                    });
                }
                out.push((v, 0.0));
            }
            Source::Point(sp) => {
                let tri =
                    triangles
                        .get(sp.face as usize)
                        .ok_or(meshcore::MeshError::FaceOutOfRange {
                            face: sp.face,
                            faces: triangles.len(),
                        })?;
                let b = sp.bary;
                if !b.is_finite() || b.min_element() < -1e-9 || (b.element_sum() - 1.0).abs() > 1e-9
                {
                    return Err(meshcore::MeshError::InvalidBarycentric(b.x, b.y, b.z).into());
                }
                let p = b.x * positions[tri[0] as usize]
                    + b.y * positions[tri[1] as usize]
                    + b.z * positions[tri[2] as usize];
                for &v in tri {
                    out.push((v, (positions[v as usize] - p).length()));
                }
            }
        }
    }
    Ok(out)
}

impl GeodesicSolver for Dijkstra {
    fn method(&self) -> Method {
        Method::Dijkstra
    }
    fn n_vertices(&self) -> usize {
        self.positions.len()
    }
    fn distances(
        &self,
        sources: &[Source],
        opts: &SolveOptions,
    ) -> Result<Vec<f64>, GeodesicError> {
        let cut = opts.cutoff()?;
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
        if cut.is_finite() {
            dist.iter_mut()
                .filter(|d| **d > cut)
                .for_each(|d| *d = f64::INFINITY);
        }
        Ok(dist)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

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
