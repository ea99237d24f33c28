//! The single-pole representation (geodesic polar coordinates around the nose tip, after
//! Gadacha and Ghorbel): points at geodesic radius levels `i * step` (i = 1..=levels) on
//! `sectors` rays leaving the pole at angles `2 pi k / sectors` from a reference direction.
//!
//! Each ray is a straightest geodesic (see [`super::walk`]); its point for level `i` is where
//! the solver's distance field from the pole first reaches `i * step` along the ray, so the
//! radius comes from the same geodesic solver as the bipolar descriptor (exact or Dijkstra) and
//! the angle from the ray. Keys are `(level, sector)`, so the keyed distance applies unchanged.
//! The angular origin is the direction towards a second point (here the midpoint of the two
//! outer eye corners), projected on the tangent plane at the pole.

use super::keyed::KeyedPoints;
use super::walk::Walker;
use anyhow::Result;
use meshcore::{DVec3, SurfacePoint};

/// Where the pole is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pole {
    /// A mesh vertex.
    Vertex(u32),
    /// A surface point.
    Point(SurfacePoint),
}

/// Options of [`polar_descriptor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarOptions {
    /// Geodesic step between radius levels.
    pub step: f64,
    /// Number of radius levels.
    pub levels: u32,
    /// Number of angular sectors (rays).
    pub sectors: u32,
}

/// Packs a polar key `(level, sector)` (bit 62 set, so it never equals a bipolar grid key).
pub fn polar_key(level: u32, sector: u32) -> u64 {
    (1u64 << 62) | (u64::from(level) << 32) | u64::from(sector)
}

/// Unpacks a polar key.
pub fn polar_key_parts(k: u64) -> (u32, u32) {
    (((k >> 32) & 0x3fff_ffff) as u32, (k & 0xffff_ffff) as u32)
}

/// The single-pole descriptor; `u` is the distance field from the pole (per vertex) and
/// `towards` fixes the angular origin. Levels a ray does not reach (boundary) are missing.
pub fn polar_descriptor(
    walker: &Walker<'_>,
    u: &[f64],
    pole: Pole,
    towards: DVec3,
    opts: &PolarOptions,
) -> Result<KeyedPoints> {
    let mesh = walker.mesh();
    // A surface point sitting on a vertex is that vertex (the wedge choice there differs from
    // projecting on one incident face).
    let pole = match pole {
        Pole::Point(sp) => {
            let t = mesh.triangles()[sp.face as usize];
            match (0..3).find(|&k| sp.bary[k] >= 1.0 - 1e-9) {
                Some(k) => Pole::Vertex(t[k]),
                None => pole,
            }
        }
        v => v,
    };
    let (p, n) = match pole {
        Pole::Vertex(v) => (mesh.try_position(v)?, walker.vertex_normal(v)),
        Pole::Point(sp) => (mesh.point_position(&sp)?, walker.point_normal(&sp)),
    };
    let rmax = opts.step * f64::from(opts.levels);
    let mut pairs = Vec::new();
    for k in 0..opts.sectors {
        let theta = std::f64::consts::TAU * f64::from(k) / f64::from(opts.sectors);
        let dir = Walker::tangent_direction(p, n, towards, theta)?;
        // A ray is at least as long as the distance it reaches; 2x covers the detours.
        let walk = match pole {
            Pole::Vertex(v) => walker.walk_from_vertex(v, dir, 2.0 * rmax)?,
            Pole::Point(sp) => walker.walk_from_point(sp, dir, 2.0 * rmax)?,
        };
        let mut next = 1u32;
        for seg in &walk.segments {
            let t = mesh.triangles()[seg.face as usize];
            let uf = DVec3::new(u[t[0] as usize], u[t[1] as usize], u[t[2] as usize]);
            if !uf.is_finite() {
                break;
            }
            let (ua, ub) = (seg.from.dot(uf), seg.to.dot(uf));
            while next <= opts.levels {
                let c = opts.step * f64::from(next);
                if ub.is_nan() || ub < c {
                    break;
                }
                let s = if ub > ua {
                    ((c - ua) / (ub - ua)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let b = seg.from + s * (seg.to - seg.from);
                let sp = SurfacePoint::new(seg.face, b);
                pairs.push((polar_key(next, k), mesh.point_position(&sp)?));
                next += 1;
            }
            if next > opts.levels {
                break;
            }
        }
    }
    Ok(KeyedPoints::from_pairs(pairs, 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::walk::tests::plane;
    use meshcore::shapes::icosphere;

    #[test]
    fn keys_round_trip() {
        for (l, s) in [(0, 0), (1, 7), (30, 63), (1000, 1)] {
            assert_eq!(polar_key_parts(polar_key(l, s)), (l, s));
        }
        assert_ne!(polar_key(1, 2), polar_key(2, 1));
    }

    #[test]
    fn plane_polar_points_are_on_circles_at_their_angles() {
        let m = plane(30, 0.3, 2);
        let w = Walker::new(&m);
        let v = 15 * 31 + 15;
        let c = m.position(v);
        let u: Vec<f64> = m.positions().iter().map(|p| (*p - c).length()).collect();
        let opts = PolarOptions {
            step: 0.08,
            levels: 4,
            sectors: 8,
        };
        let d = polar_descriptor(&w, &u, Pole::Vertex(v), c + DVec3::Y, &opts).unwrap();
        assert_eq!(d.len(), 32);
        for k in 0..d.len() {
            let (lvl, sec) = polar_key_parts(d.keys[k]);
            let theta = std::f64::consts::TAU * f64::from(sec) / 8.0;
            // Angle origin +y, counter-clockwise about +z: direction (-sin, cos).
            let expect = c + 0.08 * f64::from(lvl) * DVec3::new(-theta.sin(), theta.cos(), 0.0);
            // PL distance field: radius error O(h^2 / r).
            assert!(
                (d.points[k] - expect).length() < 5e-3,
                "{lvl} {sec} {:?} {expect:?}",
                d.points[k]
            );
        }
    }

    #[test]
    fn sphere_polar_points_match_geodesic_polar_coordinates() {
        let m = icosphere(4);
        let w = Walker::new(&m);
        let pole = 0u32;
        let c = m.position(pole);
        let u: Vec<f64> = m
            .positions()
            .iter()
            .map(|p| p.dot(c).clamp(-1.0, 1.0).acos())
            .collect();
        let opts = PolarOptions {
            step: 0.25,
            levels: 4,
            sectors: 6,
        };
        let towards = DVec3::new(0.0, 0.0, 1.0);
        let d = polar_descriptor(&w, &u, Pole::Vertex(pole), towards, &opts).unwrap();
        assert_eq!(d.len(), 24);
        let n = w.vertex_normal(pole);
        for k in 0..d.len() {
            let (lvl, sec) = polar_key_parts(d.keys[k]);
            let theta = std::f64::consts::TAU * f64::from(sec) / 6.0;
            let t = Walker::tangent_direction(c, n, towards, theta).unwrap();
            let r = 0.25 * f64::from(lvl);
            let expect = c * r.cos() + t * r.sin();
            assert!((d.points[k] - expect).length() < 0.03, "{lvl} {sec}");
        }
    }
}

#[cfg(test)]
mod face_tests {
    use super::*;
    use facemodel::load_face_set;
    use geodesic::{Method, SolveOptions, Source};

    #[test]
    fn pole_as_vertex_or_as_point_agree_on_a_face() {
        let dir = testsupport::require_shared!(testsupport::PAPER_SET);
        let faces = load_face_set(&dir).unwrap();
        let f = &faces[0];
        let m = &f.mesh;
        let s = geodesic::new_solver(m, Method::Dijkstra).unwrap();
        let v = f.landmarks.nose_tip;
        let topo = meshcore::Topology::new(m);
        let face = topo.vertex_faces(v)[0];
        let k = m.triangles()[face as usize]
            .iter()
            .position(|&x| x == v)
            .unwrap();
        let mut b = DVec3::ZERO;
        b[k] = 1.0;
        let sp = SurfacePoint::new(face, b);
        let w = Walker::new(m);
        let towards = 0.5
            * (m.position(f.landmarks.right_eye_outer) + m.position(f.landmarks.left_eye_outer));
        let opts = PolarOptions {
            step: 1.0,
            levels: 10,
            sectors: 16,
        };
        let u1 = s
            .distances(&[Source::Vertex(v)], &SolveOptions::default())
            .unwrap();
        let u2 = s
            .distances(&[Source::Point(sp)], &SolveOptions::default())
            .unwrap();
        let a = polar_descriptor(&w, &u1, Pole::Vertex(v), towards, &opts).unwrap();
        let c = polar_descriptor(&w, &u2, Pole::Point(sp), towards, &opts).unwrap();
        let ((ka, pa), (kc, pc)) = (a.unambiguous(), c.unambiguous());
        let d = shapedist::keyed_distance(&ka, &pa, &kc, &pc, &Default::default()).unwrap();
        assert_eq!(d.shared_keys, a.len());
        assert!(d.distance < 1e-12, "{}", d.distance);
    }
}
