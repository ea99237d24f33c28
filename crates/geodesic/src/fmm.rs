//! Fast marching on triangulated domains (Kimmel & Sethian 1998) with obtuse-angle unfolding.
//!
//! Every vertex `c` owns a list of *update triangles* `(c, a, b)`: planar triangles in which the
//! arrival time of `c` is computed from the times of `a` and `b` by the planar-wave update (the
//! virtual source at distances `T_a`, `T_b` from `a`, `b`, valid when the ray from it to `c`
//! crosses the segment `ab`). Acute corners give one update triangle, the face itself. An obtuse
//! corner breaks causality (the front may reach `c` before `a` or `b`), so, as in Kimmel-Sethian,
//! the neighbouring faces are unfolded across the opposite edge into the plane of the face until
//! a vertex `w` lands in the *section* of the obtuse angle (the cone bounded by the
//! perpendiculars to `ca` and `cb`); the virtual edge `cw` splits the corner into two acute
//! update triangles `(c, a, w)` and `(c, w, b)`. The unfolded strip contains the segment `cw`,
//! so its (unfolded) length is a real surface path length.

use crate::dijkstra::seeds;
use crate::{GeodesicError, GeodesicSolver, Method, SolveOptions, Source, TriMesh};
use glam::{DVec2, DVec3};
use meshcore::Topology;
use std::cmp::Ordering;
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
}

/// How the arrival time of a vertex is computed from the two other corners of a triangle.
///
/// Measured (see `docs/bench-geodesic.md`): the plane-wave update (classic Kimmel-Sethian)
/// ignores the curvature of the front and overestimates around point sources; the point-source
/// update is exact on flat and developable meshes and 3x more accurate on the paper-set faces,
/// but underestimates where geodesics converge (towards the antipode of a closed sphere, where
/// its max error exceeds the plane wave's). Their mean lies in between.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FmmUpdate {
    /// Kimmel-Sethian: the front is locally a plane wave (`T` linear in the triangle with unit
    /// gradient). Exact for plane waves.
    PlaneWave,
    /// The front is locally a circle around a virtual point source at distances `T_a`, `T_b`
    /// from `a`, `b` (the unfolded source of the triangle). Exact for point sources on flat and
    /// developable meshes. The default.
    #[default]
    PointSource,
    /// The mean of the plane-wave and point-source updates (an empirical compromise).
    Blend,
}

/// Fast marching distance on a triangle mesh.
///
/// First-order accurate (error O(h) near point sources, smaller elsewhere); exact for a planar
/// wave on a flat mesh. Obtuse corners are split by unfolding (Kimmel-Sethian), which keeps the
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
    /// the default update rule ([`FmmUpdate::PointSource`]).
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
            .map(|k| topo.face_edges[g as usize][k])
    }
}

/// Plane-wave update (Kimmel-Sethian) of `c` from `a` (time `ta`) and `b` (time `tb`).
#[inline]
fn update_plane(t: &UpdTri, ta: f64, tb: f64) -> f64 {
    let edge = (ta + t.la).min(tb + t.lb);
    if t.by <= 0.0 {
        return edge;
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
        return edge;
    }
    let tc = (-qb + disc.sqrt()) / (2.0 * qa);
    if tc < ta.max(tb) {
        return edge;
    }
    // Upwind: -g must point into the triangle, -g = alpha a + beta b with alpha, beta >= 0.
    let (gx, gy) = (ux - tc * wx, uy - tc * wy);
    let beta = -gy / by;
    let alpha = (-gx - beta * bx) / ax;
    if alpha < -1e-12 || beta < -1e-12 {
        return edge;
    }
    tc.min(edge)
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

impl GeodesicSolver for FastMarching {
    fn method(&self) -> Method {
        Method::Fmm
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
        let mut dist = vec![f64::INFINITY; n];
        let mut done = vec![false; n];
        let mut heap = BinaryHeap::new();
        for (v, d) in seeds(&self.positions, &self.triangles, sources)? {
            if d < dist[v as usize] {
                dist[v as usize] = d;
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
                let cand = if done[t.a as usize] && done[t.b as usize] {
                    match self.rule {
                        FmmUpdate::PointSource => update_point(t, ta, tb),
                        FmmUpdate::PlaneWave => update_plane(t, ta, tb),
                        FmmUpdate::Blend => {
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

    #[test]
    fn planar_update_is_exact_for_plane_waves() {
        // c = 0, a = (1, 0), b = (0, 1); plane wave travelling along direction (1, 1)/sqrt2
        // with zero time on the line x + y = 3.
        let t = UpdTri {
            a: 0,
            b: 1,
            la: 1.0,
            lb: 1.0,
            bx: 0.0,
            by: 1.0,
        };
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
        let t = UpdTri {
            a: 0,
            b: 1,
            la: 1.0,
            lb: DVec2::new(0.3, 0.9).length(),
            bx: 0.3,
            by: 0.9,
        };
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
    fn unfold_point_places_across() {
        let p = DVec2::new(0.0, 0.0);
        let q = DVec2::new(2.0, 0.0);
        let w = unfold_point(p, q, 2f64.sqrt(), 2f64.sqrt(), DVec2::new(1.0, 1.0)).unwrap();
        assert!((w - DVec2::new(1.0, -1.0)).length() < 1e-14);
    }
}
