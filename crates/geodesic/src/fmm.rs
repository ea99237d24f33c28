//! Fast marching on triangulated domains (Kimmel & Sethian 1998) with obtuse-angle unfolding.
//!
//! Every vertex `c` owns a list of *update triangles* `(c, a, b)`: planar triangles in which the
//! arrival time of `c` is computed from the times of `a` and `b` by one of the [`FmmUpdate`]
//! rules (by default a circular front whose curvature is carried from vertex to vertex, valid
//! when the characteristic reaching `c` crosses the segment `ab`). Acute corners give one update triangle, the face itself. An obtuse
//! corner breaks causality (the front may reach `c` before `a` or `b`), so, as in Kimmel-Sethian,
//! the neighbouring faces are unfolded across the opposite edge into the plane of the face until
//! a vertex `w` lands in the *section* of the obtuse angle (the cone bounded by the
//! perpendiculars to `ca` and `cb`); the virtual edge `cw` splits the corner into two acute
//! update triangles `(c, a, w)` and `(c, w, b)`. The unfolded strip contains the segment `cw`,
//! so its (unfolded) length is a real surface path length.

use crate::solver::{seeds, Field, Item};
use crate::{GeodesicError, Method, Source, TriMesh};
use glam::{DVec2, DVec3};
use meshcore::Topology;
use std::collections::BinaryHeap;

/// Maximum number of faces unfolded when looking for the split vertex of one obtuse corner.
const MAX_UNFOLD: usize = 64;

/// A planar triangle `(c, a, b)` in which the time of `c` is updated from `a` and `b`.
#[derive(Debug, Clone, Copy)]
struct UpdTri {
    a: u32,
    b: u32,
    /// Length of `ca` (unfolded length for a virtual edge).
    la: f64,
    /// Length of `cb`.
    lb: f64,
    /// `b - c` in the local frame where `c = 0` and `a = (la, 0)`: `lb * (cos, sin)` of the angle
    /// at `c`, with `sin >= 0`.
    bx: f64,
    by: f64,
    /// Gaussian curvature density of the triangle (mean of its corners'; curved-front rule).
    kg: f64,
}

meshcore::choice! {
    /// How the arrival time of a vertex is computed from the two other corners of a triangle.
    ///
    /// Measured (see `docs/bench-geodesic.md`): the plane-wave update (classic Kimmel-Sethian)
    /// ignores the curvature of the front and overestimates around point sources; the point-source
    /// update is exact on flat and developable meshes but assumes the flat-plane front curvature
    /// `1 / T`, so it underestimates where geodesics converge (towards the antipode of a closed
    /// sphere). The curved-front update (the default) tracks the front curvature per vertex and is
    /// right in both regimes.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub enum FmmUpdate: "fast-marching update", crate::GeodesicError {
        /// Kimmel-Sethian: the front is locally a plane wave (`T` linear in the triangle with unit
        /// gradient). Exact for plane waves.
        PlaneWave = "plane-wave",
        /// The front is locally a circle around a virtual point source at distances `T_a`, `T_b`
        /// from `a`, `b` (the unfolded source of the triangle). Exact for point sources on flat and
        /// developable meshes.
        PointSource = "point-source",
        /// The mean of the plane-wave and point-source updates (an empirical compromise).
        Blend = "blend",
        /// The front is locally a circle whose signed geodesic curvature `kappa` is carried from
        /// vertex to vertex: diverging (virtual source behind the front, as
        /// [`FmmUpdate::PointSource`]), converging (focus ahead of the front) or straight (plane
        /// wave). The circle through `a` and `b` gives the time of `c`; `kappa` itself follows the
        /// characteristics by the Riccati equation `dkappa/ds = -kappa^2 - K`, solved exactly for
        /// the Gaussian curvature `K` of the triangle (angle defect over a third of the incident
        /// area, averaged over its corners; zero on the boundary). Equals
        /// [`FmmUpdate::PointSource`] on flat and developable meshes (`kappa = 1 / T`); on a sphere
        /// it follows `kappa = cot T` through the equator (plane wave) to the converging front at
        /// the antipode, where the point-source rule underestimates and the plane-wave rule
        /// overestimates. The default.
        #[default]
        CurvedFront = "curved-front",
    }
}

/// Fast marching distance on a triangle mesh.
///
/// With the default [`FmmUpdate::CurvedFront`] rule: exact from a vertex source on flat and
/// developable meshes, and on the peers' unit spheres (2.5k-164k vertices) max errors of
/// 1.2e-3 down to 1.9e-5 against the great-circle distance (`docs/bench-geodesic.md`). With
/// several sources whose fronts merge (e.g. a row of vertices) it is first order, like the
/// point-source rule; [`FmmUpdate::PlaneWave`] is exact for plane waves. Obtuse corners are split by unfolding (Kimmel-Sethian), which keeps the
/// scheme monotone and accurate on meshes with obtuse or stretched triangles. A surface-point
/// source starts from the three corners of its face with their straight-line distances.
///
/// Preparation (adjacency, unfolding) is done once in [`FastMarching::new`]; each solve is
/// `O(n log n)`.
#[derive(Debug, Clone)]
pub struct FastMarching {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Update triangles, grouped by the vertex they update.
    tris: Vec<UpdTri>,
    /// For each vertex `u`, the (vertex updated, update-triangle index) pairs that use `u`.
    dep_offsets: Vec<u32>,
    deps: Vec<(u32, u32)>,
    rule: FmmUpdate,
    /// Obtuse corners found / split successfully (diagnostics).
    n_obtuse: usize,
    n_split: usize,
}

/// Third point of a triangle with base `p`, `q` and side lengths `lp = |xp|`, `lq = |xq|`, placed
/// on the side of line `pq` opposite to `away` (2D).
fn unfold_point(p: DVec2, q: DVec2, lp: f64, lq: f64, away: DVec2) -> Option<DVec2> {
    let e = q - p;
    let l = e.length();
    if l <= 0.0 || !l.is_finite() {
        return None;
    }
    let ex = e / l;
    let x = (lp * lp - lq * lq + l * l) / (2.0 * l);
    let y = (lp * lp - x * x).max(0.0).sqrt();
    let mut n = DVec2::new(-ex.y, ex.x);
    if n.dot(away - p) > 0.0 {
        n = -n;
    }
    Some(p + x * ex + y * n)
}

impl FastMarching {
    /// Prepares the solver for `mesh`: adjacency and the unfolding of every obtuse corner. Uses
    /// the default update rule ([`FmmUpdate::CurvedFront`]).
    pub fn new(mesh: &TriMesh) -> Result<Self, GeodesicError> {
        Self::with_update(mesh, FmmUpdate::default())
    }

    /// Like [`FastMarching::new`] with an explicit update rule.
    pub fn with_update(mesh: &TriMesh, rule: FmmUpdate) -> Result<Self, GeodesicError> {
        let topo = Topology::new(mesh);
        let pos = mesh.positions();
        let tris_in = mesh.triangles();
        let n = mesh.n_vertices();
        let len = |a: u32, b: u32| (pos[a as usize] - pos[b as usize]).length();

        // Per-vertex lists of update triangles, built vertex by vertex (deterministic order).
        let mut tri_offsets = Vec::with_capacity(n + 1);
        tri_offsets.push(0u32);
        let mut tris: Vec<UpdTri> = Vec::with_capacity(tris_in.len() * 3 + 16);
        let (mut n_obtuse, mut n_split) = (0usize, 0usize);
        for c in 0..n as u32 {
            for &f in topo.vertex_faces(c) {
                let t = tris_in[f as usize];
                let k = match t.iter().position(|&v| v == c) {
                    Some(k) => k,
                    None => continue,
                };
                let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
                if a == c || b == c || a == b {
                    continue;
                }
                let (la, lb) = (len(c, a), len(c, b));
                let ua = pos[a as usize] - pos[c as usize];
                let ub = pos[b as usize] - pos[c as usize];
                let cross = ua.cross(ub).length();
                let dot = ua.dot(ub);
                let (cos, sin) = if la > 0.0 && lb > 0.0 {
                    (dot / (la * lb), cross / (la * lb))
                } else {
                    (1.0, 0.0)
                };
                let plain = UpdTri {
                    a,
                    b,
                    la,
                    lb,
                    bx: lb * cos,
                    by: lb * sin,
                    kg: 0.0,
                };
                if cos < 0.0 && sin > 0.0 {
                    n_obtuse += 1;
                    if let Some((w, pw)) = Self::split(mesh, &topo, f, c, a, b, la, lb, cos, sin) {
                        n_split += 1;
                        let lw = pw.length();
                        // (c, a, w): a on the x axis, w at angle theta.
                        tris.push(UpdTri {
                            a,
                            b: w,
                            la,
                            lb: lw,
                            bx: pw.x,
                            by: pw.y,
                            kg: 0.0,
                        });
                        // (c, w, b) in a frame where w lies on the x axis.
                        let pb = DVec2::new(plain.bx, plain.by);
                        let ew = pw / lw;
                        tris.push(UpdTri {
                            a: w,
                            b,
                            la: lw,
                            lb,
                            bx: pb.dot(ew),
                            by: (ew.x * pb.y - ew.y * pb.x).max(0.0),
                            kg: 0.0,
                        });
                        continue;
                    }
                }
                tris.push(plain);
            }
            tri_offsets.push(tris.len() as u32);
        }

        // Reverse lists: which (vertex, triangle) pairs use each vertex.
        let mut dep_offsets = vec![0u32; n + 1];
        for t in &tris {
            dep_offsets[t.a as usize + 1] += 1;
            dep_offsets[t.b as usize + 1] += 1;
        }
        for i in 0..n {
            dep_offsets[i + 1] += dep_offsets[i];
        }
        let mut fill = dep_offsets.clone();
        let mut deps = vec![(0u32, 0u32); dep_offsets[n] as usize];
        for c in 0..n {
            for ti in tri_offsets[c]..tri_offsets[c + 1] {
                let t = tris[ti as usize];
                for u in [t.a, t.b] {
                    deps[fill[u as usize] as usize] = (c as u32, ti);
                    fill[u as usize] += 1;
                }
            }
        }
        let gauss = gaussian_curvature(mesh, &topo);
        for c in 0..n {
            for ti in tri_offsets[c]..tri_offsets[c + 1] {
                let t = &mut tris[ti as usize];
                t.kg = (gauss[c] + gauss[t.a as usize] + gauss[t.b as usize]) / 3.0;
            }
        }
        Ok(Self {
            positions: pos.to_vec(),
            triangles: tris_in.to_vec(),
            tris,
            dep_offsets,
            deps,
            rule,
            n_obtuse,
            n_split,
        })
    }

    /// Number of obtuse corners of the mesh and how many of them were split by unfolding (the
    /// others, at boundaries or in very long strips, use the plain update).
    pub fn obtuse_corners(&self) -> (usize, usize) {
        (self.n_obtuse, self.n_split)
    }

    /// Unfolds faces across the edge opposite the obtuse corner `c` of face `f` until a vertex
    /// lands in the section of the angle. Returns the vertex and its unfolded position in the
    /// frame `c = 0`, `a = (la, 0)`, `b = lb (cos, sin)`.
    #[allow(clippy::too_many_arguments)]
    fn split(
        mesh: &TriMesh,
        topo: &Topology,
        f: u32,
        c: u32,
        a: u32,
        b: u32,
        la: f64,
        lb: f64,
        cos: f64,
        sin: f64,
    ) -> Option<(u32, DVec2)> {
        let pos = mesh.positions();
        let tris = mesh.triangles();
        let len = |x: u32, y: u32| (pos[x as usize] - pos[y as usize]).length();
        let gamma = sin.atan2(cos);
        let (lo, hi) = (
            gamma - std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        );
        // Current edge (p, q), p on the a side, with 2D positions; face g holds it and the
        // vertex r (2D position pr) on the near side.
        let (mut p, mut q) = (a, b);
        let (mut pp, mut pq) = (DVec2::new(la, 0.0), DVec2::new(lb * cos, lb * sin));
        let mut g = f;
        let mut pr = DVec2::ZERO;
        for _ in 0..MAX_UNFOLD {
            let e = Self::edge_of(topo, tris, g, p, q)?;
            let h = topo.opposite_face(e, g)?;
            let th = tris[h as usize];
            let w = *th.iter().find(|&&v| v != p && v != q)?;
            if w == c || w == a || w == b {
                return None;
            }
            let pw = unfold_point(pp, pq, len(p, w), len(q, w), pr)?;
            let theta = pw.y.atan2(pw.x);
            if theta > lo && theta < hi && pw.length() > 0.0 {
                return Some((w, pw));
            }
            if theta <= lo {
                // The section lies between w and q.
                pr = pp;
                p = w;
                pp = pw;
            } else {
                pr = pq;
                q = w;
                pq = pw;
            }
            g = h;
        }
        None
    }

    /// Edge id of the side `(p, q)` of face `g`.
    fn edge_of(topo: &Topology, tris: &[[u32; 3]], g: u32, p: u32, q: u32) -> Option<u32> {
        let t = tris[g as usize];
        (0..3)
            .find(|&k| {
                let (x, y) = (t[k], t[(k + 1) % 3]);
                (x == p && y == q) || (x == q && y == p)
            })
            .map(|k| topo.face_edges()[g as usize][k])
    }
}

/// Plane-wave solve of `c` from `a` (time `ta`) and `b` (time `tb`): the time of `c` and the
/// unit gradient `g` of `T` in the triangle, or `None` when the wave does not come through the
/// triangle (upwind condition) or arrives before `a` or `b`.
#[inline]
fn solve_plane(t: &UpdTri, ta: f64, tb: f64) -> Option<(f64, f64, f64)> {
    if t.by <= 0.0 {
        return None;
    }
    // Rows of P: a = (ax, 0), b = (bx, by). T(x) = tc + g.x with |g| = 1.
    let (ax, bx, by) = (t.la, t.bx, t.by);
    // P^{-1} = 1/(ax*by) [[by, 0], [-bx, ax]].
    let det = ax * by;
    // g = P^{-1} (ta - tc, tb - tc) = u - tc * w with u = P^{-1} (ta, tb), w = P^{-1} (1, 1).
    let (ux, uy) = (by * ta / det, (-bx * ta + ax * tb) / det);
    let (wx, wy) = (by / det, (ax - bx) / det);
    let qa = wx * wx + wy * wy;
    let qb = -2.0 * (ux * wx + uy * wy);
    let qc = ux * ux + uy * uy - 1.0;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 || qa <= 0.0 {
        return None;
    }
    let tc = (-qb + disc.sqrt()) / (2.0 * qa);
    if tc.is_nan() || tc < ta.max(tb) {
        return None;
    }
    // Upwind: -g must point into the triangle, -g = alpha a + beta b with alpha, beta >= 0.
    let (gx, gy) = (ux - tc * wx, uy - tc * wy);
    let beta = -gy / by;
    let alpha = (-gx - beta * bx) / ax;
    if alpha < -1e-12 || beta < -1e-12 {
        return None;
    }
    Some((tc, gx, gy))
}

/// Plane-wave update (Kimmel-Sethian) of `c` from `a` (time `ta`) and `b` (time `tb`).
#[inline]
fn update_plane(t: &UpdTri, ta: f64, tb: f64) -> f64 {
    let edge = (ta + t.la).min(tb + t.lb);
    match solve_plane(t, ta, tb) {
        Some((tc, _, _)) => tc.min(edge),
        None => edge,
    }
}

/// Geodesic curvature of a front that had curvature `kappa` and travelled `step` along its
/// characteristics through a surface of constant Gaussian curvature `kg`: the exact solution of
/// the Riccati equation `dkappa/ds = -kappa^2 - kg`, `(kappa - kg sigma) / (1 + kappa sigma)`
/// with `sigma = tan(sqrt(kg) step) / sqrt(kg)` (`tanh` for `kg < 0`, `step` for `kg = 0`). On
/// a plane the radius `1 / kappa` grows by `step`, and a converging front passes its focus and
/// diverges; `kappa = inf` (a point source) gives `1 / sigma`.
#[inline]
fn advance(kappa: f64, kg: f64, step: f64) -> f64 {
    let y = kg * step * step;
    let sigma = if y.abs() < 0.05 {
        // Series of tan(x) / x (tanh for y < 0), x^2 = |y|; relative error below 1e-10 (and
        // below 1e-14 for |y| < 1e-2, the usual case: y ~ K h^2).
        step * (1.0
            + y * (1.0 / 3.0
                + y * (2.0 / 15.0
                    + y * (17.0 / 315.0 + y * (62.0 / 2835.0 + y * (1382.0 / 155925.0))))))
    } else if y > 0.0 && y < 2.4 {
        let q = kg.sqrt();
        (q * step).tan() / q
    } else if y < 0.0 {
        let q = (-kg).sqrt();
        (q * step).tanh() / q
    } else {
        // Beyond the conjugate distance of the local curvature: keep the flat evolution.
        step
    };
    if kappa.is_infinite() {
        1.0 / sigma
    } else {
        (kappa - kg * sigma) / (1.0 + kappa * sigma)
    }
}

/// [`advance`] by a step of either sign, `None` when a backward step would pass a source (or
/// a forward one a focus).
#[inline]
fn transport(kappa: f64, kg: f64, step: f64) -> Option<f64> {
    if step == 0.0 {
        return Some(kappa);
    }
    if kappa.is_infinite() {
        return (step > 0.0).then(|| advance(kappa, kg, step));
    }
    let k = advance(kappa, kg, step);
    (k.is_finite() && (k > 0.0) == (kappa > 0.0)).then_some(k)
}

/// Edge update of `c` from the better of `a`, `b` in the curved-front rule: `(time, kappa)`.
#[inline]
fn edge_curved(t: &UpdTri, ta: f64, tb: f64, ka: f64, kb: f64, kg: f64) -> (f64, f64) {
    if ta + t.la <= tb + t.lb {
        (ta + t.la, advance(ka, kg, t.la))
    } else {
        (tb + t.lb, advance(kb, kg, t.lb))
    }
}

/// `true` when the direction `v` lies in the cone spanned by `a = (ax, 0)` and `b = (bx, by)`.
#[inline]
fn in_cone(ax: f64, bx: f64, by: f64, vx: f64, vy: f64, tol: f64) -> bool {
    ax * vy >= tol && vx * by - vy * bx >= tol
}

/// Curved-front update of `c` from `a`, `b` (times `ta`, `tb`, front curvatures `ka`, `kb`;
/// `kg` the Gaussian curvature density of the triangle): `(time, kappa)` of `c`.
///
/// The front through `a` and `b` is a circle of signed radius `rho` (the mean of theirs, both
/// carried to the mean time):
/// `rho > 0` a virtual source behind the front at distances `rho +- (ta - tb) / 2` from `a` and
/// `b`, `rho < 0` a focus ahead of it at distances `|rho| -+ (ta - tb) / 2`, `|rho|` huge a plane
/// wave. The characteristic reaching `c` must cross the segment `ab`; otherwise (or if the front
/// cannot be placed) the edge update is used.
fn update_curved(t: &UpdTri, ta: f64, tb: f64, ka: f64, kb: f64, kg: f64) -> (f64, f64) {
    // The edge update (its curvature only computed when it is the answer).
    let edge_t = (ta + t.la).min(tb + t.lb);
    let edge = || edge_curved(t, ta, tb, ka, kb, kg);
    if t.by <= 0.0 {
        return edge();
    }
    let (ax, bx, by) = (t.la, t.bx, t.by);
    let (ex, ey) = (bx - ax, by);
    let l2 = ex * ex + ey * ey;
    let l = l2.sqrt();
    let dt = ta - tb;
    if l.is_nan() || l <= 0.0 || dt.abs() >= l {
        return edge();
    }
    // Both curvatures carried to the mean time (on a curved surface the radius of curvature
    // grows at the rate 1 + K rho^2, not 1), then averaged: radii when the fronts agree in
    // sense, curvatures otherwise (near a straight front).
    let tm = 0.5 * (ta + tb);
    let (ka, kb) = match (transport(ka, kg, tm - ta), transport(kb, kg, tm - tb)) {
        (Some(x), Some(y)) => (x, y),
        _ => (ka, kb),
    };
    let rho = if (ka > 0.0 && kb > 0.0) || (ka < 0.0 && kb < 0.0) {
        0.5 * (1.0 / ka + 1.0 / kb)
    } else {
        1.0 / (0.5 * (ka + kb))
    };
    // Curvature of the front at the mean time, carried to c along the characteristic by the
    // Riccati equation (not read off the circle below: within a triangle the fronts of
    // different times are concentric circles only on a plane).
    let kmid = if rho.is_nan() { 0.0 } else { 1.0 / rho };
    let scale = ax.max(t.lb).max(l);
    let tol = -1e-12 * scale * scale;
    let tc = if rho.is_nan() || rho.abs() >= 1e6 * scale {
        // Plane wave.
        match solve_plane(t, ta, tb) {
            Some((tc, _, _)) => tc,
            None => return edge(),
        }
    } else {
        let (ra, rb) = if rho > 0.0 {
            (rho + 0.5 * dt, rho - 0.5 * dt)
        } else {
            (-rho - 0.5 * dt, -rho + 0.5 * dt)
        };
        if !(ra >= 0.0 && rb >= 0.0) {
            return edge();
        }
        // Centre p with |p - a| = ra, |p - b| = rb: behind ab (away from c = 0) for a source,
        // ahead of it (c's side) for a focus.
        let x = (ra * ra - rb * rb + l2) / (2.0 * l);
        let y2 = ra * ra - x * x;
        // Tolerate rounding when the centre lies on ab (a source next to both a and b).
        if y2 < -1e-10 * (ra * ra + rb * rb) {
            return edge();
        }
        let y = y2.max(0.0).sqrt();
        let (ux, uy) = (ex / l, ey / l);
        // (uy, -ux) points away from c (see `update_point`).
        let side = if rho > 0.0 { 1.0 } else { -1.0 };
        let (px, py) = (ax + x * ux + side * y * uy, x * uy - side * y * ux);
        let pl = (px * px + py * py).sqrt();
        if pl.is_nan() || pl <= 0.0 {
            return edge();
        }
        // The characteristic through c must cross ab: the centre (a source, or a focus c has
        // passed) seen from c, or the direction away from a focus ahead, lies in the corner.
        if rho > 0.0 {
            if !in_cone(ax, bx, by, px, py, tol) {
                return edge();
            }
            ta - ra + pl
        } else if in_cone(ax, bx, by, -px, -py, tol) {
            ta + ra - pl
        } else if in_cone(ax, bx, by, px, py, tol) {
            ta + ra + pl
        } else {
            return edge();
        }
    };
    // As in the point-source update, a circle may reach `c` before `a` or `b` (strongly
    // obtuse corners that could not be split); the value is still the front's.
    if tc.is_nan() || tc >= edge_t {
        return edge();
    }
    (tc, advance(kmid, kg, tc - tm))
}

/// Point-source update of `c` from `a` (time `ta`) and `b` (time `tb`) in triangle `t`.
#[inline]
fn update_point(t: &UpdTri, ta: f64, tb: f64) -> f64 {
    let edge = (ta + t.la).min(tb + t.lb);
    if t.by <= 0.0 {
        return edge;
    }
    let (ax, bx, by) = (t.la, t.bx, t.by);
    let (ex, ey) = (bx - ax, by);
    let l2 = ex * ex + ey * ey;
    let l = l2.sqrt();
    if l <= 0.0 || (ta - tb).abs() >= l {
        return edge;
    }
    // Virtual source s with |s - a| = ta, |s - b| = tb, on the far side of ab from c = 0.
    let x = (ta * ta - tb * tb + l2) / (2.0 * l);
    let y2 = ta * ta - x * x;
    if y2 < 0.0 {
        return edge;
    }
    let y = y2.sqrt();
    let (ux, uy) = (ex / l, ey / l);
    // Normal pointing away from c: c is at the origin, a = (ax, 0), so the side of c is the sign
    // of cross(e, c - a) = ex * 0 - ey * (0 - ax) = ey * ax > 0; we want the opposite.
    let (nx, ny) = (uy, -ux);
    let sx = ax + x * ux + y * nx;
    let sy = x * uy + y * ny;
    // The ray from s to c must cross ab: s lies in the cone spanned by a and b.
    let cross_as = ax * sy; // cross((ax,0), s)
    let cross_sb = sx * by - sy * bx;
    let tol = -1e-12 * (ax * ax + l2);
    if cross_as < tol || cross_sb < tol {
        return edge;
    }
    (sx * sx + sy * sy).sqrt().min(edge)
}

/// Gaussian curvature density per vertex: angle defect over a third of the incident area; zero
/// at boundary and non-manifold vertices and where the area vanishes.
fn gaussian_curvature(mesh: &TriMesh, topo: &Topology) -> Vec<f64> {
    let pos = mesh.positions();
    let n = mesh.n_vertices();
    let mut angle = vec![0.0f64; n];
    let mut area = vec![0.0f64; n];
    for t in mesh.triangles() {
        let p = t.map(|v| pos[v as usize]);
        let a3 = (p[1] - p[0]).cross(p[2] - p[0]).length() / 6.0;
        for k in 0..3 {
            let u = p[(k + 1) % 3] - p[k];
            let w = p[(k + 2) % 3] - p[k];
            let (lu, lw) = (u.length(), w.length());
            if lu > 0.0 && lw > 0.0 {
                angle[t[k] as usize] += (u.dot(w) / (lu * lw)).clamp(-1.0, 1.0).acos();
            }
            area[t[k] as usize] += a3;
        }
    }
    let mut skip = vec![false; n];
    for e in topo.edges() {
        if e.n_faces != 2 {
            skip[e.v[0] as usize] = true;
            skip[e.v[1] as usize] = true;
        }
    }
    for &v in topo.non_manifold_vertices() {
        skip[v as usize] = true;
    }
    (0..n)
        .map(|v| {
            if skip[v] || area[v].is_nan() || area[v] <= 0.0 {
                0.0
            } else {
                (2.0 * std::f64::consts::PI - angle[v]) / area[v]
            }
        })
        .collect()
}

impl FastMarching {
    /// The marching itself: distances (not yet cut off) and, for the curved-front rule, the
    /// front curvature per vertex (empty otherwise).
    fn march(&self, sources: &[Source], cut: f64) -> Result<(Vec<f64>, Vec<f64>), GeodesicError> {
        let n = self.positions.len();
        let mut dist = vec![f64::INFINITY; n];
        let curved = self.rule == FmmUpdate::CurvedFront;
        // Front curvature per vertex (curved-front rule only).
        let mut kap = if curved { vec![0.0; n] } else { Vec::new() };
        let mut done = vec![false; n];
        let mut heap = BinaryHeap::new();
        for (v, d) in seeds(&self.positions, &self.triangles, sources)? {
            if d < dist[v as usize] {
                dist[v as usize] = d;
                if curved {
                    kap[v as usize] = 1.0 / d;
                }
                heap.push(Item(d, v));
            }
        }
        while let Some(Item(d, u)) = heap.pop() {
            if done[u as usize] || d > dist[u as usize] {
                continue;
            }
            if d > cut {
                break;
            }
            done[u as usize] = true;
            let (s, e) = (
                self.dep_offsets[u as usize] as usize,
                self.dep_offsets[u as usize + 1] as usize,
            );
            for &(c, ti) in &self.deps[s..e] {
                if done[c as usize] {
                    continue;
                }
                let t = &self.tris[ti as usize];
                let (ta, tb) = (dist[t.a as usize], dist[t.b as usize]);
                if curved {
                    let kg = t.kg;
                    let (ka, kb) = (kap[t.a as usize], kap[t.b as usize]);
                    let (cand, kc) = if done[t.a as usize] && done[t.b as usize] {
                        update_curved(t, ta, tb, ka, kb, kg)
                    } else {
                        let (tu, ku, lu) = if t.a == u {
                            (ta, ka, t.la)
                        } else {
                            (tb, kb, t.lb)
                        };
                        if tu + lu >= dist[c as usize] {
                            continue;
                        }
                        (tu + lu, advance(ku, kg, lu))
                    };
                    if cand < dist[c as usize] {
                        dist[c as usize] = cand;
                        kap[c as usize] = kc;
                        heap.push(Item(cand, c));
                    }
                    continue;
                }
                let cand = if done[t.a as usize] && done[t.b as usize] {
                    match self.rule {
                        FmmUpdate::PointSource => update_point(t, ta, tb),
                        FmmUpdate::PlaneWave => update_plane(t, ta, tb),
                        FmmUpdate::Blend | FmmUpdate::CurvedFront => {
                            0.5 * (update_point(t, ta, tb) + update_plane(t, ta, tb))
                        }
                    }
                } else if t.a == u {
                    ta + t.la
                } else {
                    tb + t.lb
                };
                if cand < dist[c as usize] {
                    dist[c as usize] = cand;
                    heap.push(Item(cand, c));
                }
            }
        }
        Ok((dist, kap))
    }
}

impl Field for FastMarching {
    const METHOD: Method = Method::Fmm;
    fn positions(&self) -> &[DVec3] {
        &self.positions
    }
    fn field(&self, sources: &[Source], cut: f64) -> Result<Vec<f64>, GeodesicError> {
        Ok(self.march(sources, cut)?.0)
    }
}

/// Diagnostic of the curved-front rule on a mesh of the unit sphere, for the `fmm_trace`
/// example; not part of the API. From the source vertex `src`: the carried front curvature
/// against the sphere's `cot(g)` by geodesic distance `g`, the vertices where it is worst at
/// `g` in [2, 2.4), then the walk back from `start` (default: the vertex of largest error)
/// through the best candidate update of each step, with the candidates.
#[doc(hidden)]
pub fn trace_curved_front(
    mesh: &TriMesh,
    src: u32,
    start: Option<u32>,
) -> Result<String, GeodesicError> {
    use std::fmt::Write;
    let fm = FastMarching::with_update(mesh, FmmUpdate::CurvedFront)?;
    let (d, kap) = fm.march(&[Source::Vertex(src)], f64::INFINITY)?;
    let mut report = String::new();
    macro_rules! say {
        ($($t:tt)*) => {
            let _ = writeln!(report, $($t)*);
        };
    }
    let ps = mesh.position(src).normalize();
    let g: Vec<f64> = mesh
        .positions()
        .iter()
        .map(|v| v.normalize().dot(ps).clamp(-1.0, 1.0).acos())
        .collect();
    // Front curvature against the sphere's cot(g), by distance.
    for k in 0..16 {
        let (lo, hi) = (k as f64 * 0.2, (k + 1) as f64 * 0.2);
        let sel: Vec<usize> = (0..d.len()).filter(|&i| g[i] >= lo && g[i] < hi).collect();
        if sel.is_empty() {
            continue;
        }
        let mean_k = sel.iter().map(|&i| kap[i]).sum::<f64>() / sel.len() as f64;
        let mean_c = sel.iter().map(|&i| 1.0 / g[i].tan()).sum::<f64>() / sel.len() as f64;
        let mean_e = sel.iter().map(|&i| d[i] - g[i]).sum::<f64>() / sel.len() as f64;
        let max_e = sel.iter().map(|&i| (d[i] - g[i]).abs()).fold(0.0, f64::max);
        say!(
            "g in [{lo:.1}, {hi:.1}): kappa {mean_k:+.3} sphere {mean_c:+.3} mean err {mean_e:+.2e} max |err| {max_e:.2e}"
        );
    }
    // Where the carried curvature is worst at moderate distance.
    let mut sel: Vec<usize> = (0..d.len())
        .filter(|&i| g[i] >= 2.0 && g[i] < 2.4)
        .collect();
    sel.sort_by(|&i, &j| {
        (kap[j] - 1.0 / g[j].tan())
            .abs()
            .total_cmp(&(kap[i] - 1.0 / g[i].tan()).abs())
    });
    for &i in sel.iter().take(12) {
        let q = mesh.position(i as u32).normalize();
        say!(
            "  kappa off at v{i}: lat {:+.1} lon {:+.1} g {:.3} kappa {:+.3} sphere {:+.3}",
            q.z.asin().to_degrees(),
            q.y.atan2(q.x).to_degrees(),
            g[i],
            kap[i],
            1.0 / g[i].tan()
        );
    }
    let mut v = start.unwrap_or_else(|| {
        (0..d.len())
            .max_by(|&i, &j| (d[i] - g[i]).abs().total_cmp(&(d[j] - g[j]).abs()))
            .unwrap() as u32
    });
    for _ in 0..60 {
        let q = mesh.position(v).normalize();
        say!(
            "v{v}: lat {:+.1} lon {:+.1} T {:.4} err {:+.2e} kappa {:+.3e} (sphere {:+.3e})",
            q.z.asin().to_degrees(),
            q.y.atan2(q.x).to_degrees(),
            d[v as usize],
            d[v as usize] - g[v as usize],
            kap[v as usize],
            1.0 / g[v as usize].tan(),
        );
        if v == src {
            break;
        }
        // All candidates of v from vertices accepted before it.
        let mut cands = Vec::new();
        for (ti, t) in fm.tris.iter().enumerate() {
            let _ = ti;
            let owner = fm.deps
                [fm.dep_offsets[t.a as usize] as usize..fm.dep_offsets[t.a as usize + 1] as usize]
                .iter()
                .any(|&(c, i)| c == v && i as usize == ti);
            if !owner {
                continue;
            }
            let (a, b) = (t.a as usize, t.b as usize);
            if !(d[a] < d[v as usize] && d[b] < d[v as usize]) {
                continue;
            }
            let kg = t.kg;
            let (tc, kc) = update_curved(t, d[a], d[b], kap[a], kap[b], kg);
            let edge = edge_curved(t, d[a], d[b], kap[a], kap[b], kg).0;
            let (tx, kx) = update_curved(t, g[a], g[b], 1.0 / g[a].tan(), 1.0 / g[b].tan(), kg);
            if cands.is_empty() {
                say!("    [exact inputs for the first triangle: T {tx:.5} (g {:.5}) kappa {kx:+.3e}]", g[v as usize]);
            }
            cands.push((tc, kc, a, b, tc == edge, t.la, t.lb));
        }
        cands.sort_by(|x, y| x.0.total_cmp(&y.0));
        for c in cands.iter().take(3) {
            say!(
                "    cand T {:.4} kappa {:+.3e} from a v{} (err {:+.2e}) b v{} (err {:+.2e}) edge {} la {:.4} lb {:.4}",
                c.0, c.1, c.2, d[c.2] - g[c.2], c.3, d[c.3] - g[c.3], c.4, c.5, c.6
            );
        }
        let Some(best) = cands.first() else { break };
        // Follow the corner with the larger error magnitude.
        v = if (d[best.2] - g[best.2]).abs() >= (d[best.3] - g[best.3]).abs() {
            best.2 as u32
        } else {
            best.3 as u32
        };
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The update triangle with `c = 0`, `a = (1, 0)` and `b` in the upper half-plane.
    fn unit_tri(b: DVec2) -> UpdTri {
        UpdTri {
            a: 0,
            b: 1,
            la: 1.0,
            lb: b.length(),
            bx: b.x,
            by: b.y,
            kg: 0.0,
        }
    }

    #[test]
    fn planar_update_is_exact_for_plane_waves() {
        // c = 0, a = (1, 0), b = (0, 1); plane wave travelling along direction (1, 1)/sqrt2
        // with zero time on the line x + y = 3.
        let t = unit_tri(DVec2::new(0.0, 1.0));
        let time = |x: f64, y: f64| (3.0 - x - y) / 2f64.sqrt();
        let got = update_plane(&t, time(1.0, 0.0), time(0.0, 1.0));
        assert!((got - time(0.0, 0.0)).abs() < 1e-14, "{got}");
        // A wave coming from outside the cone falls back to the edge update.
        assert_eq!(update_plane(&t, 0.0, 5.0), 1.0);
        assert_eq!(update_point(&t, 0.0, 5.0), 1.0);
    }

    #[test]
    fn point_update_is_exact_for_point_sources() {
        // c = 0, a = (1, 0), b = (0.3, 0.9); source at (2, 1.5).
        let t = unit_tri(DVec2::new(0.3, 0.9));
        let s = DVec2::new(2.0, 1.5);
        let ta = (s - DVec2::new(1.0, 0.0)).length();
        let tb = (s - DVec2::new(0.3, 0.9)).length();
        let got = update_point(&t, ta, tb);
        assert!((got - s.length()).abs() < 1e-14, "{got}");
        // The plane-wave update is not exact here, but close.
        let pw = update_plane(&t, ta, tb);
        assert!((pw - s.length()).abs() < 0.1 && (pw - s.length()).abs() > 1e-6);
    }

    #[test]
    fn riccati_advance_follows_geodesic_circles() {
        // Unit sphere: geodesic circles of radius r have curvature cot r.
        for (r0, s) in [(0.3, 0.05), (1.2, 0.4), (2.0, -0.3), (2.5, 0.5)] {
            let k = advance(1.0 / f64::tan(r0), 1.0, s);
            assert!((k - 1.0 / f64::tan(r0 + s)).abs() < 1e-11, "{r0} {s}: {k}");
        }
        assert!((advance(f64::INFINITY, 1.0, 0.7) - 1.0 / 0.7f64.tan()).abs() < 1e-12);
        // Hyperbolic plane (K = -1): coth r.
        let k = advance(1.0 / 0.5f64.tanh(), -1.0, 0.8);
        assert!((k - 1.0 / 1.3f64.tanh()).abs() < 1e-12);
        // Plane: the radius grows by the step, a focus is passed.
        assert!((advance(0.5, 0.0, 1.0) - 1.0 / 3.0).abs() < 1e-15);
        assert!((advance(-1.0, 0.0, 3.0) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn curved_update_is_exact_for_flat_circles_both_ways() {
        // c = 0, a = (1, 0), b = (0.3, 0.9).
        let t = unit_tri(DVec2::new(0.3, 0.9));
        let (pa, pb) = (DVec2::new(1.0, 0.0), DVec2::new(0.3, 0.9));
        // Diverging from a source behind ab: the point-source update.
        let s = DVec2::new(2.0, 1.5);
        let (ta, tb) = ((s - pa).length(), (s - pb).length());
        let (tc, kc) = update_curved(&t, ta, tb, 1.0 / ta, 1.0 / tb, 0.0);
        assert!((tc - s.length()).abs() < 1e-12 && (kc - 1.0 / s.length()).abs() < 1e-12);
        // Converging on a focus beyond c: T = 10 - |x - f|, f = -(2, 1.5).
        let f = -s;
        let time = |p: DVec2| 10.0 - (p - f).length();
        let (ta, tb) = (time(pa), time(pb));
        let (ka, kb) = (-1.0 / (pa - f).length(), -1.0 / (pb - f).length());
        let (tc, kc) = update_curved(&t, ta, tb, ka, kb, 0.0);
        assert!((tc - time(DVec2::ZERO)).abs() < 1e-12, "{tc}");
        assert!((kc + 1.0 / f.length()).abs() < 1e-12, "{kc}");
        // The point-source and plane-wave updates both miss it.
        assert!((update_point(&t, ta, tb) - time(DVec2::ZERO)).abs() > 1e-3);
        assert!((update_plane(&t, ta, tb) - time(DVec2::ZERO)).abs() > 1e-3);
    }

    #[test]
    fn unfold_point_places_across() {
        let p = DVec2::new(0.0, 0.0);
        let q = DVec2::new(2.0, 0.0);
        let w = unfold_point(p, q, 2f64.sqrt(), 2f64.sqrt(), DVec2::new(1.0, 1.0)).unwrap();
        assert!((w - DVec2::new(1.0, -1.0)).length() < 1e-14);
    }
}
