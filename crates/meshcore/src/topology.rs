use crate::TriMesh;
use std::collections::HashMap;

/// Marker for "no face" in [`Edge::faces`].
pub const NO_FACE: u32 = u32::MAX;

/// A unique undirected edge with its incident faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// Endpoints, `v[0] < v[1]`.
    pub v: [u32; 2],
    /// The first two incident faces; `faces[1] == NO_FACE` on a boundary edge.
    pub faces: [u32; 2],
    /// Total number of incident faces (more than 2 on a non-manifold edge).
    pub n_faces: u32,
}

impl Edge {
    /// True if exactly one face uses the edge.
    pub fn is_boundary(&self) -> bool {
        self.n_faces == 1
    }
    /// True if more than two faces use the edge.
    pub fn is_non_manifold(&self) -> bool {
        self.n_faces > 2
    }
}

/// Adjacency of a [`TriMesh`], built once and read many times (read-only: every field is
/// behind an accessor, so it always describes the mesh it was built from).
///
/// Edge ids are assigned in order of first appearance when scanning faces `0..m` and their
/// corners `(0,1), (1,2), (2,0)`, so they are deterministic for a given mesh.
#[derive(Debug, Clone)]
pub struct Topology {
    /// CSR offsets into `vertex_face_list`, length `n_vertices + 1`.
    vertex_face_offsets: Vec<u32>,
    vertex_face_list: Vec<u32>,
    /// Unique edges.
    edges: Vec<Edge>,
    /// For each face, the edge id of its sides `(c0,c1), (c1,c2), (c2,c0)`.
    face_edges: Vec<[u32; 3]>,
    /// Boundary loops as ordered vertex lists (each loop listed once, not closed explicitly).
    boundary_loops: Vec<Vec<u32>>,
    /// Component id of each vertex (faces connected through shared vertices); isolated vertices
    /// get their own component.
    vertex_component: Vec<u32>,
    /// Number of connected components (isolated vertices included).
    n_components: usize,
    /// Number of vertices used by no face.
    isolated_vertices: usize,
    /// Edges used by more than two faces.
    non_manifold_edges: Vec<u32>,
    /// Vertices whose incident faces do not form a single fan (bow-ties).
    non_manifold_vertices: Vec<u32>,
    /// Interior edges traversed in the same direction by both faces (orientation conflicts).
    inconsistent_edges: Vec<u32>,
}

impl Topology {
    /// Builds the adjacency of `mesh` in O(n + m) expected time.
    pub fn new(mesh: &TriMesh) -> Self {
        let n = mesh.n_vertices();
        let tris = mesh.triangles();
        // Vertex -> faces (CSR).
        let mut counts = vec![0u32; n + 1];
        for t in tris {
            for &v in t {
                counts[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut fill = counts;
        let mut list = vec![0u32; offsets[n] as usize];
        for (f, t) in tris.iter().enumerate() {
            for &v in t {
                list[fill[v as usize] as usize] = f as u32;
                fill[v as usize] += 1;
            }
        }

        // Unique edges. An edge met before was met as a side of an earlier face around its lower
        // end (those faces are listed in increasing order), or as an earlier side of this face:
        // a look-up in that fan, no hashing.
        let mut edges: Vec<Edge> = Vec::with_capacity(tris.len() * 3 / 2 + 1);
        let mut face_edges: Vec<[u32; 3]> = Vec::with_capacity(tris.len());
        let mut inconsistent = Vec::new();
        // Directed orientation of each edge in its first face: true if traversed lo->hi.
        let mut first_dir: Vec<bool> = Vec::with_capacity(edges.capacity());
        for (f, t) in tris.iter().enumerate() {
            let mut fe = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                let forward = a < b;
                let same = |s: &[u32; 3], j: usize| {
                    let (x, y) = (s[j], s[(j + 1) % 3]);
                    (x.min(y), x.max(y)) == key
                };
                let lo = key.0 as usize;
                let fan = &list[offsets[lo] as usize..offsets[lo + 1] as usize];
                let earlier = fan
                    .iter()
                    .take_while(|&&g| (g as usize) < f)
                    .find_map(|&g| {
                        let s = &tris[g as usize];
                        (0..3)
                            .find(|&j| same(s, j))
                            .map(|j| face_edges[g as usize][j])
                    })
                    .or_else(|| (0..k).find(|&j| same(t, j)).map(|j| fe[j]));
                let id = earlier.unwrap_or_else(|| {
                    edges.push(Edge {
                        v: [key.0, key.1],
                        faces: [NO_FACE, NO_FACE],
                        n_faces: 0,
                    });
                    first_dir.push(forward);
                    (edges.len() - 1) as u32
                });
                let e = &mut edges[id as usize];
                match e.n_faces {
                    0 => e.faces[0] = f as u32,
                    1 => {
                        e.faces[1] = f as u32;
                        if first_dir[id as usize] == forward && a != b {
                            inconsistent.push(id);
                        }
                    }
                    _ => {}
                }
                e.n_faces += 1;
                fe[k] = id;
            }
            face_edges.push(fe);
        }
        let non_manifold_edges: Vec<u32> = edges
            .iter()
            .enumerate()
            .filter(|(_, e)| e.is_non_manifold())
            .map(|(i, _)| i as u32)
            .collect();
        inconsistent.retain(|&e| !edges[e as usize].is_non_manifold());

        let (vertex_component, n_components) = vertex_components(mesh);
        let isolated_vertices = (0..n).filter(|&v| offsets[v + 1] == offsets[v]).count();

        let mut topo = Self {
            vertex_face_offsets: offsets,
            vertex_face_list: list,
            edges,
            face_edges,
            boundary_loops: Vec::new(),
            vertex_component,
            n_components,
            isolated_vertices,
            non_manifold_edges,
            non_manifold_vertices: Vec::new(),
            inconsistent_edges: inconsistent,
        };
        topo.boundary_loops = topo.compute_boundary_loops(mesh);
        topo.non_manifold_vertices = topo.compute_non_manifold_vertices(mesh);
        topo
    }

    /// Unique edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// For each face, the edge id of its sides `(c0,c1), (c1,c2), (c2,c0)`.
    pub fn face_edges(&self) -> &[[u32; 3]] {
        &self.face_edges
    }

    /// Boundary loops as ordered vertex lists (each loop listed once, not closed explicitly).
    pub fn boundary_loops(&self) -> &[Vec<u32>] {
        &self.boundary_loops
    }

    /// Component id of each vertex (faces connected through shared vertices); isolated vertices
    /// get their own component.
    pub fn vertex_component(&self) -> &[u32] {
        &self.vertex_component
    }

    /// Number of connected components (isolated vertices included).
    pub fn n_components(&self) -> usize {
        self.n_components
    }

    /// Number of vertices used by no face.
    pub fn isolated_vertices(&self) -> usize {
        self.isolated_vertices
    }

    /// Edges used by more than two faces.
    pub fn non_manifold_edges(&self) -> &[u32] {
        &self.non_manifold_edges
    }

    /// Vertices whose incident faces do not form a single fan (bow-ties).
    pub fn non_manifold_vertices(&self) -> &[u32] {
        &self.non_manifold_vertices
    }

    /// Interior edges traversed in the same direction by both faces (orientation conflicts).
    pub fn inconsistent_edges(&self) -> &[u32] {
        &self.inconsistent_edges
    }

    /// Faces incident to vertex `v`.
    pub fn vertex_faces(&self, v: u32) -> &[u32] {
        let a = self.vertex_face_offsets[v as usize] as usize;
        let b = self.vertex_face_offsets[v as usize + 1] as usize;
        &self.vertex_face_list[a..b]
    }

    /// Boundary edges (exactly one incident face).
    pub fn boundary_edges(&self) -> impl Iterator<Item = u32> + '_ {
        self.edges
            .iter()
            .enumerate()
            .filter(|(_, e)| e.is_boundary())
            .map(|(i, _)| i as u32)
    }

    /// The face on the other side of edge `e` from face `f` (`None` on a boundary or
    /// non-manifold edge).
    pub fn opposite_face(&self, e: u32, f: u32) -> Option<u32> {
        let edge = &self.edges[e as usize];
        if edge.n_faces != 2 {
            return None;
        }
        if edge.faces[0] == f {
            Some(edge.faces[1])
        } else if edge.faces[1] == f {
            Some(edge.faces[0])
        } else {
            None
        }
    }

    /// True if every edge has one or two faces, every vertex is a single fan and the faces are
    /// consistently oriented.
    pub fn is_oriented_manifold(&self) -> bool {
        self.non_manifold_edges.is_empty()
            && self.non_manifold_vertices.is_empty()
            && self.inconsistent_edges.is_empty()
    }

    /// Vertices of each component, in increasing vertex order; components in order of their
    /// smallest vertex.
    pub fn components(&self) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.n_components];
        for (v, &c) in self.vertex_component.iter().enumerate() {
            out[c as usize].push(v as u32);
        }
        out
    }

    fn compute_boundary_loops(&self, mesh: &TriMesh) -> Vec<Vec<u32>> {
        // Directed boundary half-edges, following the winding of their face.
        let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut starts: Vec<u32> = Vec::new();
        for e in self.boundary_edges() {
            let edge = &self.edges[e as usize];
            let t = mesh.triangles()[edge.faces[0] as usize];
            let (a, b) = (0..3)
                .map(|k| (t[k], t[(k + 1) % 3]))
                .find(|&(a, b)| a.min(b) == edge.v[0] && a.max(b) == edge.v[1])
                .unwrap_or((edge.v[0], edge.v[1]));
            next.entry(a).or_default().push(b);
            starts.push(a);
        }
        starts.sort_unstable();
        for list in next.values_mut() {
            list.sort_unstable();
        }
        let mut loops = Vec::new();
        for s in starts {
            if next.get(&s).is_none_or(|l| l.is_empty()) {
                continue;
            }
            let mut lp = vec![s];
            let mut cur = s;
            while let Some(n) = next.get_mut(&cur).and_then(|list| list.pop()) {
                if n == s {
                    break;
                }
                lp.push(n);
                cur = n;
                if lp.len() > self.edges.len() {
                    break;
                }
            }
            loops.push(lp);
        }
        loops
    }

    fn compute_non_manifold_vertices(&self, mesh: &TriMesh) -> Vec<u32> {
        // A vertex is a single fan if its incident faces are connected through edges that
        // contain the vertex.
        let tris = mesh.triangles();
        let mut out = Vec::new();
        let mut seen: Vec<u32> = Vec::new();
        let mut stack: Vec<u32> = Vec::new();
        for v in 0..mesh.n_vertices() as u32 {
            let faces = self.vertex_faces(v);
            if faces.len() <= 1 {
                continue;
            }
            seen.clear();
            stack.clear();
            stack.push(faces[0]);
            seen.push(faces[0]);
            while let Some(f) = stack.pop() {
                for &e in &self.face_edges[f as usize] {
                    let edge = &self.edges[e as usize];
                    if edge.v[0] != v && edge.v[1] != v {
                        continue;
                    }
                    for &g in &edge.faces {
                        if g != NO_FACE && !seen.contains(&g) && faces.contains(&g) {
                            seen.push(g);
                            stack.push(g);
                        }
                    }
                }
            }
            if seen.len() < faces.len() && tris[faces[0] as usize].contains(&v) {
                out.push(v);
            }
        }
        out
    }
}

/// The connected component of each vertex (faces sharing a vertex are connected; a vertex in
/// no face is a component of its own), numbered in order of each component's first vertex, and
/// the number of components: what [`Topology::new`] stores, without the edges and loops.
pub fn vertex_components(mesh: &TriMesh) -> (Vec<u32>, usize) {
    let n = mesh.n_vertices();
    // Union-find over face corners.
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for t in mesh.triangles() {
        for &v in &t[1..] {
            // Re-find both roots every time: a union may have changed t[0]'s root.
            let r0 = find(&mut parent, t[0]);
            let r = find(&mut parent, v);
            if r != r0 {
                let (lo, hi) = (r.min(r0), r.max(r0));
                parent[hi as usize] = lo;
            }
        }
    }
    let mut comp_of_root = vec![u32::MAX; n];
    let mut n_components = 0u32;
    let mut vertex_component = vec![0u32; n];
    for v in 0..n as u32 {
        let r = find(&mut parent, v) as usize;
        if comp_of_root[r] == u32::MAX {
            comp_of_root[r] = n_components;
            n_components += 1;
        }
        vertex_component[v as usize] = comp_of_root[r];
    }
    (vertex_component, n_components as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn grid(nx: usize, ny: usize) -> TriMesh {
        crate::shapes::grid(nx, ny, crate::shapes::Diagonals::Uniform, |i, j| {
            DVec3::new(i as f64, j as f64, 0.0)
        })
        .unwrap()
    }

    #[test]
    fn grid_topology() {
        let m = grid(4, 3);
        let t = Topology::new(&m);
        assert_eq!(t.n_components, 1);
        assert_eq!(t.boundary_loops.len(), 1);
        assert_eq!(t.boundary_loops[0].len(), 2 * (4 + 3));
        assert!(t.is_oriented_manifold());
        // Euler: V - E + F = 1 for a disc.
        assert_eq!(
            m.n_vertices() as i64 - t.edges.len() as i64 + m.n_faces() as i64,
            1
        );
    }

    #[test]
    fn components_survive_root_changes() {
        // A face whose corners come in decreasing order changes its first corner's root in the
        // middle of the face: a stale root used to split even a single triangle in two.
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let t = Topology::new(&TriMesh::new(p, vec![[2, 1, 0]]).unwrap());
        assert_eq!(t.n_components, 1);
        // A grid with reversed corner order is one component too.
        let (pos, tris) = grid(7, 5).into_parts();
        let tris: Vec<[u32; 3]> = tris.into_iter().map(|[a, b, c]| [c, b, a]).rev().collect();
        let t = Topology::new(&TriMesh::new(pos, tris).unwrap());
        assert_eq!(t.n_components, 1);
    }

    /// Edge ids by first appearance, counted with a hash map (the plain statement of the rule).
    fn reference_edges(tris: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<[u32; 3]>) {
        let mut map: HashMap<(u32, u32), u32> = HashMap::new();
        let mut ends = Vec::new();
        let face_edges = tris
            .iter()
            .map(|t| {
                [0, 1, 2].map(|k| {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let key = (a.min(b), a.max(b));
                    *map.entry(key).or_insert_with(|| {
                        ends.push([key.0, key.1]);
                        (ends.len() - 1) as u32
                    })
                })
            })
            .collect();
        (ends, face_edges)
    }

    #[test]
    fn edge_ids_follow_first_appearance() {
        // Shuffled faces and corners, repeated corners, non-manifold edges, duplicate faces.
        let mut state = 7u64;
        let mut next = |m: u32| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) % m as u64) as u32
        };
        let (pos, mut tris) = grid(9, 7).into_parts();
        for i in (1..tris.len()).rev() {
            tris.swap(i, next(i as u32 + 1) as usize);
        }
        for t in tris.iter_mut() {
            t.rotate_left(next(3) as usize);
        }
        let nv = pos.len() as u32;
        for _ in 0..20 {
            let t = [next(nv), next(nv), next(nv)];
            tris.push(t);
            tris.push([t[0], t[0], t[1]]);
        }
        let dup = tris[3];
        tris.push(dup);
        let m = TriMesh::new(pos, tris).unwrap();
        let topo = Topology::new(&m);
        let (ends, face_edges) = reference_edges(m.triangles());
        assert_eq!(topo.face_edges, face_edges);
        assert_eq!(topo.edges.iter().map(|e| e.v).collect::<Vec<_>>(), ends);
        for (f, fe) in topo.face_edges.iter().enumerate() {
            for &e in fe {
                let edge = &topo.edges[e as usize];
                assert!(edge.faces[0] as usize <= f);
            }
        }
    }

    #[test]
    fn detects_problems() {
        let mut m = grid(2, 2);
        // Flip one face: orientation conflict.
        let (p, mut tr) = m.clone().into_parts();
        tr[0].swap(1, 2);
        let t = Topology::new(&TriMesh::new(p.clone(), tr.clone()).unwrap());
        assert!(!t.inconsistent_edges.is_empty());
        // Two separate triangles sharing one vertex: bow-tie.
        let q = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            -DVec3::X,
            -DVec3::Y,
            DVec3::new(5.0, 5.0, 5.0),
        ];
        m = TriMesh::new(q, vec![[0, 1, 2], [0, 3, 4]]).unwrap();
        let t = Topology::new(&m);
        assert_eq!(t.non_manifold_vertices, vec![0]);
        assert_eq!(t.n_components, 2); // the isolated vertex 5 counts
        assert_eq!(t.isolated_vertices, 1);
        assert_eq!(t.boundary_loops.len(), 2);
        // Three faces on one edge.
        let q = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, -DVec3::Y];
        m = TriMesh::new(q, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        let t = Topology::new(&m);
        assert_eq!(t.non_manifold_edges.len(), 1);
    }
}
