//! Straightest geodesics on a triangle mesh: walk a given length from a vertex or a surface
//! point in a given tangent direction, unfolding the path across every edge it crosses.
//!
//! Inside a face the path is a straight segment; at an edge the direction is carried into the
//! next face by the rotation about the edge that flattens the two faces (the angle with the edge
//! is kept), so the path is straight in the unfolding of the faces it crosses. On a plane the
//! walk ends at the Euclidean position; on a fine sphere mesh at the great-circle position.
//! A path that reaches a boundary edge stops there (`truncated`). A path that hits a vertex
//! exactly is nudged along the crossed edge by 1e-9 of its length (a measure-zero event).
//!
//! Bad input is an error, never a panic: a start vertex or surface point not on the mesh
//! ([`GeodesicError::Mesh`]), a zero, non-finite or normal direction
//! ([`GeodesicError::InvalidDirection`]), a negative or non-finite length
//! ([`GeodesicError::InvalidLength`]), a walk into a zero-area face
//! ([`GeodesicError::DegenerateFace`]).

use crate::GeodesicError;
use meshcore::{DVec3, SurfacePoint, Topology, TriMesh};

type Result<T> = std::result::Result<T, GeodesicError>;

fn direction_error(message: impl Into<String>) -> GeodesicError {
    GeodesicError::InvalidDirection(message.into())
}

fn walk_error(message: impl Into<String>) -> GeodesicError {
    GeodesicError::WalkFailed(message.into())
}

/// Checks the inputs every walk shares: a finite non-zero direction and a finite length >= 0.
fn check_walk_input(dir: DVec3, length: f64) -> Result<()> {
    if !dir.is_finite() || dir == DVec3::ZERO {
        return Err(direction_error(format!(
            "walk direction {dir} must be finite and non-zero"
        )));
    }
    if !(length.is_finite() && length >= 0.0) {
        return Err(GeodesicError::InvalidLength(length));
    }
    Ok(())
}

/// One straight piece of a walk, inside one face (barycentric end points in that face).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkSegment {
    /// Face holding the piece.
    pub face: u32,
    /// Barycentric coordinates where the piece starts.
    pub from: DVec3,
    /// Barycentric coordinates where it ends.
    pub to: DVec3,
    /// Length walked before this piece.
    pub start: f64,
    /// Length of the piece.
    pub length: f64,
}

/// Result of a walk.
#[derive(Debug, Clone, PartialEq)]
pub struct Walk {
    /// Where the walk ended.
    pub end: SurfacePoint,
    /// Its position.
    pub position: DVec3,
    /// Length actually walked (shorter than asked when truncated).
    pub length: f64,
    /// True if the walk stopped on the mesh boundary before reaching the length.
    pub truncated: bool,
    /// The pieces, in order.
    pub segments: Vec<WalkSegment>,
}

/// Prepared walker for one mesh (topology and normals built once); borrows the mesh.
#[derive(Debug)]
pub struct Walker<'a> {
    mesh: &'a TriMesh,
    topo: Topology,
    face_normals: Vec<DVec3>,
    vertex_normals: Vec<DVec3>,
}

impl<'a> Walker<'a> {
    /// Builds the walker's adjacency for `mesh`.
    pub fn new(mesh: &'a TriMesh) -> Self {
        let topo = Topology::new(mesh);
        let face_normals = (0..mesh.n_faces() as u32)
            .map(|f| mesh.face_normal(f))
            .collect();
        Self {
            mesh,
            topo,
            face_normals,
            vertex_normals: mesh.vertex_normals(),
        }
    }

    /// The mesh.
    pub fn mesh(&self) -> &'a TriMesh {
        self.mesh
    }

    /// Area-weighted normal at vertex `v`.
    pub fn vertex_normal(&self, v: u32) -> DVec3 {
        self.vertex_normals[v as usize]
    }

    /// Interpolated normal at a surface point (falls back to the face normal).
    pub fn point_normal(&self, sp: &SurfacePoint) -> DVec3 {
        let t = self.mesh.triangles()[sp.face as usize];
        let n = sp.bary.x * self.vertex_normals[t[0] as usize]
            + sp.bary.y * self.vertex_normals[t[1] as usize]
            + sp.bary.z * self.vertex_normals[t[2] as usize];
        let n = n.normalize_or_zero();
        if n == DVec3::ZERO {
            self.face_normals[sp.face as usize]
        } else {
            n
        }
    }

    /// Tangent direction at a point with normal `n`: `towards - p` projected on the tangent
    /// plane, then rotated by `theta` (radians, counter-clockwise about `n`). Errors
    /// ([`GeodesicError::InvalidDirection`]) when an input is not finite or `towards - p` is zero
    /// or along `n`.
    pub fn tangent_direction(p: DVec3, n: DVec3, towards: DVec3, theta: f64) -> Result<DVec3> {
        if !(p.is_finite() && n.is_finite() && towards.is_finite() && theta.is_finite()) {
            return Err(direction_error(format!(
                "tangent direction inputs must be finite (p {p}, n {n}, towards {towards}, theta {theta})"
            )));
        }
        let d = towards - p;
        let r = (d - d.dot(n) * n).normalize_or_zero();
        if r == DVec3::ZERO {
            return Err(direction_error(
                "reference direction is normal to the surface or zero",
            ));
        }
        let s = n.cross(r);
        Ok(theta.cos() * r + theta.sin() * s)
    }

    /// Walks `length` from vertex `v` along the tangent direction `dir`.
    pub fn walk_from_vertex(&self, v: u32, dir: DVec3, length: f64) -> Result<Walk> {
        check_walk_input(dir, length)?;
        self.mesh.try_position(v)?;
        let p = self.mesh.position(v);
        let mut best: Option<(u32, usize, DVec3)> = None;
        let mut best_score = f64::NEG_INFINITY;
        for &f in self.topo.vertex_faces(v) {
            let t = self.mesh.triangles()[f as usize];
            let Some(k) = t.iter().position(|&x| x == v) else {
                continue;
            };
            let n = self.face_normals[f as usize];
            if n == DVec3::ZERO {
                continue;
            }
            let dp = (dir - dir.dot(n) * n).normalize_or_zero();
            if dp == DVec3::ZERO {
                continue;
            }
            let a = (self.mesh.position(t[(k + 1) % 3]) - p).normalize_or_zero();
            let b = (self.mesh.position(t[(k + 2) % 3]) - p).normalize_or_zero();
            let inside = a.cross(dp).dot(n) >= 0.0 && dp.cross(b).dot(n) >= 0.0;
            // Prefer faces whose wedge holds the direction; among the others, the closest wedge.
            let score = if inside { 10.0 } else { 0.0 } + dp.dot((a + b).normalize_or_zero());
            if score > best_score {
                best_score = score;
                best = Some((f, k, dp));
            }
        }
        let Some((f, k, dp)) = best else {
            return Err(direction_error(format!(
                "no face incident to vertex {v} has a tangent plane the direction is not normal to"
            )));
        };
        let mut bary = DVec3::ZERO;
        bary[k] = 1.0;
        self.walk(SurfacePoint::new(f, bary), dp, length)
    }

    /// Walks `length` from a surface point along `dir` (projected on the start face's plane).
    pub fn walk_from_point(&self, sp: SurfacePoint, dir: DVec3, length: f64) -> Result<Walk> {
        check_walk_input(dir, length)?;
        self.mesh.check_surface_point(&sp)?;
        let n = self.face_normals[sp.face as usize];
        let dp = (dir - dir.dot(n) * n).normalize_or_zero();
        if dp == DVec3::ZERO {
            return Err(direction_error(format!(
                "walk direction is normal to face {}",
                sp.face
            )));
        }
        self.walk(sp, dp, length)
    }

    fn walk(&self, start: SurfacePoint, dir: DVec3, length: f64) -> Result<Walk> {
        let tris = self.mesh.triangles();
        let mut f = start.face;
        let mut b = start.bary;
        let mut d = dir;
        let mut walked = 0.0;
        let mut segments = Vec::new();
        let max_steps = 4 * self.mesh.n_faces() + 1000;
        for _ in 0..max_steps {
            let [c0, c1, c2] = self.mesh.face_corners(f);
            let (e1, e2) = (c1 - c0, c2 - c0);
            let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let det = g11 * g22 - g12 * g12;
            if det.abs() <= 1e-300 {
                return Err(GeodesicError::DegenerateFace(f));
            }
            let (r1, r2) = (d.dot(e1), d.dot(e2));
            let db1 = (g22 * r1 - g12 * r2) / det;
            let db2 = (g11 * r2 - g12 * r1) / det;
            let db = DVec3::new(-db1 - db2, db1, db2);
            let remaining = length - walked;
            let mut t_exit = f64::INFINITY;
            let mut k_exit = 3;
            for k in 0..3 {
                if db[k] < -1e-15 * (db.abs().max_element() + 1e-300) {
                    let t = (b[k].max(0.0)) / (-db[k]);
                    if t < t_exit {
                        t_exit = t;
                        k_exit = k;
                    }
                }
            }
            if t_exit >= remaining || k_exit == 3 {
                let nb = clamp_bary(b + db * remaining);
                segments.push(WalkSegment {
                    face: f,
                    from: b,
                    to: nb,
                    start: walked,
                    length: remaining,
                });
                let end = SurfacePoint::new(f, nb);
                return Ok(Walk {
                    position: self.mesh.point_position(&end)?,
                    end,
                    length,
                    truncated: false,
                    segments,
                });
            }
            let mut nb = b + db * t_exit;
            nb[k_exit] = 0.0;
            let mut nb = clamp_bary(nb);
            segments.push(WalkSegment {
                face: f,
                from: b,
                to: nb,
                start: walked,
                length: t_exit,
            });
            walked += t_exit;
            // Edge opposite corner k_exit joins corners k_exit+1 and k_exit+2 (side (k+1)%3).
            let (ka, kb) = ((k_exit + 1) % 3, (k_exit + 2) % 3);
            // Nudge off a vertex along the edge.
            let eps = 1e-9;
            if nb[ka] < eps {
                nb[ka] = eps;
                nb[kb] = 1.0 - eps;
            } else if nb[kb] < eps {
                nb[kb] = eps;
                nb[ka] = 1.0 - eps;
            }
            let edge = self.topo.face_edges()[f as usize][(k_exit + 1) % 3];
            let Some(g) = self.topo.opposite_face(edge, f) else {
                let end = SurfacePoint::new(f, nb);
                return Ok(Walk {
                    position: self.mesh.point_position(&end)?,
                    end,
                    length: walked,
                    truncated: true,
                    segments,
                });
            };
            let (va, vb) = (tris[f as usize][ka], tris[f as usize][kb]);
            let tg = tris[g as usize];
            let (Some(ga), Some(gb)) = (
                tg.iter().position(|&x| x == va),
                tg.iter().position(|&x| x == vb),
            ) else {
                return Err(walk_error(format!(
                    "faces {f} and {g} do not share edge ({va}, {vb})"
                )));
            };
            let mut gbary = DVec3::ZERO;
            gbary[ga] = nb[ka];
            gbary[gb] = nb[kb];
            // Unfold the direction about the shared edge.
            let e = (self.mesh.position(vb) - self.mesh.position(va)).normalize_or_zero();
            let (nf, ng) = (self.face_normals[f as usize], self.face_normals[g as usize]);
            let (wf, wg) = (nf.cross(e), ng.cross(e));
            let nd = (d.dot(e) * e + d.dot(wf) * wg).normalize_or_zero();
            if nd == DVec3::ZERO {
                return Err(walk_error(format!(
                    "walk direction vanished crossing into face {g}"
                )));
            }
            d = nd;
            f = g;
            b = gbary;
        }
        Err(walk_error(format!(
            "walk did not finish within {max_steps} face crossings"
        )))
    }
}

fn clamp_bary(b: DVec3) -> DVec3 {
    let c = b.max(DVec3::ZERO);
    let s = c.x + c.y + c.z;
    if s > 0.0 {
        c / s
    } else {
        DVec3::new(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::shapes::icosphere;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The shared jittered unit plane ([`testsupport::jittered_unit_plane`]).
    fn plane(n: usize, jitter: f64, seed: u64) -> TriMesh {
        testsupport::jittered_unit_plane(n, jitter, seed)
    }

    #[test]
    fn bad_input_is_an_error() {
        let m = plane(4, 0.0, 1);
        let w = Walker::new(&m);
        let v = 2 * 5 + 2;
        let inside = SurfacePoint::new(0, DVec3::splat(1.0 / 3.0));
        // Off the mesh: a vertex or face that does not exist, barycentrics that do not sum to 1.
        assert!(matches!(
            w.walk_from_vertex(99, DVec3::X, 0.1),
            Err(GeodesicError::Mesh(_))
        ));
        for sp in [
            SurfacePoint::new(999, DVec3::splat(1.0 / 3.0)),
            SurfacePoint::new(0, DVec3::new(2.0, 0.0, 0.0)),
            SurfacePoint::new(0, DVec3::new(f64::NAN, 0.5, 0.5)),
        ] {
            assert!(matches!(
                w.walk_from_point(sp, DVec3::X, 0.1),
                Err(GeodesicError::Mesh(_))
            ));
        }
        // Zero, NaN, infinite and normal directions.
        for d in [
            DVec3::ZERO,
            DVec3::new(f64::NAN, 0.0, 0.0),
            DVec3::new(f64::INFINITY, 0.0, 0.0),
            DVec3::Z,
        ] {
            assert!(matches!(
                w.walk_from_vertex(v, d, 0.1),
                Err(GeodesicError::InvalidDirection(_))
            ));
            assert!(matches!(
                w.walk_from_point(inside, d, 0.1),
                Err(GeodesicError::InvalidDirection(_))
            ));
        }
        // Negative and non-finite lengths.
        for len in [-0.1, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                w.walk_from_vertex(v, DVec3::X, len),
                Err(GeodesicError::InvalidLength(_))
            ));
            assert!(matches!(
                w.walk_from_point(inside, DVec3::X, len),
                Err(GeodesicError::InvalidLength(_))
            ));
        }
        let p = m.position(v);
        assert!(Walker::tangent_direction(p, DVec3::Z, p, 0.0).is_err());
        assert!(Walker::tangent_direction(p, DVec3::Z, p + DVec3::Z, 0.0).is_err());
        assert!(Walker::tangent_direction(p, DVec3::Z, p + DVec3::X, f64::NAN).is_err());
        // A zero length is a walk that stays where it started.
        let r = w.walk_from_vertex(v, DVec3::X, 0.0).unwrap();
        assert!((r.position - p).length() < 1e-12 && !r.truncated);
    }

    #[test]
    fn plane_walk_lands_at_euclidean_position() {
        let m = plane(20, 0.3, 7);
        let w = Walker::new(&m);
        let v = 10 * 21 + 10; // centre vertex
        let p = m.position(v);
        for k in 0..16 {
            let theta = k as f64 * std::f64::consts::TAU / 16.0 + 0.01;
            let dir = Walker::tangent_direction(p, DVec3::Z, p + DVec3::X, theta).unwrap();
            let r = w.walk_from_vertex(v, dir, 0.37).unwrap();
            let expect = p + 0.37 * DVec3::new(theta.cos(), theta.sin(), 0.0);
            assert!(!r.truncated);
            assert!(
                (r.position - expect).length() < 1e-9,
                "theta {theta}: {:?} vs {expect:?}",
                r.position
            );
            let total: f64 = r.segments.iter().map(|s| s.length).sum();
            assert!((total - 0.37).abs() < 1e-12);
        }
        // Through a grid vertex exactly (diagonal of the unjittered grid) is nudged, not stuck.
        let m = plane(10, 0.0, 1);
        let w = Walker::new(&m);
        let r = w
            .walk_from_vertex(0, DVec3::new(1.0, 1.0, 0.0).normalize(), 1.0)
            .unwrap();
        assert!((r.position - DVec3::new(1.0, 1.0, 0.0) / 2f64.sqrt()).length() < 1e-7);
    }

    #[test]
    fn plane_walk_stops_at_the_boundary() {
        let m = plane(10, 0.2, 3);
        let w = Walker::new(&m);
        let v = 5 * 11 + 5;
        let p = m.position(v);
        let r = w.walk_from_vertex(v, DVec3::X, 2.0).unwrap();
        assert!(r.truncated);
        assert!((r.position.x - 1.0).abs() < 1e-9 && (r.position.y - p.y).abs() < 1e-9);
        assert!((r.length - (1.0 - p.x)).abs() < 1e-9);
    }

    #[test]
    fn folded_plane_walk_is_straight_in_the_unfolding() {
        // Plane folded along x = 0.5 by 40 degrees: the part x > 0.5 is rotated about the crease.
        let flat = plane(16, 0.25, 11);
        let a = 40f64.to_radians();
        let fold = |q: DVec3| {
            if q.x <= 0.5 {
                q
            } else {
                let u = q.x - 0.5;
                DVec3::new(0.5 + u * a.cos(), q.y, u * a.sin())
            }
        };
        let (pos, tri) = flat.clone().into_parts();
        // Put the crease on grid lines: x = 0.5 is a grid line of the 16-cell grid, but jitter
        // moved interior vertices; snap the crease column back.
        let pos: Vec<DVec3> = pos
            .into_iter()
            .enumerate()
            .map(|(i, q)| {
                if i % 17 == 8 {
                    DVec3::new(0.5, q.y, 0.0)
                } else {
                    q
                }
            })
            .collect();
        let flat = TriMesh::new(pos.clone(), tri.clone()).unwrap();
        let folded = TriMesh::new(pos.iter().map(|&q| fold(q)).collect(), tri).unwrap();
        let (wf, wu) = (Walker::new(&folded), Walker::new(&flat));
        let v = 8 * 17 + 3;
        for theta in [-0.6f64, -0.2, 0.1, 0.5] {
            let d = DVec3::new(theta.cos(), theta.sin(), 0.0);
            let rf = wf.walk_from_vertex(v, d, 0.6).unwrap();
            let ru = wu.walk_from_vertex(v, d, 0.6).unwrap();
            // Same face and barycentrics as on the flat plane, so the folded position is fold(flat).
            assert_eq!(rf.end.face, ru.end.face);
            assert!((rf.position - fold(ru.position)).length() < 1e-9);
            assert!(rf.position.z > 0.01, "the walk must cross the crease");
        }
    }

    #[test]
    fn sphere_walk_lands_near_great_circle_position() {
        let m = icosphere(5);
        let w = Walker::new(&m);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut worst: f64 = 0.0;
        for _ in 0..12 {
            let v = rng.random_range(0..m.n_vertices() as u32);
            let p = m.position(v);
            let n = p.normalize();
            let towards = DVec3::new(0.3, -0.7, 0.2);
            let theta = rng.random_range(0.0..std::f64::consts::TAU);
            let t = Walker::tangent_direction(p, n, towards, theta).unwrap();
            let len = 1.2;
            let r = w.walk_from_vertex(v, t, len).unwrap();
            let expect = p * len.cos() + t * len.sin();
            worst = worst.max((r.position - expect).length());
        }
        // Level 5: edge ~0.03; a polyhedral straightest path drifts by a fraction of that.
        assert!(worst < 0.02, "worst great-circle error {worst}");
    }
}
