//! Heat method (Crane, Weischedel & Wardetzky 2013) with faer's sparse Cholesky.
//!
//! 1. Heat flow: `(M + t L) u = δ` (lumped mass `M`, positive semi-definite cotan Laplacian
//!    `L`, `t = h²` with `h` the mean edge length, `δ` the source spread by barycentric weights).
//! 2. Normalised field `X = -∇u / |∇u|` per face.
//! 3. Poisson: `L φ = -div X`. `L` is singular (constants on each component), so instead of the
//!    common `L + εM` shift (which biases the result and makes the error grow with mesh size)
//!    one vertex per component is pinned (its row and column replaced by the identity) and the
//!    right-hand side is projected onto the range of `L` (zero sum per component). This gives
//!    the exact solution of the singular, consistent system up to a constant per component,
//!    which is then fixed so that the distance at the sources is zero.
//!
//! Both factorisations are computed once in [`HeatMethod::new`] and reused by every solve.
//! On meshes with boundary the heat flow is the mean of the Neumann and zero-Dirichlet
//! solutions (Crane et al., section 3.2; libigl does the same), a third factorisation.
//!
//! Per-solve cost (see `docs/bench-geodesic-heat.md`): the matrices share one fill-reducing
//! ordering, and every per-solve array lives in that order, so the triangular solves
//! (`heat/factor.rs`, hand-written over faer's factor) need no permutation; the gradient and
//! divergence use two precomputed vectors per face and no geometry; a solve allocates its two
//! working vectors (one becomes the result) and nothing else. Results equal the textbook
//! formulation to rounding (`tests/heat_accuracy.rs` keeps a reference implementation).

#![allow(clippy::needless_range_loop)] // index loops over parallel per-vertex arrays

mod factor;

use crate::solver::{seeds, Field};
use crate::{GeodesicError, Method, Source, TriMesh};
use factor::Factor;
use faer::sparse::{Pair, Triplet};
use glam::DVec3;

/// Per-face data of the gradient and divergence operators (internal vertex numbering).
///
/// With `a_c = ½ n × e_c` (`n` the unit normal, `e_c` the edge opposite corner `c` along the
/// winding), the hat-function gradients are `∇φ_c = a_c / A` and `a_0 + a_1 + a_2 = 0`. The
/// heat gradient is therefore parallel to `g = (u_1 - u_0) a_1 + (u_2 - u_0) a_2`, the unit
/// field is `X = -g / |g|`, and the integrated divergence of `X` at corner `c` (the cotan
/// formula of Crane et al.) is `-A ∇φ_c · X = -a_c · X`; the Poisson right-hand side
/// `-div X` gets `a_c · X` per corner. No areas, cotangents or positions are needed per solve.
#[derive(Debug, Clone, Copy)]
struct FaceOp {
    /// Internal indices of the corners.
    v: [u32; 3],
    /// `a_1 = ½ n × e_1` (see above).
    a1: DVec3,
    /// `a_2 = ½ n × e_2`.
    a2: DVec3,
}

/// Heat-method geodesic distance.
///
/// Smooth and fast per source once prepared (two sparse triangular solve pairs and one linear
/// pass over the faces), but only an approximation: the error shrinks slowly with refinement
/// and is largest near the source and at the cut locus. Unreachable vertices (components
/// without a source, and vertices touched by no non-degenerate face) get `f64::INFINITY`.
#[derive(Debug)]
pub struct HeatMethod {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Internal (fill-reducing) index of each original vertex; every per-solve array is in
    /// internal order, so the factors are used without permuting.
    internal: Vec<u32>,
    /// Non-degenerate faces, sorted by their smallest internal corner (memory locality).
    faces: Vec<FaceOp>,
    /// Component of each internal vertex (faces connected through shared vertices, degenerate
    /// faces ignored); `u32::MAX` for vertices touched by no non-degenerate face.
    component: Vec<u32>,
    /// Pinned vertex (internal index) of each component: its smallest original vertex.
    pins: Vec<u32>,
    /// Number of vertices per component.
    comp_size: Vec<usize>,
    /// Heat time step `t`.
    t: f64,
    /// Cholesky factor of `M + tL` (internal numbering).
    heat: Factor,
    /// Factor of the heat matrix with zero Dirichlet conditions on boundary vertices (meshes with
    /// boundary: the heat flow is the average of the Neumann and Dirichlet solutions, as
    /// recommended by Crane et al. and done by libigl).
    heat_dirichlet: Option<Factor>,
    /// Boundary vertices (edges with one face), internal numbering.
    is_boundary: Vec<bool>,
    /// Factor of `L` with the pinned vertices' rows and columns replaced by the identity.
    poisson: Factor,
}

impl HeatMethod {
    /// Prepares the solver: cotan Laplacian, lumped mass matrix and the Cholesky factorisations
    /// of `M + tL` and of the pinned `L`, with `t = h²` (`h` the mean edge length).
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        let h = mesh.mean_edge_length();
        Self::with_time_factor(mesh, 1.0, h)
    }

    /// Like [`HeatMethod::new`] with `t = factor * h²`; `h` is the edge length to use (normally
    /// the mean edge length of the mesh).
    pub fn with_time_factor(mesh: &TriMesh, factor: f64, h: f64) -> Result<Self, GeodesicError> {
        let t = factor * h * h;
        if !(t.is_finite() && t > 0.0) {
            return Err(GeodesicError::Numerical(format!(
                "heat time step t = {factor} * {h}^2 is not a positive finite number"
            )));
        }
        let pos = mesh.positions();
        let tris = mesh.triangles();
        let n = pos.len();
        if u32::try_from(n).is_err() {
            return Err(GeodesicError::Numerical(format!(
                "{n} vertices are too many for the heat method's 32-bit indices"
            )));
        }
        // Per non-degenerate face (original numbering): corners and a_1, a_2.
        let mut ops: Vec<FaceOp> = Vec::with_capacity(tris.len());
        let mut mass = vec![0.0f64; n];
        // Union-find over non-degenerate faces.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut touched = vec![false; n];
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        // Cotan Laplacian, lower triangle (row >= col), original numbering.
        let mut lap: Vec<Triplet<u32, u32, f64>> = Vec::with_capacity(tris.len() * 6);
        // Edges of non-degenerate faces as `min << 32 | max`, for the boundary.
        let mut edges: Vec<u64> = Vec::with_capacity(tris.len() * 3);
        for t3 in tris {
            let [i, j, k] = t3.map(|v| v as usize);
            let (pi, pj, pk) = (pos[i], pos[j], pos[k]);
            let nrm = (pj - pi).cross(pk - pi);
            let dbl_area = nrm.length();
            let scale = (pj - pi)
                .length_squared()
                .max((pk - pj).length_squared())
                .max((pi - pk).length_squared());
            if i == j || j == k || i == k || dbl_area.is_nan() || dbl_area <= 1e-14 * scale {
                continue;
            }
            let nu = nrm / dbl_area;
            let corners = [(i, pi), (j, pj), (k, pk)];
            let mut hc = [0.0; 3];
            for c in 0..3 {
                let (_, p0) = corners[c];
                let (_, p1) = corners[(c + 1) % 3];
                let (_, p2) = corners[(c + 2) % 3];
                let (u, w) = (p1 - p0, p2 - p0);
                hc[c] = 0.5 * u.dot(w) / dbl_area;
            }
            for c in 0..3 {
                let (a, b) = (corners[(c + 1) % 3].0 as u32, corners[(c + 2) % 3].0 as u32);
                let wgt = hc[c];
                lap.push(Triplet::new(a.max(b), a.min(b), -wgt));
                lap.push(Triplet::new(a, a, wgt));
                lap.push(Triplet::new(b, b, wgt));
                edges.push((u64::from(a.min(b)) << 32) | u64::from(a.max(b)));
            }
            for &v in &[i, j, k] {
                mass[v] += dbl_area / 6.0;
                touched[v] = true;
            }
            for &v in &[j, k] {
                let r0 = find(&mut parent, i as u32);
                let r = find(&mut parent, v as u32);
                if r != r0 {
                    let (lo, hi) = (r.min(r0), r.max(r0));
                    parent[hi as usize] = lo;
                }
            }
            // a_c = ½ n × (edge opposite c, along the winding).
            ops.push(FaceOp {
                v: *t3,
                a1: 0.5 * nu.cross(pi - pk),
                a2: 0.5 * nu.cross(pj - pi),
            });
        }
        // Components (numbered in order of their smallest vertex) and pins (that vertex).
        let mut component = vec![u32::MAX; n];
        let mut pins = Vec::new();
        let mut comp_of_root = vec![u32::MAX; n];
        for v in 0..n {
            if !touched[v] {
                continue;
            }
            let r = find(&mut parent, v as u32) as usize;
            if comp_of_root[r] == u32::MAX {
                comp_of_root[r] = pins.len() as u32;
                pins.push(v as u32);
            }
            component[v] = comp_of_root[r];
        }
        let mut comp_size = vec![0usize; pins.len()];
        for &c in &component {
            if c != u32::MAX {
                comp_size[c as usize] += 1;
            }
        }
        let mut is_pin = vec![false; n];
        for &p in &pins {
            is_pin[p as usize] = true;
        }
        // Boundary vertices: endpoints of edges used by exactly one non-degenerate face.
        edges.sort_unstable();
        let mut is_boundary = vec![false; n];
        let mut e = 0;
        while e < edges.len() {
            let mut f = e + 1;
            while f < edges.len() && edges[f] == edges[e] {
                f += 1;
            }
            if f - e == 1 {
                is_boundary[(edges[e] >> 32) as usize] = true;
                is_boundary[(edges[e] & 0xffff_ffff) as usize] = true;
            }
            e = f;
        }
        let has_boundary = is_boundary.iter().any(|&b| b);

        // All matrices share one pattern (the Laplacian's plus the diagonal), hence one
        // symbolic analysis; rows and columns replaced by the identity keep their positions
        // as explicit zeros (dropped again when the factor is copied out).
        let nl = lap.len();
        let idx: Vec<Pair<u32, u32>> = lap
            .iter()
            .map(|e| Pair::new(e.row, e.col))
            .chain((0..n as u32).map(|v| Pair::new(v, v)))
            .collect();
        let pattern = factor::Pattern::new(n, &idx)?;
        // Heat matrix M + tL; untouched vertices get an identity row.
        let mut vals = vec![0.0f64; nl + n];
        for (x, l) in vals.iter_mut().zip(&lap) {
            *x = t * l.val;
        }
        for v in 0..n {
            vals[nl + v] = if touched[v] { mass[v] } else { 1.0 };
        }
        let heat_mat = pattern.matrix(&vals, "heat")?;
        let symbolic = factor::analyse(&heat_mat)?;
        let heat = Factor::new(&symbolic, &heat_mat, "heat")?;
        drop(heat_mat);
        let heat_dirichlet = if has_boundary {
            // Boundary rows and columns become the identity (the diagonal entries come last).
            let mut d = vals.clone();
            for (k, (x, e)) in d.iter_mut().zip(&idx).enumerate() {
                if is_boundary[e.row as usize] || is_boundary[e.col as usize] {
                    *x = if k >= nl { 1.0 } else { 0.0 };
                }
            }
            let m = pattern.matrix(&d, "Dirichlet heat")?;
            Some(Factor::new(&symbolic, &m, "Dirichlet heat")?)
        } else {
            None
        };
        // Poisson matrix: L with the rows/columns of pinned and untouched vertices replaced by
        // the identity.
        for (x, l) in vals.iter_mut().zip(&lap) {
            let (r, c) = (l.row as usize, l.col as usize);
            *x = if is_pin[r] || is_pin[c] { 0.0 } else { l.val };
        }
        for v in 0..n {
            vals[nl + v] = if is_pin[v] || !touched[v] { 1.0 } else { 0.0 };
        }
        let pois_mat = pattern.matrix(&vals, "Poisson")?;
        let poisson = Factor::new(&symbolic, &pois_mat, "Poisson")?;
        drop(pois_mat);

        // Internal numbering = the fill-reducing ordering.
        let (original, internal) = factor::permutation(&symbolic);
        let mut faces = ops;
        for f in faces.iter_mut() {
            f.v = f.v.map(|v| internal[v as usize]);
        }
        faces.sort_by_key(|f| f.v.iter().copied().min().unwrap_or(0));
        let by_internal =
            |x: &[bool]| -> Vec<bool> { original.iter().map(|&v| x[v as usize]).collect() };
        let component_int: Vec<u32> = original.iter().map(|&v| component[v as usize]).collect();
        Ok(Self {
            positions: pos.to_vec(),
            triangles: tris.to_vec(),
            faces,
            component: component_int,
            pins: pins.iter().map(|&p| internal[p as usize]).collect(),
            comp_size,
            t,
            heat,
            heat_dirichlet,
            is_boundary: by_internal(&is_boundary),
            poisson,
            internal,
        })
    }

    /// The heat time step `t` in use.
    pub fn time_step(&self) -> f64 {
        self.t
    }

    /// Source weights: (vertex, weight) pairs, validated.
    fn source_weights(&self, sources: &[Source]) -> Result<Vec<(u32, f64)>, GeodesicError> {
        if sources.is_empty() {
            return Err(GeodesicError::NoSource);
        }
        let n = self.positions.len();
        let mut out = Vec::new();
        for s in sources {
            match *s {
                Source::Vertex(v) => {
                    if v as usize >= n {
                        return Err(GeodesicError::SourceOutOfRange {
                            vertex: v,
                            vertices: n,
                        });
                    }
                    out.push((v, 1.0));
                }
                Source::Point(sp) => {
                    // Validation shared with the other solvers.
                    seeds(&self.positions, &self.triangles, &[*s])?;
                    let t = self.triangles[sp.face as usize];
                    for k in 0..3 {
                        out.push((t[k], sp.bary[k].max(0.0)));
                    }
                }
            }
        }
        Ok(out)
    }

    /// Adds `-div X` of the normalised negative gradient of `u` (internal numbering) to `rhs`.
    fn divergence_of_unit_gradient(&self, u: &[f64], rhs: &mut [f64]) {
        for f in &self.faces {
            let [i, j, k] = f.v.map(|v| v as usize);
            let ui = u[i];
            let mut g = (u[j] - ui) * f.a1 + (u[k] - ui) * f.a2;
            let mut sq = g.length_squared();
            // Far from the source u can be so small that |g|² underflows; the direction is
            // scale invariant, so rescale by the largest component.
            if !(sq > 1e-280 && sq.is_finite()) {
                let m = g.abs().max_element();
                if !(m > 0.0 && m.is_finite()) {
                    continue;
                }
                g /= m;
                sq = g.length_squared();
            }
            let s = 1.0 / sq.sqrt();
            // rhs_c += a_c · X with X = -g/|g| and a_0 = -(a_1 + a_2).
            let (r1, r2) = (f.a1.dot(g) * s, f.a2.dot(g) * s);
            rhs[i] += r1 + r2;
            rhs[j] -= r1;
            rhs[k] -= r2;
        }
    }
}

impl Field for HeatMethod {
    const METHOD: Method = Method::Heat;
    fn positions(&self) -> &[DVec3] {
        &self.positions
    }
    /// Computes the whole field (the heat method cannot stop early).
    fn field(&self, sources: &[Source], _cut: f64) -> Result<Vec<f64>, GeodesicError> {
        let n = self.positions.len();
        let weights = self.source_weights(sources)?;
        // 1. Heat flow (internal numbering). The right-hand side is zero before the smallest
        // internal source index, which the forward substitution skips.
        let mut u = vec![0.0f64; n];
        let mut start = n;
        for &(v, w) in &weights {
            let p = self.internal[v as usize] as usize;
            if self.component[p] != u32::MAX && w != 0.0 {
                u[p] += w;
                start = start.min(p);
            }
        }
        let mut rhs = vec![0.0f64; n];
        if let Some(hd) = &self.heat_dirichlet {
            // Dirichlet solution first, in `rhs` (used as scratch), then averaged into `u`.
            let mut sd = n;
            for p in start..n {
                if u[p] != 0.0 && !self.is_boundary[p] {
                    rhs[p] = u[p];
                    sd = sd.min(p);
                }
            }
            hd.solve_in_place(&mut rhs, sd);
            self.heat.solve_in_place(&mut u, start);
            for ((x, y), &b) in u.iter_mut().zip(rhs.iter_mut()).zip(&self.is_boundary) {
                *x = 0.5 * (*x + if b { 0.0 } else { *y });
                *y = 0.0;
            }
        } else {
            self.heat.solve_in_place(&mut u, start);
        }
        // 2-3. Normalised gradient and its integrated divergence (right-hand side -div X).
        self.divergence_of_unit_gradient(&u, &mut rhs);
        // Project onto the range of L (zero sum per component), then pin.
        let nc = self.pins.len();
        if nc == 1 && self.comp_size[0] == n {
            let mean = rhs.iter().sum::<f64>() / n as f64;
            for r in rhs.iter_mut() {
                *r -= mean;
            }
        } else {
            let mut sum = vec![0.0f64; nc];
            for (r, &c) in rhs.iter().zip(&self.component) {
                if c != u32::MAX {
                    sum[c as usize] += *r;
                }
            }
            for (r, &c) in rhs.iter_mut().zip(&self.component) {
                if c != u32::MAX {
                    *r -= sum[c as usize] / self.comp_size[c as usize] as f64;
                } else {
                    *r = 0.0;
                }
            }
        }
        for &p in &self.pins {
            rhs[p as usize] = 0.0;
        }
        self.poisson.solve_in_place(&mut rhs, 0);
        let phi = rhs;
        // Shift each component so that the smallest source value is zero.
        let mut offset = vec![f64::INFINITY; nc];
        let at = |v: u32| self.internal[v as usize] as usize;
        for s in sources {
            let (val, c) = match *s {
                Source::Vertex(v) => (phi[at(v)], self.component[at(v)]),
                Source::Point(sp) => {
                    let t = self.triangles[sp.face as usize];
                    let val = (0..3).map(|k| sp.bary[k] * phi[at(t[k])]).sum::<f64>();
                    let c = t
                        .iter()
                        .map(|&v| self.component[at(v)])
                        .find(|&c| c != u32::MAX)
                        .unwrap_or(u32::MAX);
                    (val, c)
                }
            };
            if c != u32::MAX && val < offset[c as usize] {
                offset[c as usize] = val;
            }
        }
        // Output in original numbering, reusing the heat buffer.
        let mut dist = u;
        for (d, &p) in dist.iter_mut().zip(&self.internal) {
            let p = p as usize;
            let c = self.component[p];
            *d = f64::INFINITY;
            if c != u32::MAX {
                let o = offset[c as usize];
                if o.is_finite() {
                    *d = (phi[p] - o).max(0.0);
                }
            }
        }
        // A source vertex touched by no face is at distance zero from itself.
        for s in sources {
            if let Source::Vertex(v) = *s {
                dist[v as usize] = 0.0;
            }
        }
        Ok(dist)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GeodesicSolver, SolveOptions};
    use meshcore::shapes::{grid, Diagonals};

    #[test]
    fn flat_disc_with_boundary_is_finite_and_close() {
        let n = 12;
        let idx = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let m = grid(n, n, Diagonals::Uniform, |i, j| {
            DVec3::new(i as f64, j as f64, 0.0)
        })
        .unwrap();
        let h = HeatMethod::new(&m).unwrap();
        assert!(h.heat_dirichlet.is_some());
        for src in [idx(6, 6), idx(0, 3)] {
            let d = h
                .distances(&[Source::Vertex(src)], &SolveOptions::default())
                .unwrap();
            let c = m.position(src);
            for (v, x) in d.iter().enumerate() {
                let e = (m.position(v as u32) - c).length();
                assert!(x.is_finite(), "vertex {v}: {x}");
                assert!((x - e).abs() < 1.5, "vertex {v}: {x} vs {e}");
            }
        }
    }
}
