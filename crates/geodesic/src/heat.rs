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

#![allow(clippy::needless_range_loop)] // index loops over parallel per-vertex arrays

use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source, TriMesh};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::sparse::{SparseColMat, Triplet};
use faer::Side;
use glam::DVec3;

/// Heat-method geodesic distance.
///
/// Smooth and fast per source once prepared (two sparse triangular solve pairs and two linear
/// passes over the faces), but only an approximation: the error shrinks slowly with refinement
/// and is largest near the source and at the cut locus. Unreachable vertices (components
/// without a source, and vertices touched by no non-degenerate face) get `f64::INFINITY`.
#[derive(Debug)]
pub struct HeatMethod {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Per face: `N × e_i / (2A)` for each corner `i` (gradient of the hat functions); zero for
    /// degenerate faces.
    grad_basis: Vec<[DVec3; 3]>,
    /// Per face: half cotangents of the angles at its corners (0 for degenerate faces).
    half_cot: Vec<[f64; 3]>,
    /// Component of each vertex (faces connected through shared vertices, degenerate faces
    /// ignored); `u32::MAX` for vertices touched by no non-degenerate face.
    component: Vec<u32>,
    /// Pinned vertex of each component.
    pins: Vec<u32>,
    /// Number of vertices per component.
    comp_size: Vec<usize>,
    /// Heat time step `t`.
    t: f64,
    heat: Llt<usize, f64>,
    /// Heat matrix with zero Dirichlet conditions on boundary vertices (meshes with boundary:
    /// the heat flow is the average of the Neumann and Dirichlet solutions, as recommended by
    /// Crane et al. and done by libigl).
    heat_dirichlet: Option<Llt<usize, f64>>,
    /// Boundary vertices (edges with one face).
    is_boundary: Vec<bool>,
    poisson: Llt<usize, f64>,
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
        let mut grad_basis = Vec::with_capacity(tris.len());
        let mut half_cot = Vec::with_capacity(tris.len());
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
        let mut lap: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(tris.len() * 6);
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
                grad_basis.push([DVec3::ZERO; 3]);
                half_cot.push([0.0; 3]);
                continue;
            }
            let nu = nrm / dbl_area;
            let corners = [(i, pi), (j, pj), (k, pk)];
            let mut gb = [DVec3::ZERO; 3];
            let mut hc = [0.0; 3];
            for c in 0..3 {
                let (_, p0) = corners[c];
                let (_, p1) = corners[(c + 1) % 3];
                let (_, p2) = corners[(c + 2) % 3];
                // Edge opposite corner c, oriented along the face winding.
                gb[c] = nu.cross(p2 - p1) / dbl_area;
                let (u, w) = (p1 - p0, p2 - p0);
                hc[c] = 0.5 * u.dot(w) / dbl_area;
            }
            for c in 0..3 {
                let (a, b) = (corners[(c + 1) % 3].0, corners[(c + 2) % 3].0);
                let wgt = hc[c];
                // Lower triangle only (row >= col).
                lap.push(Triplet::new(a.max(b), a.min(b), -wgt));
                lap.push(Triplet::new(a, a, wgt));
                lap.push(Triplet::new(b, b, wgt));
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
            grad_basis.push(gb);
            half_cot.push(hc);
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

        // Heat matrix M + tL; untouched vertices get an identity row.
        let mut heat_trip: Vec<Triplet<usize, usize, f64>> = lap
            .iter()
            .map(|e| Triplet::new(e.row, e.col, t * e.val))
            .collect();
        // Poisson matrix: L without the rows/columns of pinned and untouched vertices.
        let mut pois_trip: Vec<Triplet<usize, usize, f64>> = lap
            .into_iter()
            .filter(|e| !is_pin[e.row] && !is_pin[e.col])
            .collect();
        for v in 0..n {
            if touched[v] {
                heat_trip.push(Triplet::new(v, v, mass[v]));
            } else {
                heat_trip.push(Triplet::new(v, v, 1.0));
            }
            if is_pin[v] || !touched[v] {
                pois_trip.push(Triplet::new(v, v, 1.0));
            }
        }
        let factor_of = |trip: &[Triplet<usize, usize, f64>], what: &str| {
            let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, trip).map_err(|e| {
                GeodesicError::Numerical(format!("building the {what} matrix: {e:?}"))
            })?;
            m.sp_cholesky(Side::Lower).map_err(|e| {
                GeodesicError::Numerical(format!(
                    "Cholesky factorisation of the {what} matrix failed ({e:?}); \
                     the mesh probably has near-degenerate faces"
                ))
            })
        };
        // Boundary vertices: endpoints of edges used by exactly one non-degenerate face.
        let mut edge_count: std::collections::HashMap<(u32, u32), u32> =
            std::collections::HashMap::with_capacity(tris.len() * 2);
        for (f, t3) in tris.iter().enumerate() {
            if half_cot[f] == [0.0; 3] && grad_basis[f] == [DVec3::ZERO; 3] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t3[k], t3[(k + 1) % 3]);
                *edge_count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        let mut is_boundary = vec![false; n];
        for (&(a, b), &c) in &edge_count {
            if c == 1 {
                is_boundary[a as usize] = true;
                is_boundary[b as usize] = true;
            }
        }
        let heat_dirichlet = if is_boundary.iter().any(|&b| b) {
            let mut trip: Vec<Triplet<usize, usize, f64>> = heat_trip
                .iter()
                .filter(|e| !is_boundary[e.row] && !is_boundary[e.col])
                .copied()
                .collect();
            for v in 0..n {
                if is_boundary[v] {
                    trip.push(Triplet::new(v, v, 1.0));
                }
            }
            Some(factor_of(&trip, "Dirichlet heat")?)
        } else {
            None
        };
        let heat = factor_of(&heat_trip, "heat")?;
        let poisson = factor_of(&pois_trip, "Poisson")?;
        Ok(Self {
            positions: pos.to_vec(),
            triangles: tris.to_vec(),
            grad_basis,
            half_cot,
            component,
            pins,
            comp_size,
            t,
            heat,
            heat_dirichlet,
            is_boundary,
            poisson,
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
                    crate::dijkstra::seeds(&self.positions, &self.triangles, &[*s])?;
                    let t = self.triangles[sp.face as usize];
                    for k in 0..3 {
                        out.push((t[k], sp.bary[k].max(0.0)));
                    }
                }
            }
        }
        Ok(out)
    }
}

impl GeodesicSolver for HeatMethod {
    fn method(&self) -> Method {
        Method::Heat
    }
    fn n_vertices(&self) -> usize {
        self.positions.len()
    }
    fn distances(
        &self,
        sources: &[Source],
        opts: &SolveOptions,
    ) -> Result<Vec<f64>, GeodesicError> {
        let cut = match opts.max_distance {
            Some(c) if c.is_nan() || c <= 0.0 => return Err(GeodesicError::InvalidCutoff(c)),
            Some(c) => c,
            None => f64::INFINITY,
        };
        let n = self.positions.len();
        let weights = self.source_weights(sources)?;
        // 1. Heat flow.
        let mut u = vec![0.0f64; n];
        for &(v, w) in &weights {
            if self.component[v as usize] != u32::MAX {
                u[v as usize] += w;
            }
        }
        let u0 = if self.heat_dirichlet.is_some() {
            u.clone()
        } else {
            Vec::new()
        };
        self.heat
            .solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut u, n, 1));
        if let Some(hd) = &self.heat_dirichlet {
            let mut ud = u0;
            for (x, &b) in ud.iter_mut().zip(&self.is_boundary) {
                if b {
                    *x = 0.0;
                }
            }
            hd.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut ud, n, 1));
            for ((x, y), &b) in u.iter_mut().zip(&ud).zip(&self.is_boundary) {
                *x = 0.5 * (*x + if b { 0.0 } else { *y });
            }
        }
        // 2-3. Normalised gradient and its integrated divergence (right-hand side -div X).
        let mut rhs = vec![0.0f64; n];
        for (f, t) in self.triangles.iter().enumerate() {
            let gb = &self.grad_basis[f];
            let [i, j, k] = t.map(|v| v as usize);
            let g = u[i] * gb[0] + u[j] * gb[1] + u[k] * gb[2];
            let gl = g.length();
            if gl.is_nan() || gl <= 0.0 {
                continue;
            }
            let x = -g / gl;
            let hc = &self.half_cot[f];
            let (pi, pj, pk) = (self.positions[i], self.positions[j], self.positions[k]);
            // div at i: cot_k (e_ij . X) + cot_j (e_ik . X), with half cotangents.
            let (xij, xjk, xki) = ((pj - pi).dot(x), (pk - pj).dot(x), (pi - pk).dot(x));
            rhs[i] -= hc[2] * xij - hc[1] * xki;
            rhs[j] -= hc[0] * xjk - hc[2] * xij;
            rhs[k] -= hc[1] * xki - hc[0] * xjk;
        }
        // Project onto the range of L (zero sum per component), then pin.
        let nc = self.pins.len();
        let mut sum = vec![0.0f64; nc];
        for v in 0..n {
            let c = self.component[v];
            if c != u32::MAX {
                sum[c as usize] += rhs[v];
            }
        }
        for v in 0..n {
            let c = self.component[v];
            if c != u32::MAX {
                rhs[v] -= sum[c as usize] / self.comp_size[c as usize] as f64;
            } else {
                rhs[v] = 0.0;
            }
        }
        for &p in &self.pins {
            rhs[p as usize] = 0.0;
        }
        self.poisson
            .solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1));
        let phi = rhs;
        // Shift each component so that the smallest source value is zero.
        let mut offset = vec![f64::INFINITY; nc];
        for s in sources {
            let (val, c) = match *s {
                Source::Vertex(v) => (phi[v as usize], self.component[v as usize]),
                Source::Point(sp) => {
                    let t = self.triangles[sp.face as usize];
                    let val = (0..3).map(|k| sp.bary[k] * phi[t[k] as usize]).sum::<f64>();
                    let c = t
                        .iter()
                        .map(|&v| self.component[v as usize])
                        .find(|&c| c != u32::MAX)
                        .unwrap_or(u32::MAX);
                    (val, c)
                }
            };
            if c != u32::MAX && val < offset[c as usize] {
                offset[c as usize] = val;
            }
        }
        let mut dist = vec![f64::INFINITY; n];
        for v in 0..n {
            let c = self.component[v];
            if c != u32::MAX && offset[c as usize].is_finite() {
                let d = (phi[v] - offset[c as usize]).max(0.0);
                if d <= cut {
                    dist[v] = d;
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

    #[test]
    fn flat_disc_with_boundary_is_finite_and_close() {
        let n = 12;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let idx = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                t.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
            }
        }
        let m = TriMesh::new(p, t).unwrap();
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
