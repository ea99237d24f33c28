//! Synthetic meshes for tests, benchmarks and validation (the generators of
//! `meshcore::shapes`; their analytic distance fields are `testsupport::fields`), and the
//! analytic bipolar representation of the unit sphere ([`sphere_truth`]) with the comparison of
//! a mesh descriptor against it ([`SphereErrors`]): the oracle of the paper's section 3.

pub use meshcore::shapes::{grid_plane, icosphere, uv_sphere};

use crate::{Descriptor, Key, SelectionRule};
use glam::DVec3;
use std::collections::{BTreeMap, HashMap};

/// The analytic points of a rule on the unit sphere: key -> (position, cosine of the opening).
pub type SphereTruth = BTreeMap<Key, (DVec3, f64)>;

/// The analytic bipolar representation of the unit sphere with poles `r = +Z` and `q = +X`
/// (geodesic distance `pi / 2`) for `rule`, with `n` levels between the poles (step
/// `pi / (2 n)`), levels `1..=max_level` of both fields, and `angles` = K angle levels up to the
/// opening `alpha` (iso-angle and filter rules):
///
/// * grid points (rules `All` and `Filter`): the level circles `z = cos a` and `x = cos b` meet
///   at `y = +-sqrt(1 - z^2 - x^2)`, where the spherical law of cosines gives the opening
///   `cos = -cot a cot b`; `Filter` keeps those within its tolerance of an angle level;
/// * iso-angle points: on the circle of level `i` (`a = i step`), `cos = +-alpha k / K` is met
///   where `cot b = -cos tan a`, one point on each side.
///
/// Keys are those [`crate::describe`] gives a two-pole descriptor (pair `(0, 1)`).
pub fn sphere_truth(
    rule: SelectionRule,
    n: u32,
    max_level: u32,
    angles: u32,
    alpha: f64,
) -> SphereTruth {
    let step = std::f64::consts::FRAC_PI_2 / f64::from(n.max(1));
    let mut out = BTreeMap::new();
    for i in 1..=max_level {
        let a = f64::from(i) * step;
        if a >= std::f64::consts::PI {
            continue;
        }
        match rule {
            SelectionRule::All | SelectionRule::Filter { .. } => {
                grid_points(&mut out, rule, (i, a), step, max_level, (angles, alpha));
            }
            SelectionRule::IsoAngle => {
                iso_angle_points(&mut out, (i, a), step, max_level, (angles, alpha));
            }
        }
    }
    out
}

/// Side of `p` (+1 or -1) relative to the pole pair, as the descriptor keys it.
fn side_of(p: DVec3) -> i8 {
    // Away-from-r direction: -(r - (r.p) p); away from q likewise.
    let ar = -(DVec3::Z - p.z * p);
    let aq = -(DVec3::X - p.x * p);
    if p.dot(ar.cross(aq)) > 0.0 {
        1
    } else {
        -1
    }
}

/// The key of level `i` of r, `j` of q (or angle level `j`), at `p`.
fn key_at(p: DVec3, i: u32, j: u32, sign: i8) -> Key {
    let side = side_of(p);
    Key {
        a: 0,
        b: 1,
        i,
        j,
        side,
        sign,
    }
}

/// The grid intersections of level `i` of r (distance `a`) with every level of q.
fn grid_points(
    out: &mut SphereTruth,
    rule: SelectionRule,
    (i, a): (u32, f64),
    step: f64,
    max_level: u32,
    (k, alpha): (u32, f64),
) {
    for j in 1..=max_level {
        let b = f64::from(j) * step;
        let (z, x) = (a.cos(), b.cos());
        let y2 = 1.0 - z * z - x * x;
        if y2 <= 1e-12 {
            continue;
        }
        let cos = -(a.cos() / a.sin()) * (b.cos() / b.sin());
        if let SelectionRule::Filter { tolerance } = rule {
            let c = cos.abs();
            let ks = (c * f64::from(k) / alpha).round();
            if ks > f64::from(k) || (c - alpha * ks / f64::from(k)).abs() > tolerance {
                continue;
            }
        }
        for s in [1.0, -1.0] {
            let p = DVec3::new(x, s * y2.sqrt(), z);
            out.insert(key_at(p, i, j, 0), (p, cos));
        }
    }
}

/// The iso-angle points of level `i` of r (distance `a`).
fn iso_angle_points(
    out: &mut SphereTruth,
    (i, a): (u32, f64),
    step: f64,
    max_level: u32,
    (k_max, alpha): (u32, f64),
) {
    let bmax = f64::from(max_level) * step;
    for k in 0..=k_max {
        let c = alpha * f64::from(k) / f64::from(k_max);
        let targets: &[(f64, i8)] = if k == 0 {
            &[(0.0, 0)]
        } else {
            &[(c, 1), (-c, -1)]
        };
        for &(t, sign) in targets {
            // cos = -cot a cot b  =>  cot b = -t / cot a = -t tan a.
            let b = std::f64::consts::FRAC_PI_2 - (-t * a.tan()).atan();
            if b.is_nan() || b <= 0.0 || b > bmax {
                continue;
            }
            let cphi = b.cos() / a.sin();
            if cphi.abs() >= 1.0 {
                continue;
            }
            let phi = cphi.acos();
            for s in [1.0, -1.0] {
                let p = DVec3::new(a.sin() * phi.cos(), s * a.sin() * phi.sin(), a.cos());
                out.insert(key_at(p, i, k, sign), (p, t));
            }
        }
    }
}

/// How a descriptor of the unit sphere (poles `+Z`, `+X`) compares with [`sphere_truth`] over
/// the keys found once, unambiguous, in the descriptor and present in the truth.
#[derive(Debug, Clone, Default)]
pub struct SphereErrors {
    /// The descriptor's points of the common keys, in descriptor order.
    pub mesh_points: Vec<DVec3>,
    /// The analytic points of the same keys.
    pub truth_points: Vec<DVec3>,
    /// Mean distance between the two (NaN with no common key).
    pub pos_err: f64,
    /// Mean `|cos_mesh - cos_exact(P_mesh)|`, `cos_exact` the spherical law of cosines at the
    /// mesh point's direction (for iso-angle points the cosine is the target by construction,
    /// so their error shows in the positions); NaN with no common key.
    pub cos_err: f64,
    /// Largest such cosine error (NaN with no common key).
    pub cos_err_max: f64,
}

impl SphereErrors {
    /// Compares `d` with `truth`.
    pub fn of(d: &Descriptor, truth: &SphereTruth) -> Self {
        let mut e = SphereErrors::default();
        let (mut pos, mut cerr, mut cmax) = (0.0, 0.0, 0.0f64);
        let mut counts: HashMap<Key, usize> = HashMap::new();
        for p in &d.points {
            *counts.entry(p.key).or_default() += 1;
        }
        for p in &d.points {
            if p.ambiguous || counts[&p.key] > 1 {
                continue;
            }
            if let Some((t, _)) = truth.get(&p.key) {
                e.mesh_points.push(p.position);
                e.truth_points.push(*t);
                pos += (p.position - *t).length();
                let q = p.position.normalize();
                let (aa, bb) = (q.z.clamp(-1.0, 1.0).acos(), q.x.clamp(-1.0, 1.0).acos());
                let exact_here = -(aa.cos() / aa.sin()) * (bb.cos() / bb.sin());
                let err = (p.cos - exact_here).abs();
                cerr += err;
                cmax = cmax.max(err);
            }
        }
        let n = e.mesh_points.len();
        if n == 0 {
            (e.pos_err, e.cos_err, e.cos_err_max) = (f64::NAN, f64::NAN, f64::NAN);
        } else {
            (e.pos_err, e.cos_err, e.cos_err_max) = (pos / n as f64, cerr / n as f64, cmax);
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{describe, DescriptorOptions, Fields, LevelSpec, Source, Surface, TangentMethod};
    use meshcore::{FaceLocator, Topology};

    #[test]
    fn sphere_truth_points_sit_on_their_levels_and_openings() {
        let (n, k, alpha) = (4, 8, 0.95);
        let step = std::f64::consts::FRAC_PI_2 / f64::from(n);
        let grid = sphere_truth(SelectionRule::All, n, 2 * n - 1, k, alpha);
        assert!(grid.len() > 20);
        for (key, (p, cos)) in &grid {
            assert!((p.length() - 1.0).abs() < 1e-12);
            assert!((p.z.acos() - f64::from(key.i) * step).abs() < 1e-9);
            assert!((p.x.acos() - f64::from(key.j) * step).abs() < 1e-9);
            let (a, b) = (p.z.acos(), p.x.acos());
            assert!((cos + a.cos() * b.cos() / (a.sin() * b.sin())).abs() < 1e-9);
            assert_eq!(key.side, side_of(*p));
        }
        let filter = sphere_truth(
            SelectionRule::Filter { tolerance: 0.03 },
            n,
            2 * n - 1,
            k,
            alpha,
        );
        assert!(!filter.is_empty() && filter.len() < grid.len());
        for (key, (_, cos)) in sphere_truth(SelectionRule::IsoAngle, n, 2 * n - 1, k, alpha) {
            let target = alpha * f64::from(key.j) / f64::from(k) * f64::from(key.sign);
            assert!((cos - target).abs() < 1e-12, "{key:?}");
        }
    }

    #[test]
    fn a_sphere_descriptor_is_near_the_truth_and_a_moved_truth_is_not() {
        let mesh = icosphere(4);
        let loc = FaceLocator::new(&mesh);
        let refs = [DVec3::Z, DVec3::X].map(|p| Source::Point(loc.nearest(p).unwrap().0));
        let solver = geodesic::new_solver(&mesh, geodesic::Method::Exact).unwrap();
        let opts = DescriptorOptions {
            levels: LevelSpec::Count(4),
            max_level: Some(7),
            rule: SelectionRule::All,
            tangent: TangentMethod::Gradient,
            ..DescriptorOptions::default()
        };
        let d = describe(
            &Surface::new(mesh),
            Fields::Solve {
                solver: solver.as_ref(),
                references: &refs,
            },
            &opts,
        )
        .unwrap();
        let truth = sphere_truth(SelectionRule::All, 4, 7, 8, 0.95);
        let e = SphereErrors::of(&d, &truth);
        assert!(
            e.mesh_points.len() > truth.len() / 2,
            "{} of {}",
            e.mesh_points.len(),
            truth.len()
        );
        assert!(
            e.pos_err < 0.02 && e.cos_err < 0.05 && e.cos_err_max >= e.cos_err,
            "{e:?}"
        );
        let moved: SphereTruth = truth
            .iter()
            .map(|(k, (p, c))| (*k, (*p * 1.1, *c)))
            .collect();
        assert!(SphereErrors::of(&d, &moved).pos_err > 0.05);
        assert!(SphereErrors::of(&d, &SphereTruth::new()).pos_err.is_nan());
    }

    #[test]
    fn spheres_are_closed_and_outward() {
        for m in [icosphere(2), uv_sphere(8, 12)] {
            let t = Topology::new(&m);
            assert!(t.boundary_loops().is_empty());
            assert!(t.inconsistent_edges().is_empty());
            // Outward: every face normal points away from the centre.
            for f in 0..m.n_faces() as u32 {
                let [a, b, c] = m.face_corners(f);
                assert!(m.face_normal(f).dot((a + b + c) / 3.0) > 0.0);
            }
            assert_eq!(t.n_components(), 1);
        }
        assert_eq!(icosphere(2).n_vertices(), 162);
    }

    #[test]
    fn grid_with_hole_has_two_loops() {
        let m = grid_plane(10, 0.1, -0.5, 0.2, 1, |c| c.length() < 0.2);
        let t = Topology::new(&m);
        assert_eq!(t.boundary_loops().len(), 2);
        assert_eq!(t.isolated_vertices(), 0);
    }
}
