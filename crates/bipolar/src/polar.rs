//! The single-pole representation (geodesic polar coordinates around the nose tip, after
//! Gadacha and Ghorbel): points at geodesic radius levels `i * step` (i = 1..=levels) on
//! `sectors` rays leaving the pole at angles `2 pi k / sectors` from a reference direction.
//!
//! Each ray is a straightest geodesic ([`geodesic::straightest`]); its point for level `i` is
//! where the solver's distance field from the pole first reaches `i * step` along the ray, so the
//! radius comes from the same geodesic solver as the bipolar descriptor (exact or Dijkstra) and
//! the angle from the ray. Keys are `(level, sector)` ([`PolarKey`]), packed into a `u64` that
//! never equals a [`crate::Key::pack`] value, so the keyed distances of `shapedist` apply
//! unchanged. The angular origin is the direction towards a second point (for faces the
//! midpoint of the two outer eye corners), projected on the tangent plane at the pole.

use crate::BipolarError;
use geodesic::{Source, Walker};
use glam::DVec3;
use meshcore::SurfacePoint;

/// Options of [`describe_polar`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarOptions {
    /// Geodesic step between radius levels (positive, finite).
    pub step: f64,
    /// Number of radius levels, `1..=PolarKey::MAX_LEVEL`.
    pub levels: u32,
    /// Number of angular sectors (rays), at least 1.
    pub sectors: u32,
}

/// The key of a polar point: radius level and angular sector.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PolarKey {
    /// Radius level `i` (the point is at geodesic distance `i * step` from the pole).
    pub level: u32,
    /// Sector `k` (the ray leaves the pole at angle `2 pi k / sectors`).
    pub sector: u32,
}

impl PolarKey {
    /// Largest level [`PolarKey::pack`] stores without loss (30 bits).
    pub const MAX_LEVEL: u32 = 0x3fff_ffff;

    /// Packs the key: bit 62 set, `level` in bits 32..62, `sector` in bits 0..32. Order
    /// preserving; never equal to a [`crate::Key::pack`] value of the bipolar descriptor.
    pub fn pack(self) -> u64 {
        (1u64 << 62) | (u64::from(self.level & Self::MAX_LEVEL) << 32) | u64::from(self.sector)
    }

    /// Inverse of [`PolarKey::pack`].
    pub fn unpack(k: u64) -> Self {
        Self {
            level: ((k >> 32) & u64::from(Self::MAX_LEVEL)) as u32,
            sector: (k & 0xffff_ffff) as u32,
        }
    }
}

/// One point of the polar descriptor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarPoint {
    /// Its key.
    pub key: PolarKey,
    /// Position.
    pub position: DVec3,
    /// Face holding the point.
    pub face: u32,
    /// Barycentric coordinates in that face.
    pub bary: DVec3,
}

/// The single-pole descriptor: points sorted by key, at most one per key.
#[derive(Debug, Clone, PartialEq)]
pub struct PolarDescriptor {
    /// The points, sorted by key.
    pub points: Vec<PolarPoint>,
    /// The options it was built with.
    pub options: PolarOptions,
}

impl PolarDescriptor {
    /// Packed keys, in point order (the `keys` input of `shapedist`).
    pub fn keys(&self) -> Vec<u64> {
        self.points.iter().map(|p| p.key.pack()).collect()
    }

    /// Positions, in point order.
    pub fn positions(&self) -> Vec<DVec3> {
        self.points.iter().map(|p| p.position).collect()
    }
}

fn check_polar_input(
    n_vertices: usize,
    field: &[f64],
    towards: DVec3,
    opts: &PolarOptions,
) -> Result<(), BipolarError> {
    crate::build::check_field(0, field, n_vertices)?;
    let bad = |m: String| Err(BipolarError::InvalidOption(m));
    if !(opts.step.is_finite() && opts.step > 0.0) {
        return bad(format!(
            "polar step {} (must be positive and finite)",
            opts.step
        ));
    }
    if opts.levels == 0 || opts.levels > PolarKey::MAX_LEVEL {
        return bad(format!(
            "{} polar levels (must be in 1..={})",
            opts.levels,
            PolarKey::MAX_LEVEL
        ));
    }
    if opts.sectors == 0 {
        return bad("the number of polar sectors must be at least 1".into());
    }
    if !towards.is_finite() {
        return bad(format!(
            "polar reference direction point {towards} is not finite"
        ));
    }
    Ok(())
}

/// The single-pole descriptor of the walker's mesh around `pole`; `field` is the distance field
/// from the pole (one value per vertex, `+inf` where unreachable) and `towards` fixes the
/// angular origin. Levels a ray does not reach (boundary, unreachable vertices) are missing.
///
/// Errors: a field of the wrong length or with NaN / `-inf` values, options out of range, a
/// pole off the mesh, a reference direction along the normal ([`BipolarError::Geodesic`] from
/// the walk), and [`BipolarError::NoIntersections`] when no ray reaches level 1.
pub fn describe_polar(
    walker: &Walker<'_>,
    field: &[f64],
    pole: Source,
    towards: DVec3,
    opts: &PolarOptions,
) -> Result<PolarDescriptor, BipolarError> {
    let mesh = walker.mesh();
    check_polar_input(mesh.n_vertices(), field, towards, opts)?;
    let u = field;
    // A surface point sitting on a vertex is that vertex (the wedge choice there differs from
    // projecting on one incident face).
    let pole = match pole {
        Source::Point(sp) => {
            mesh.check_surface_point(&sp)?;
            let t = mesh.triangles()[sp.face as usize];
            match (0..3).find(|&k| sp.bary[k] >= 1.0 - 1e-9) {
                Some(k) => Source::Vertex(t[k]),
                None => pole,
            }
        }
        v => v,
    };
    let (p, n) = match pole {
        Source::Vertex(v) => (mesh.try_position(v)?, walker.vertex_normal(v)),
        Source::Point(sp) => (mesh.point_position(&sp)?, walker.point_normal(&sp)),
    };
    let rmax = opts.step * f64::from(opts.levels);
    let mut points = Vec::new();
    for k in 0..opts.sectors {
        let theta = std::f64::consts::TAU * f64::from(k) / f64::from(opts.sectors);
        let dir = Walker::tangent_direction(p, n, towards, theta)?;
        // A ray is at least as long as the distance it reaches; 2x covers the detours.
        let walk = match pole {
            Source::Vertex(v) => walker.walk_from_vertex(v, dir, 2.0 * rmax)?,
            Source::Point(sp) => walker.walk_from_point(sp, dir, 2.0 * rmax)?,
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
                points.push(PolarPoint {
                    key: PolarKey {
                        level: next,
                        sector: k,
                    },
                    position: mesh.point_position(&sp)?,
                    face: seg.face,
                    bary: b,
                });
                next += 1;
            }
            if next > opts.levels {
                break;
            }
        }
    }
    if points.is_empty() {
        return Err(BipolarError::NoIntersections(format!(
            "no ray of the polar descriptor reaches level 1 (step {:e})",
            opts.step
        )));
    }
    // One point per key (each ray reaches each level once), so sorting by key is total.
    points.sort_by_key(|p| p.key);
    Ok(PolarDescriptor {
        points,
        options: *opts,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::shapes::icosphere;
    use meshcore::TriMesh;

    /// `PolarOptions` from its three fields.
    pub(super) fn options(step: f64, levels: u32, sectors: u32) -> PolarOptions {
        PolarOptions {
            step,
            levels,
            sectors,
        }
    }

    /// The shared jittered unit plane of `n` cells a side ([`testsupport::jittered_unit_plane`],
    /// `n` even), its centre vertex, that vertex's position and the Euclidean distance from it.
    fn centred_plane(n: usize, jitter: f64, seed: u64) -> (TriMesh, u32, DVec3, Vec<f64>) {
        let m = testsupport::jittered_unit_plane(n, jitter, seed);
        let v = (n / 2 * (n + 1) + n / 2) as u32;
        let c = m.position(v);
        let u = m.positions().iter().map(|p| (*p - c).length()).collect();
        (m, v, c, u)
    }

    fn parts(k: u64) -> (u32, u32) {
        let k = PolarKey::unpack(k);
        (k.level, k.sector)
    }

    #[test]
    fn keys_round_trip() {
        for (level, sector) in [(0, 0), (1, 7), (30, 63), (1000, 1)] {
            let k = PolarKey { level, sector };
            assert_eq!(PolarKey::unpack(k.pack()), k);
        }
        let k = |level, sector| PolarKey { level, sector }.pack();
        assert_ne!(k(1, 2), k(2, 1));
        assert!(k(1, 9) < k(2, 0));
        // Bit 62 set: never a bipolar key (whose top byte is the reference index a < 255).
        assert_ne!(k(1, 1) >> 62, 0);
    }

    #[test]
    fn bad_input_is_an_error() {
        let (m, v, c, u) = centred_plane(6, 0.0, 1);
        let w = Walker::new(&m);
        let opts = options(0.1, 2, 4);
        let run =
            |u: &[f64], pole, towards, o: &PolarOptions| describe_polar(&w, u, pole, towards, o);
        let towards = c + DVec3::Y;
        assert!(run(&u, Source::Vertex(v), towards, &opts).is_ok());
        assert!(matches!(
            run(&u[1..], Source::Vertex(v), towards, &opts),
            Err(BipolarError::FieldLength { .. })
        ));
        let mut nan = u.clone();
        nan[5] = f64::NAN;
        assert!(matches!(
            run(&nan, Source::Vertex(v), towards, &opts),
            Err(BipolarError::NonFiniteField { vertex: 5, .. })
        ));
        for o in [
            PolarOptions { step: 0.0, ..opts },
            PolarOptions {
                step: f64::NAN,
                ..opts
            },
            PolarOptions { levels: 0, ..opts },
            PolarOptions { sectors: 0, ..opts },
        ] {
            assert!(matches!(
                run(&u, Source::Vertex(v), towards, &o),
                Err(BipolarError::InvalidOption(_))
            ));
        }
        assert!(run(&u, Source::Vertex(999), towards, &opts).is_err());
        let off = SurfacePoint::new(999, DVec3::splat(1.0 / 3.0));
        assert!(run(&u, Source::Point(off), towards, &opts).is_err());
        // Towards the pole itself or along the normal: no angular origin.
        assert!(matches!(
            run(&u, Source::Vertex(v), c, &opts),
            Err(BipolarError::Geodesic(_))
        ));
        assert!(run(&u, Source::Vertex(v), c + DVec3::Z, &opts).is_err());
        // Nothing reachable: no point, an error rather than an empty descriptor.
        let far = vec![f64::INFINITY; u.len()];
        assert!(matches!(
            run(&far, Source::Vertex(v), towards, &opts),
            Err(BipolarError::NoIntersections(_))
        ));
    }

    #[test]
    fn plane_polar_points_are_on_circles_at_their_angles() {
        let (m, v, c, u) = centred_plane(30, 0.3, 2);
        let w = Walker::new(&m);
        let opts = options(0.08, 4, 8);
        let d = describe_polar(&w, &u, Source::Vertex(v), c + DVec3::Y, &opts).unwrap();
        assert_eq!(d.points.len(), 32);
        let (keys, points) = (d.keys(), d.positions());
        for k in 0..keys.len() {
            let (lvl, sec) = parts(keys[k]);
            let theta = std::f64::consts::TAU * f64::from(sec) / 8.0;
            // Angle origin +y, counter-clockwise about +z: direction (-sin, cos).
            let expect = c + 0.08 * f64::from(lvl) * DVec3::new(-theta.sin(), theta.cos(), 0.0);
            // PL distance field: radius error O(h^2 / r).
            assert!(
                (points[k] - expect).length() < 5e-3,
                "{lvl} {sec} {:?} {expect:?}",
                points[k]
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
        let opts = options(0.25, 4, 6);
        let towards = DVec3::new(0.0, 0.0, 1.0);
        let d = describe_polar(&w, &u, Source::Vertex(pole), towards, &opts).unwrap();
        assert_eq!(d.points.len(), 24);
        let n = w.vertex_normal(pole);
        for p in &d.points {
            let (lvl, sec) = (p.key.level, p.key.sector);
            let theta = std::f64::consts::TAU * f64::from(sec) / 6.0;
            let t = Walker::tangent_direction(c, n, towards, theta).unwrap();
            let r = 0.25 * f64::from(lvl);
            let expect = c * r.cos() + t * r.sin();
            assert!((p.position - expect).length() < 0.03, "{lvl} {sec}");
        }
    }
}

#[cfg(test)]
mod face_tests {
    use super::*;
    use facemodel::load_face_set;
    use geodesic::{Method, SolveOptions};

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
        let opts = super::tests::options(1.0, 10, 16);
        let u1 = s
            .distances(&[Source::Vertex(v)], &SolveOptions::default())
            .unwrap();
        let u2 = s
            .distances(&[Source::Point(sp)], &SolveOptions::default())
            .unwrap();
        let a = describe_polar(&w, &u1, Source::Vertex(v), towards, &opts).unwrap();
        let c = describe_polar(&w, &u2, Source::Point(sp), towards, &opts).unwrap();
        // The point on a vertex is that vertex: same keys, same positions.
        assert_eq!(a.keys(), c.keys());
        assert!(a.points.len() > 100, "{} points", a.points.len());
        let worst = a
            .points
            .iter()
            .zip(&c.points)
            .map(|(p, q)| (p.position - q.position).length())
            .fold(0.0f64, f64::max);
        assert!(worst < 1e-9, "{worst}");
    }
}
