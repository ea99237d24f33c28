//! Isolines of piecewise-linear scalar fields on triangle meshes.
//!
//! A field `U` known at the vertices and linear inside each face has straight isoline segments
//! in every face it crosses. [`isolines`] extracts them for many levels at once and assembles
//! them into ordered, consistently oriented polylines ([`Isoline`]):
//!
//! * **Symbolic perturbation** (specification §1.2): a vertex is "above" level `c` iff
//!   `U(v) >= c`. An edge is crossed iff its two ends disagree, so every face is crossed by 0 or
//!   exactly 2 of its edges, never 1 or 3, and values exactly at a level need no special case.
//! * **One point per crossed edge** (§1.3): the crossing point is computed once per unique edge
//!   with its endpoints ordered `lo < hi`, so both incident faces share bit-identical points.
//! * **Assembly through the crossed-edge graph** (§1.4): nodes are crossed edges, links are
//!   faces. Open polylines start and end on boundary edges (outer border, hole rims, faces
//!   skipped for non-finite values, non-manifold edges); the rest are closed loops.
//! * **Orientation** (§1.5): each polyline runs along `n_f x grad U` (higher values on the
//!   right when the normal points up), decided by a majority vote over its segments.
//! * **Many levels** (§1.6): faces are bucketed by the levels they cross, so the cost is
//!   `O(|F| log L + output)`.
//!
//! Faces with a non-finite vertex value are skipped (they behave like holes).

use glam::DVec3;
use meshcore::{Topology, TriMesh};
use thiserror::Error;

/// Errors of isoline extraction.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LevelCurveError {
    /// The field does not have one value per vertex.
    #[error("field has {got} values but the mesh has {expected} vertices")]
    FieldLength {
        /// Number of mesh vertices.
        expected: usize,
        /// Number of field values given.
        got: usize,
    },
    /// A level is NaN or infinite.
    #[error("level {index} is not finite ({value})")]
    NonFiniteLevel {
        /// Index of the level in the list given.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The topology was not built for this mesh.
    #[error("topology has {topo_faces} faces but the mesh has {mesh_faces}")]
    TopologyMismatch {
        /// Faces of the mesh.
        mesh_faces: usize,
        /// Faces known to the topology.
        topo_faces: usize,
    },
    /// A non-positive or non-finite step for uniform levels.
    #[error("invalid level step {0}: must be positive and finite")]
    InvalidStep(f64),
}

/// One connected piece of an isoline: an ordered, oriented polyline.
#[derive(Debug, Clone, PartialEq)]
pub struct Isoline {
    /// Ordered points (a closed curve does not repeat its first point).
    pub points: Vec<DVec3>,
    /// Mesh edge `(lo, hi)` (`lo < hi`) on which each point lies.
    pub edge_of: Vec<(u32, u32)>,
    /// Position of each point on its edge, from `lo` (0) to `hi` (1).
    pub t_of: Vec<f64>,
    /// Face crossed by segment `j` (`points[j] -> points[j+1]`); for a closed curve the last
    /// entry is the closing segment (so `face_of.len() == points.len()`), for an open one
    /// `face_of.len() == points.len() - 1`.
    pub face_of: Vec<u32>,
    /// True for a closed loop.
    pub closed: bool,
    /// Index of the level (in the list given to [`isolines`]) this piece belongs to.
    pub level_index: usize,
}

impl Isoline {
    /// Number of segments.
    pub fn n_segments(&self) -> usize {
        self.face_of.len()
    }

    /// End points of segment `j` (wrapping for the closing segment of a closed curve).
    pub fn segment(&self, j: usize) -> (DVec3, DVec3) {
        let a = self.points[j];
        let b = self.points[(j + 1) % self.points.len()];
        (a, b)
    }

    /// Total length of the polyline (closing segment included for a closed curve).
    pub fn length(&self) -> f64 {
        (0..self.n_segments())
            .map(|j| {
                let (a, b) = self.segment(j);
                (b - a).length()
            })
            .sum()
    }
}

/// Gradient of the linear interpolant of `u` on the triangle `p` (specification §0).
///
/// Returns zero for a degenerate triangle. The result lies in the plane of the triangle and
/// satisfies `<g, p1 - p0> = u1 - u0`, `<g, p2 - p0> = u2 - u0`.
pub fn face_gradient(p: [DVec3; 3], u: [f64; 3]) -> DVec3 {
    let cross = (p[1] - p[0]).cross(p[2] - p[0]);
    let a2 = cross.length_squared();
    if a2 <= 0.0 || !a2.is_finite() {
        return DVec3::ZERO;
    }
    // n x e_i / (2A) with n = cross / |cross| gives cross x e_i / |cross|^2.
    let e0 = p[2] - p[1];
    let e1 = p[0] - p[2];
    let e2 = p[1] - p[0];
    (u[0] * cross.cross(e0) + u[1] * cross.cross(e1) + u[2] * cross.cross(e2)) / a2
}

/// Indices `i` in `1..=i_max` of the uniform levels `i * step` crossing a face whose vertex
/// values span `[min, max]`, i.e. with `min < i * step <= max` (specification §1.6).
///
/// Returns an empty range when none does (or when `min`/`max` are not finite).
pub fn uniform_level_range(min: f64, max: f64, step: f64, i_max: u32) -> std::ops::Range<u32> {
    if !(min.is_finite() && max.is_finite()) || step <= 0.0 || min >= max {
        return 0..0;
    }
    let mut lo = (min / step).floor() + 1.0;
    let mut hi = (max / step).floor();
    // Guard the floors against rounding by re-testing the end indices.
    if (lo - 1.0) * step > min {
        lo -= 1.0;
    }
    if lo * step <= min {
        lo += 1.0;
    }
    if (hi + 1.0) * step <= max {
        hi += 1.0;
    }
    if hi * step > max {
        hi -= 1.0;
    }
    let lo = lo.max(1.0);
    let hi = hi.min(i_max as f64);
    if hi < lo {
        return 0..0;
    }
    (lo as u32)..(hi as u32 + 1)
}

/// Uniform levels `step, 2 step, ..., n step`.
pub fn uniform_levels(step: f64, n: u32) -> Result<Vec<f64>, LevelCurveError> {
    if !(step.is_finite() && step > 0.0) {
        return Err(LevelCurveError::InvalidStep(step));
    }
    Ok((1..=n).map(|i| i as f64 * step).collect())
}

/// Isolines of the per-vertex field `field` at every level of `levels`.
///
/// Returns one `Vec<Isoline>` per level, in the order of `levels` (a level crossing nothing
/// gets an empty vector). Within a level, pieces come in a deterministic order (open pieces
/// first, by first crossed edge met in face order; then closed loops).
pub fn isolines(
    mesh: &TriMesh,
    topo: &Topology,
    field: &[f64],
    levels: &[f64],
) -> Result<Vec<Vec<Isoline>>, LevelCurveError> {
    check_inputs(mesh, topo, field)?;
    if let Some((index, &value)) = levels.iter().enumerate().find(|(_, l)| !l.is_finite()) {
        return Err(LevelCurveError::NonFiniteLevel { index, value });
    }
    // Sorted level order for bucketing.
    let mut order: Vec<usize> = (0..levels.len()).collect();
    order.sort_by(|&a, &b| levels[a].total_cmp(&levels[b]).then(a.cmp(&b)));
    let sorted: Vec<f64> = order.iter().map(|&i| levels[i]).collect();

    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); levels.len()];
    for (f, tri) in mesh.triangles().iter().enumerate() {
        let u = [
            field[tri[0] as usize],
            field[tri[1] as usize],
            field[tri[2] as usize],
        ];
        if !u.iter().all(|x| x.is_finite()) {
            continue;
        }
        let min = u[0].min(u[1]).min(u[2]);
        let max = u[0].max(u[1]).max(u[2]);
        // Levels c with min < c <= max.
        let start = sorted.partition_point(|&c| c <= min);
        let end = sorted.partition_point(|&c| c <= max);
        for &li in &order[start..end] {
            buckets[li].push(f as u32);
        }
    }
    let mut ex = Extractor::new(mesh, topo, field);
    Ok(buckets
        .iter()
        .enumerate()
        .map(|(li, faces)| ex.extract(levels[li], li, faces))
        .collect())
}

/// Isolines at the uniform levels `step, 2 step, ..., n_levels step` (index `i - 1` of the
/// result holds level `i`); same as [`isolines`] with [`uniform_levels`] but bucketed in O(1)
/// per face.
pub fn isolines_uniform(
    mesh: &TriMesh,
    topo: &Topology,
    field: &[f64],
    step: f64,
    n_levels: u32,
) -> Result<Vec<Vec<Isoline>>, LevelCurveError> {
    check_inputs(mesh, topo, field)?;
    if !(step.is_finite() && step > 0.0) {
        return Err(LevelCurveError::InvalidStep(step));
    }
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); n_levels as usize];
    for (f, tri) in mesh.triangles().iter().enumerate() {
        let u = [
            field[tri[0] as usize],
            field[tri[1] as usize],
            field[tri[2] as usize],
        ];
        let min = u[0].min(u[1]).min(u[2]);
        let max = u[0].max(u[1]).max(u[2]);
        for i in uniform_level_range(min, max, step, n_levels) {
            buckets[i as usize - 1].push(f as u32);
        }
    }
    let mut ex = Extractor::new(mesh, topo, field);
    Ok(buckets
        .iter()
        .enumerate()
        .map(|(li, faces)| ex.extract((li + 1) as f64 * step, li, faces))
        .collect())
}

fn check_inputs(mesh: &TriMesh, topo: &Topology, field: &[f64]) -> Result<(), LevelCurveError> {
    if field.len() != mesh.n_vertices() {
        return Err(LevelCurveError::FieldLength {
            expected: mesh.n_vertices(),
            got: field.len(),
        });
    }
    if topo.face_edges().len() != mesh.n_faces() {
        return Err(LevelCurveError::TopologyMismatch {
            mesh_faces: mesh.n_faces(),
            topo_faces: topo.face_edges().len(),
        });
    }
    Ok(())
}

const NONE: u32 = u32::MAX;

/// Reusable scratch space for the extraction of one level at a time.
struct Extractor<'a> {
    mesh: &'a TriMesh,
    topo: &'a Topology,
    field: &'a [f64],
    /// Node index of each mesh edge for the current level (NONE when not crossed).
    node_of_edge: Vec<u32>,
    diag: f64,
}

struct Node {
    edge: u32,
    point: DVec3,
    t: f64,
}

impl<'a> Extractor<'a> {
    fn new(mesh: &'a TriMesh, topo: &'a Topology, field: &'a [f64]) -> Self {
        Self {
            mesh,
            topo,
            field,
            node_of_edge: vec![NONE; topo.edges().len()],
            diag: mesh.bbox().diagonal(),
        }
    }

    fn extract(&mut self, c: f64, level_index: usize, faces: &[u32]) -> Vec<Isoline> {
        if faces.is_empty() {
            return Vec::new();
        }
        let pos = self.mesh.positions();
        let tris = self.mesh.triangles();
        let field = self.field;
        let mut nodes: Vec<Node> = Vec::with_capacity(faces.len());
        // Links: (node a, node b, face).
        let mut links: Vec<[u32; 3]> = Vec::with_capacity(faces.len());
        for &f in faces {
            let fe = self.topo.face_edges()[f as usize];
            let tri = tris[f as usize];
            let mut ends = [NONE; 2];
            let mut k_found = 0;
            for k in 0..3 {
                let a = tri[k];
                let b = tri[(k + 1) % 3];
                let sa = field[a as usize] >= c;
                let sb = field[b as usize] >= c;
                if sa == sb {
                    continue;
                }
                let e = fe[k];
                let mut id = self.node_of_edge[e as usize];
                if id == NONE {
                    let (lo, hi) = (a.min(b), a.max(b));
                    let (ul, uh) = (field[lo as usize], field[hi as usize]);
                    let t = ((c - ul) / (uh - ul)).clamp(0.0, 1.0);
                    let pl = pos[lo as usize];
                    let ph = pos[hi as usize];
                    id = nodes.len() as u32;
                    nodes.push(Node {
                        edge: e,
                        point: pl + t * (ph - pl),
                        t,
                    });
                    self.node_of_edge[e as usize] = id;
                }
                if k_found < 2 {
                    ends[k_found] = id;
                }
                k_found += 1;
            }
            // Under the boolean rule k_found is 0 or 2; 0 cannot happen for bucketed faces.
            if k_found == 2 && ends[0] != ends[1] {
                links.push([ends[0], ends[1], f]);
            }
        }
        // Reset scratch.
        for n in &nodes {
            self.node_of_edge[n.edge as usize] = NONE;
        }
        // CSR adjacency node -> links.
        let nn = nodes.len();
        let mut off = vec![0u32; nn + 1];
        for l in &links {
            off[l[0] as usize + 1] += 1;
            off[l[1] as usize + 1] += 1;
        }
        for i in 0..nn {
            off[i + 1] += off[i];
        }
        let mut fill = off.clone();
        let mut adj = vec![0u32; off[nn] as usize];
        for (li, l) in links.iter().enumerate() {
            for &n in &l[..2] {
                adj[fill[n as usize] as usize] = li as u32;
                fill[n as usize] += 1;
            }
        }
        let degree = |n: u32| off[n as usize + 1] - off[n as usize];
        let mut used = vec![false; links.len()];
        let mut out = Vec::new();

        // Walk from node `start` through link `first`; returns (node list, face list).
        let walk = |start: u32, first: u32, used: &mut [bool]| -> (Vec<u32>, Vec<u32>, bool) {
            let mut ns = vec![start];
            let mut fs = Vec::new();
            let mut cur = start;
            let mut link = first;
            loop {
                used[link as usize] = true;
                let l = links[link as usize];
                fs.push(l[2]);
                let nxt = if l[0] == cur { l[1] } else { l[0] };
                if nxt == start {
                    return (ns, fs, true);
                }
                ns.push(nxt);
                if degree(nxt) != 2 {
                    return (ns, fs, false);
                }
                let a = off[nxt as usize] as usize;
                let next_link = if adj[a] == link { adj[a + 1] } else { adj[a] };
                if used[next_link as usize] {
                    return (ns, fs, false);
                }
                cur = nxt;
                link = next_link;
            }
        };

        // Open curves first, from their end (or branch) nodes; then the closed loops left.
        let ends = (0..nn as u32).filter(|&n| degree(n) != 2);
        for n in ends.chain(0..nn as u32) {
            for k in off[n as usize]..off[n as usize + 1] {
                let l = adj[k as usize];
                if used[l as usize] {
                    continue;
                }
                let (ns, fs, closed) = walk(n, l, &mut used);
                out.push(self.build(&nodes, ns, fs, closed, level_index));
            }
        }
        out
    }

    fn build(
        &self,
        nodes: &[Node],
        mut ns: Vec<u32>,
        mut fs: Vec<u32>,
        closed: bool,
        level_index: usize,
    ) -> Isoline {
        // Orientation by majority vote: segment direction against n_f x grad U.
        let mut votes: i64 = 0;
        for (j, &f) in fs.iter().enumerate() {
            let a = nodes[ns[j] as usize].point;
            let b = nodes[ns[(j + 1) % ns.len()] as usize].point;
            let tri = self.mesh.triangles()[f as usize];
            let p = self.mesh.face_corners(f);
            let u = tri.map(|v| self.field[v as usize]);
            let g = face_gradient(p, u);
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let s = (b - a).dot(cross.cross(g));
            if s > 0.0 {
                votes += 1;
            } else if s < 0.0 {
                votes -= 1;
            }
        }
        if votes < 0 {
            if closed {
                // Keep the start point; reverse the cyclic order.
                ns[1..].reverse();
                fs.reverse();
            } else {
                ns.reverse();
                fs.reverse();
            }
        }
        // Remove consecutive duplicates (exact-level vertices), keeping topology.
        let tol = 1e-12 * self.diag;
        let mut keep_n: Vec<u32> = Vec::with_capacity(ns.len());
        let mut keep_f: Vec<u32> = Vec::with_capacity(fs.len());
        for (j, &n) in ns.iter().enumerate() {
            if let Some(&last) = keep_n.last() {
                let d = (nodes[n as usize].point - nodes[last as usize].point).length();
                if d <= tol {
                    // Drop the zero-length segment ending here (face fs[j-1]) and keep the
                    // later point (so an open curve still ends on its boundary edge), except
                    // for the first point of an open curve (which starts on one).
                    if closed || keep_n.len() > 1 {
                        keep_n.pop();
                        keep_n.push(n);
                    }
                    keep_f.pop();
                    if j < fs.len() {
                        keep_f.push(fs[j]);
                    }
                    continue;
                }
            }
            keep_n.push(n);
            if j < fs.len() {
                keep_f.push(fs[j]);
            }
        }
        if closed && keep_n.len() > 1 {
            let first = nodes[keep_n[0] as usize].point;
            let last = nodes[*keep_n.last().unwrap_or(&keep_n[0]) as usize].point;
            if (first - last).length() <= tol {
                // Drop the last point and the zero-length closing segment: the segment that
                // ended at the dropped point now closes the loop.
                keep_n.pop();
                keep_f.pop();
            }
        }
        let points = keep_n.iter().map(|&n| nodes[n as usize].point).collect();
        let edge_of = keep_n
            .iter()
            .map(|&n| {
                let e = self.topo.edges()[nodes[n as usize].edge as usize].v;
                (e[0], e[1])
            })
            .collect();
        let t_of = keep_n.iter().map(|&n| nodes[n as usize].t).collect();
        Isoline {
            points,
            edge_of,
            t_of,
            face_of: keep_f,
            closed,
            level_index,
        }
    }
}
