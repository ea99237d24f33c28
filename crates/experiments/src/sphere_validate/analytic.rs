//! The analytic bipolar representation of the unit sphere with poles `r = +Z`, `q = +X`, and
//! the comparison of a mesh descriptor with it.

use super::{ALPHA, K};
use bipolar::{Descriptor, Key, SelectionRule};
use glam::DVec3;
use std::collections::{BTreeMap, HashMap};

/// The analytic points of a rule: key -> (position, cos).
pub(super) type Truth = BTreeMap<Key, (DVec3, f64)>;

/// Analytic representation of `rule` with `n` levels between the poles, levels 1..=`max_level`:
/// key -> (position, cos).
pub(super) fn analytic(rule: SelectionRule, n: u32, max_level: u32) -> Truth {
    let step = std::f64::consts::FRAC_PI_2 / n as f64;
    let mut out = BTreeMap::new();
    for i in 1..=max_level {
        let a = i as f64 * step;
        if a >= std::f64::consts::PI {
            continue;
        }
        match rule {
            SelectionRule::All | SelectionRule::Filter { .. } => {
                grid_points(&mut out, rule, i, a, step, max_level);
            }
            SelectionRule::IsoAngle => iso_angle_points(&mut out, i, a, step, max_level),
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

/// The grid intersections of level `i` of r (distance `a`) with every level of q (rules `all`
/// and `filter`): level circles `z = cos a` and `x = cos b` meet at `y = +-sqrt(1 - z^2 -
/// x^2)`, where the opening is `cos = -cot a cot b`.
fn grid_points(out: &mut Truth, rule: SelectionRule, i: u32, a: f64, step: f64, max_level: u32) {
    for j in 1..=max_level {
        let b = j as f64 * step;
        let (z, x) = (a.cos(), b.cos());
        let y2 = 1.0 - z * z - x * x;
        if y2 <= 1e-12 {
            continue;
        }
        let cos = -(a.cos() / a.sin()) * (b.cos() / b.sin());
        if let SelectionRule::Filter { tolerance } = rule {
            let c = cos.abs();
            let ks = (c * K as f64 / ALPHA).round();
            if ks > K as f64 || (c - ALPHA * ks / K as f64).abs() > tolerance {
                continue;
            }
        }
        for s in [1.0, -1.0] {
            let p = DVec3::new(x, s * y2.sqrt(), z);
            let key = Key {
                a: 0,
                b: 1,
                i,
                j,
                side: side_of(p),
                sign: 0,
            };
            out.insert(key, (p, cos));
        }
    }
}

/// The iso-angle points of level `i` of r (distance `a`): `cos = +-alpha k / K` is met where
/// `cot b = -cos / cot a`, one point on each side.
fn iso_angle_points(out: &mut Truth, i: u32, a: f64, step: f64, max_level: u32) {
    let bmax = max_level as f64 * step;
    for k in 0..=K {
        let c = ALPHA * k as f64 / K as f64;
        let targets: Vec<(f64, i8)> = if k == 0 {
            vec![(0.0, 0)]
        } else {
            vec![(c, 1), (-c, -1)]
        };
        for (t, sign) in targets {
            // cos = -cot a cot b  =>  cot b = -t / cot a = -t tan a.
            let cotb = -t * a.tan();
            let b = std::f64::consts::FRAC_PI_2 - cotb.atan();
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
                let key = Key {
                    a: 0,
                    b: 1,
                    i,
                    j: k,
                    side: side_of(p),
                    sign,
                };
                out.insert(key, (p, t));
            }
        }
    }
}

/// How a mesh descriptor compares with the analytic one over their common unambiguous keys.
#[derive(Debug, Clone, Copy)]
pub(super) struct Comparison {
    /// Keys present (and unambiguous) in both.
    pub n_common: usize,
    /// Normalised keyed shape distance after centring and the best rotation.
    pub distance: f64,
    /// Mean position error.
    pub pos_err: f64,
    /// Mean error of the cosine against the spherical law of cosines at the mesh point.
    pub cos_err: f64,
    /// Largest such cosine error.
    pub cos_err_max: f64,
}

/// Compares descriptor `d` with the analytic representation `truth`.
pub(super) fn compare(d: &Descriptor, truth: &Truth) -> Comparison {
    let mut a = Vec::new();
    let mut b = Vec::new();
    let mut pos = 0.0;
    let mut cerr = 0.0;
    let mut cmax: f64 = 0.0;
    let mut counts: HashMap<Key, usize> = HashMap::new();
    for p in &d.points {
        *counts.entry(p.key).or_default() += 1;
    }
    for p in &d.points {
        if p.ambiguous || counts[&p.key] > 1 {
            continue;
        }
        if let Some((t, _)) = truth.get(&p.key) {
            a.push(p.position);
            b.push(*t);
            pos += (p.position - *t).length();
            // Angle error at the mesh point: analytic cos at the mesh position for the grid,
            // the target value for iso-angle points (their cos is the target by construction,
            // so the error shows in the position instead).
            let q = p.position.normalize();
            let (aa, bb) = (q.z.clamp(-1.0, 1.0).acos(), q.x.clamp(-1.0, 1.0).acos());
            let exact_here = -(aa.cos() / aa.sin()) * (bb.cos() / bb.sin());
            let e = (p.cos - exact_here).abs();
            cerr += e;
            cmax = cmax.max(e);
        }
    }
    let n = a.len();
    let distance = shapedist::align_pairs(&a, &b, None, shapedist::RotationMethod::Kabsch)
        .map(|al| al.distance)
        .unwrap_or(f64::NAN);
    if n == 0 {
        return Comparison {
            n_common: 0,
            distance: f64::NAN,
            pos_err: f64::NAN,
            cos_err: f64::NAN,
            cos_err_max: f64::NAN,
        };
    }
    Comparison {
        n_common: n,
        distance,
        pos_err: pos / n as f64,
        cos_err: cerr / n as f64,
        cos_err_max: cmax,
    }
}
