//! Per-vertex principal curvatures by local quadric fitting at a chosen scale, shape index,
//! curvedness and Taubin smoothing (for curvature only).
//!
//! Sign convention: curvatures are positive where the surface bends away from its normal, so a
//! sphere with outward normals has `k1 = k2 = +1/R` and a shape index of `+1` (a cap, like the
//! nose tip); the same sphere with inward normals (reversed winding) has `-1/R` and `-1` (a cup).

#![allow(clippy::needless_range_loop)] // Dense small linear algebra reads best with indices.

use meshcore::{DVec3, TriMesh};
use rayon::prelude::*;

/// Principal curvatures and directions at one vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curvature {
    /// Maximum principal curvature (`k1 >= k2`), in 1 / mesh units.
    pub k1: f64,
    /// Minimum principal curvature.
    pub k2: f64,
    /// Unit tangent direction of `k1`.
    pub d1: DVec3,
    /// Unit tangent direction of `k2`.
    pub d2: DVec3,
    /// Unit normal used for the fit (area-weighted vertex normal).
    pub normal: DVec3,
}

impl Curvature {
    /// Mean curvature `(k1 + k2) / 2`.
    pub fn mean(&self) -> f64 {
        0.5 * (self.k1 + self.k2)
    }

    /// Gaussian curvature `k1 k2`.
    pub fn gaussian(&self) -> f64 {
        self.k1 * self.k2
    }

    /// Shape index in `[-1, 1]` (see [`shape_index`]).
    pub fn shape_index(&self) -> f64 {
        shape_index(self.k1, self.k2)
    }

    /// Curvedness (see [`curvedness`]).
    pub fn curvedness(&self) -> f64 {
        curvedness(self.k1, self.k2)
    }
}

/// Koenderink's shape index `S = (2/pi) atan((k1 + k2) / (k1 - k2))` with `k1 >= k2` (the order
/// of the arguments does not matter): `+1` cap, `+0.5` ridge, `0` saddle, `-0.5` rut, `-1` cup.
/// Umbilic points get `+-1` by the sign of the mean curvature, and `0` when both are zero.
pub fn shape_index(k1: f64, k2: f64) -> f64 {
    let (a, b) = if k1 >= k2 { (k1, k2) } else { (k2, k1) };
    let s = a + b;
    let d = a - b;
    if d <= 1e-12 * (a.abs() + b.abs()) {
        return if s > 0.0 {
            1.0
        } else if s < 0.0 {
            -1.0
        } else {
            0.0
        };
    }
    std::f64::consts::FRAC_2_PI * (s / d).atan()
}

/// Curvedness `sqrt((k1^2 + k2^2) / 2)`.
pub fn curvedness(k1: f64, k2: f64) -> f64 {
    (0.5 * (k1 * k1 + k2 * k2)).sqrt()
}

/// Options of [`vertex_curvatures`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureOptions {
    /// Fitting radius (Euclidean, over the vertices reachable through edges within the ball), in
    /// mesh units.
    pub radius: f64,
    /// Minimum number of neighbours of a fit; the neighbourhood grows by edge rings beyond the
    /// radius until it has that many (at least 5).
    pub min_neighbours: usize,
}

impl CurvatureOptions {
    /// Fitting at `radius` with at least 12 neighbours.
    pub fn with_radius(radius: f64) -> Self {
        Self {
            radius,
            min_neighbours: 12,
        }
    }
}

/// The vertex adjacency of the curvature fits and the detector (it lives in `meshcore`).
pub use meshcore::VertexAdjacency;

/// Reusable breadth-first collector of the vertices within a Euclidean ball reachable through
/// edges inside the ball.
#[derive(Debug, Clone)]
pub(crate) struct BallCollector {
    stamp: Vec<u32>,
    generation: u32,
    /// Vertices reached but outside the ball (with their offsets), kept for ring growth.
    outside: Vec<(u32, DVec3)>,
}

impl BallCollector {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            stamp: vec![0; n],
            generation: 0,
            outside: Vec::new(),
        }
    }

    /// Vertices (including `v`) connected to `v` through vertices within `radius` of `center`;
    /// if fewer than `min_count`, whole edge rings are added until there are enough (or the
    /// component is exhausted). `offsets` gets each one's position minus `center`, in the
    /// same order.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn collect(
        &mut self,
        adj: &[&[u32]],
        pos: &[DVec3],
        v: u32,
        center: DVec3,
        radius: f64,
        min_count: usize,
        out: &mut Vec<u32>,
        offsets: &mut Vec<DVec3>,
    ) {
        out.clear();
        offsets.clear();
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.generation = 1;
        }
        let g = self.generation;
        let r2 = radius * radius;
        // `out` and `offsets` are the queue: a vertex is appended when it is reached inside
        // the ball and expanded in that order.
        out.push(v);
        offsets.push(pos[v as usize] - center);
        self.stamp[v as usize] = g;
        let outside = &mut self.outside;
        outside.clear();
        let mut head = 0;
        while head < out.len() {
            let u = out[head];
            head += 1;
            for &w in adj[u as usize] {
                let s = &mut self.stamp[w as usize];
                if *s == g {
                    continue;
                }
                *s = g;
                let d = pos[w as usize] - center;
                if d.length_squared() <= r2 {
                    out.push(w);
                    offsets.push(d);
                } else {
                    outside.push((w, d));
                }
            }
        }
        // Ring growth when the ball is too small for a stable fit.
        while out.len() < min_count && !outside.is_empty() {
            let ring = std::mem::take(outside);
            for &(u, d) in &ring {
                out.push(u);
                offsets.push(d);
            }
            for &(u, _) in &ring {
                for &w in adj[u as usize] {
                    if self.stamp[w as usize] != g {
                        self.stamp[w as usize] = g;
                        outside.push((w, pos[w as usize] - center));
                    }
                }
            }
        }
    }
}

/// A right-handed orthonormal tangent basis `(u, w)` of the plane orthogonal to unit `n`.
pub(crate) fn tangent_basis(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.6 {
        DVec3::X
    } else if n.y.abs() < 0.6 {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let u = (a - n * n.dot(a)).normalize();
    let w = n.cross(u);
    (u, w)
}

/// Principal curvatures of every vertex by weighted least-squares fitting of
/// `h = a x^2 + b xy + c y^2 + d x + e y + f` in the local frame of the vertex normal, over the
/// vertices within `options.radius` (reached through edges). Weights `(1 - r^2/R^2)^2`.
///
/// Vertices whose neighbourhood cannot support a fit (isolated vertices, fewer than 5
/// neighbours, degenerate layouts) get zero curvatures with arbitrary orthonormal directions.
pub fn vertex_curvatures(mesh: &TriMesh, options: &CurvatureOptions) -> Vec<Curvature> {
    let normals = mesh.vertex_normals();
    let adj = VertexAdjacency::new(mesh);
    vertex_curvatures_with(mesh, &normals, &adj, options)
}

/// [`vertex_curvatures`] with precomputed unit normals and adjacency.
pub fn vertex_curvatures_with(
    mesh: &TriMesh,
    normals: &[DVec3],
    adj: &VertexAdjacency,
    options: &CurvatureOptions,
) -> Vec<Curvature> {
    let all: Vec<u32> = (0..mesh.n_vertices() as u32).collect();
    curvatures_at(mesh, normals, adj, options, &all)
}

/// [`vertex_curvatures_with`] at the given vertices only, in their order (each value is the
/// one the whole-mesh computation gives at that vertex: the fit still uses every neighbour).
/// Vertex ids out of range get zero curvatures.
pub fn curvatures_at(
    mesh: &TriMesh,
    normals: &[DVec3],
    adj: &VertexAdjacency,
    options: &CurvatureOptions,
    vertices: &[u32],
) -> Vec<Curvature> {
    let pos = mesh.positions();
    // The neighbour lists once, indexed here (the walks of the balls read them millions of
    // times).
    let adj: Vec<&[u32]> = adj.iter().collect();
    fit_balls(pos, &adj, options, vertices, |v| {
        Some((v, *pos.get(v as usize)?, *normals.get(v as usize)?))
    })
}

/// The vertices of a mesh thinned to one per occupied cube of side `spacing` (cubes of the
/// grid through the origin): the first vertex (lowest id) of each cube stands for it.
#[derive(Debug, Clone, PartialEq)]
pub struct CubeThinning {
    kept: Vec<u32>,
    cube_of: Vec<u32>,
}

impl CubeThinning {
    /// Thins `positions` to one vertex per occupied cube of side `spacing` (positive and
    /// finite; otherwise every vertex is kept). A `TriMesh`'s positions are finite; a
    /// non-finite coordinate would get the saturated integer cube index (NaN: 0).
    pub fn new(positions: &[DVec3], spacing: f64) -> Self {
        if !(spacing > 0.0 && spacing.is_finite()) {
            let all: Vec<u32> = (0..positions.len() as u32).collect();
            return Self {
                kept: all.clone(),
                cube_of: all,
            };
        }
        let mut cubes = std::collections::HashMap::new();
        let mut kept = Vec::new();
        let cube_of = positions
            .iter()
            .enumerate()
            .map(|(v, p)| {
                let c = (*p / spacing).floor();
                *cubes
                    .entry((c.x as i64, c.y as i64, c.z as i64))
                    .or_insert_with(|| {
                        kept.push(v as u32);
                        kept.len() as u32 - 1
                    })
            })
            .collect();
        Self { kept, cube_of }
    }

    /// The kept vertices (the cubes' first vertices), in increasing order.
    pub fn kept(&self) -> &[u32] {
        &self.kept
    }

    /// For every vertex thinned, the index in [`CubeThinning::kept`] of its cube's vertex.
    pub fn cube_of(&self) -> &[u32] {
        &self.cube_of
    }
}

/// [`curvatures_at`] on a dense mesh, each fit over the mesh's vertices thinned to one per
/// cube ([`CubeThinning`] of its positions): the kept vertices within `options.radius` of the
/// vertex, reached through cubes joined by an edge of the mesh (two cubes are joined when an
/// edge joins two of their vertices) inside the ball, with the vertex's own position and
/// normal at the centre. A fit then costs about `(radius / spacing)^2` neighbours whatever the
/// mesh's density (at a spacing of a sixth of the radius, about 110). Vertex ids out of range,
/// or beyond the thinning (of another mesh), get zero curvatures.
pub fn curvatures_at_thinned(
    mesh: &TriMesh,
    normals: &[DVec3],
    adj: &VertexAdjacency,
    options: &CurvatureOptions,
    vertices: &[u32],
    thin: &CubeThinning,
) -> Vec<Curvature> {
    let pos = mesh.positions();
    let kept_pos: Vec<DVec3> = thin
        .kept
        .iter()
        .map(|&v| pos.get(v as usize).copied().unwrap_or(DVec3::ZERO))
        .collect();
    // The edges between cubes, once each way, sorted: the neighbour lists of the thinned mesh.
    let cube_of = &thin.cube_of;
    let mut joins: Vec<(u32, u32)> = adj
        .iter()
        .enumerate()
        .filter_map(|(v, nb)| Some((*cube_of.get(v)?, nb)))
        .flat_map(|(a, nb)| {
            nb.iter().filter_map(move |&w| {
                let b = *cube_of.get(w as usize)?;
                (a != b).then_some((a, b))
            })
        })
        .collect();
    joins.sort_unstable();
    joins.dedup();
    let mut start = vec![0usize; thin.kept.len() + 1];
    for &(a, _) in &joins {
        start[a as usize + 1] += 1;
    }
    for i in 0..thin.kept.len() {
        start[i + 1] += start[i];
    }
    let targets: Vec<u32> = joins.iter().map(|&(_, b)| b).collect();
    let thin_adj: Vec<&[u32]> = start.windows(2).map(|w| &targets[w[0]..w[1]]).collect();
    fit_balls(&kept_pos, &thin_adj, options, vertices, |v| {
        Some((
            *thin.cube_of.get(v as usize)?,
            *pos.get(v as usize)?,
            *normals.get(v as usize)?,
        ))
    })
}

/// The fits of [`curvatures_at`] over the graph `adj` of the points `pos`: for each vertex,
/// `site` gives the point its ball walk starts from, the centre and the unit normal (`None`,
/// or a zero normal, gives zero curvatures). Vertices are independent: in parallel, each
/// result computed exactly as on one thread (the ball collector's state only marks visited
/// points), collected in vertex order.
fn fit_balls(
    pos: &[DVec3],
    adj: &[&[u32]],
    options: &CurvatureOptions,
    vertices: &[u32],
    site: impl Fn(u32) -> Option<(u32, DVec3, DVec3)> + Sync,
) -> Vec<Curvature> {
    let n = pos.len();
    let radius = options.radius.max(0.0);
    let min_count = options.min_neighbours.max(5) + 1;
    vertices
        .par_iter()
        .copied()
        .with_min_len(256)
        .map_init(
            || (BallCollector::new(n), Vec::new(), Vec::new()),
            |(ball, nb, offsets), v| {
                let Some((s, p, nrm)) = site(v) else {
                    return flat(DVec3::Z);
                };
                if nrm == DVec3::ZERO {
                    return flat(DVec3::Z);
                }
                ball.collect(adj, pos, s, p, radius, min_count, nb, offsets);
                fit_vertex(nrm, offsets, radius).unwrap_or_else(|| flat(nrm))
            },
        )
        .collect()
}

fn flat(n: DVec3) -> Curvature {
    let (u, w) = tangent_basis(n);
    Curvature {
        k1: 0.0,
        k2: 0.0,
        d1: u,
        d2: w,
        normal: n,
    }
}

/// Quadric fit at one vertex from the offsets of its neighbours (the vertex itself among them);
/// heights measured along `-n` so that convex (outward-normal) caps have positive curvature.
fn fit_vertex(n: DVec3, offsets: &[DVec3], radius: f64) -> Option<Curvature> {
    if offsets.len() < 6 {
        return None;
    }
    let (u, w) = tangent_basis(n);
    // Effective radius: at least the farthest neighbour (ring growth may exceed `radius`).
    let mut r2max: f64 = radius * radius;
    for &d in offsets {
        r2max = r2max.max((d - n * d.dot(n)).length_squared());
    }
    let r2max = r2max * 1.0001 + 1e-300;
    let mut ata = [[0.0; 6]; 6];
    let mut atb = [0.0; 6];
    let mut edge = [0.0; 6];
    let scale = r2max.sqrt();
    for &d in offsets {
        // Normalised coordinates for conditioning.
        let x = d.dot(u) / scale;
        let y = d.dot(w) / scale;
        let h = -d.dot(n) / scale;
        let r2 = x * x + y * y;
        let wt = (1.0 - r2 * scale * scale / r2max).max(0.0).powi(2) + 1e-3;
        // The row is [x^2, xy, y^2, x, y, 1]: each entry of `ata` sums `wt * row[i] * row[j]`
        // (left to right); those with the constant term are `wt * row[i]` (times 1, exactly),
        // the same summands in the same order for `ata[i][5]` and `ata[5][i]`: summed once.
        let row = [x * x, x * y, y * y, x, y];
        let wr = row.map(|r| wt * r);
        for i in 0..5 {
            for j in 0..5 {
                ata[i][j] += wr[i] * row[j];
            }
            edge[i] += wr[i];
            atb[i] += wr[i] * h;
        }
        edge[5] += wt;
        atb[5] += wt * h;
    }
    for i in 0..6 {
        ata[i][5] = edge[i];
        ata[5][i] = edge[i];
    }
    let c = meshcore::linalg::solve_sym_tol(ata, atb, 1e-13)?;
    // Back to mesh units: h = s * H(x/s, y/s): second derivatives divide by s, first unchanged.
    let fxx = 2.0 * c[0] / scale;
    let fxy = c[1] / scale;
    let fyy = 2.0 * c[2] / scale;
    let fx = c[3];
    let fy = c[4];
    let g = 1.0 + fx * fx + fy * fy;
    let sg = g.sqrt();
    // First and second fundamental forms of the graph (x, y, h(x, y)).
    let (e1, f1, g1) = (1.0 + fx * fx, fx * fy, 1.0 + fy * fy);
    let (l2, m2, n2) = (fxx / sg, fxy / sg, fyy / sg);
    // Shape operator W = I^{-1} II.
    let det = e1 * g1 - f1 * f1;
    let w11 = (g1 * l2 - f1 * m2) / det;
    let w12 = (g1 * m2 - f1 * n2) / det;
    let w21 = (e1 * m2 - f1 * l2) / det;
    let w22 = (e1 * n2 - f1 * m2) / det;
    let tr = w11 + w22;
    let dt = w11 * w22 - w12 * w21;
    let disc = (0.25 * tr * tr - dt).max(0.0).sqrt();
    let k1 = 0.5 * tr + disc;
    let k2 = 0.5 * tr - disc;
    // Eigenvector of W for k1 in parameter space.
    let ev = |k: f64| -> (f64, f64) {
        let a = (w12, k - w11);
        let b = (k - w22, w21);
        if a.0 * a.0 + a.1 * a.1 >= b.0 * b.0 + b.1 * b.1 {
            a
        } else {
            b
        }
    };
    let (a, b) = ev(k1);
    // Tangent of the graph: X_x = u - fx n, X_y = w - fy n (heights along -n).
    let t1 = (u - n * fx) * a + (w - n * fy) * b;
    let nn = n;
    let d1 = if t1.length_squared() > 1e-24 && disc > 1e-12 * (k1.abs() + k2.abs() + 1e-300) {
        (t1 - nn * t1.dot(nn)).normalize_or_zero()
    } else {
        DVec3::ZERO
    };
    let d1 = if d1 == DVec3::ZERO { u } else { d1 };
    let d2 = nn.cross(d1);
    Some(Curvature {
        k1,
        k2,
        d1,
        d2,
        normal: nn,
    })
}

/// Taubin lambda/mu smoothing (umbrella operator with uniform weights), returning a smoothed
/// copy; meant for curvature estimation only, the descriptor uses the original positions.
/// Typical values: `lambda = 0.5`, `mu = -0.53`, 5-10 iterations. Boundary vertices are moved
/// too (along their one-sided umbrella), which shrinks open borders slightly.
pub fn taubin_smooth(mesh: &TriMesh, iterations: usize, lambda: f64, mu: f64) -> TriMesh {
    let adj = VertexAdjacency::new(mesh);
    let mut pos = mesh.positions().to_vec();
    let mut next = pos.clone();
    for _ in 0..iterations {
        for factor in [lambda, mu] {
            for v in 0..pos.len() {
                let nb = adj.neighbours(v as u32);
                if nb.is_empty() {
                    next[v] = pos[v];
                    continue;
                }
                let mut c = DVec3::ZERO;
                for &q in nb {
                    c += pos[q as usize];
                }
                c /= nb.len() as f64;
                next[v] = pos[v] + factor * (c - pos[v]);
            }
            std::mem::swap(&mut pos, &mut next);
        }
    }
    // Positions stay finite (convex combinations with bounded factors), so this cannot fail; keep
    // the original mesh if it ever did.
    TriMesh::new(pos, mesh.triangles().to_vec()).unwrap_or_else(|_| mesh.clone())
}
