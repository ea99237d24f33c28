//! The one ICP loop of the workspace, generic over where the correspondences come from.
//!
//! An [`IcpTarget`] answers, for every source point moved by the current pose, its partner on
//! the target (a point, optionally a unit normal, and a squared distance). [`icp_to_target`]
//! then selects the pairs (distance and normal gates, trimming), takes a point-to-point
//! (closed-form Kabsch) or point-to-plane (linearised, damped) step and applies the chosen
//! convergence rule. Implementations: [`crate::PreparedSet`] (exact nearest points), and, as
//! [`PointTarget`]s (one point at a time, no state), a mesh surface through
//! [`meshcore::FaceLocator`] (closest points on triangles) and the landmark detector's surface
//! index (in the `landmarks` crate).
//!
//! Arithmetic, in a fixed order whatever the thread count: the sums of the kept pairs are
//! formed per chunk of `CHUNK` (512) source points and added in chunk order; the point-to-plane
//! normal equations are accumulated over the kept pairs in source order.

#![allow(clippy::needless_range_loop)] // index loops read best in the 6x6 normal equations

use glam::{DAffine3, DMat3, DVec3};
use meshcore::linalg::{axis_angle, kabsch_rotation, orthonormalise, solve_sym_tol};
use meshcore::FaceLocator;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::ShapeDistError;
use crate::icp::{IcpResult, IcpVariant};
use crate::points::outer;

/// Below this many source points the sums of the kept pairs are formed on one thread.
pub(crate) const PAR_MIN: usize = 2048;

/// Source points per work unit of the sums (and of the parallel correspondence passes).
pub(crate) const CHUNK: usize = 512;

/// The partner of one source point on an [`IcpTarget`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Match {
    /// Squared distance used for gating, trimming and the RMS (the target defines it: exact
    /// for point sets and surfaces, an approximation for the landmark surface index).
    pub d2: f64,
    /// The partner point.
    pub point: DVec3,
    /// Unit normal at the partner (only read when the target [has normals](IcpTarget::has_normals)
    /// and normals were asked for; zero otherwise).
    pub normal: DVec3,
}

impl Match {
    /// No partner yet (infinitely far).
    pub const NONE: Match = Match {
        d2: f64::INFINITY,
        point: DVec3::ZERO,
        normal: DVec3::ZERO,
    };
}

/// Where ICP finds the partners of the moved source points.
pub trait IcpTarget: Sync {
    /// Per-run state (for example warm starts from the previous partners).
    type State: Send;

    /// The state of a new run with `n` source points.
    fn start(&self, n: usize) -> Self::State;

    /// Whether [`Match::normal`] can be filled (needed by point-to-plane steps and normal
    /// gates).
    fn has_normals(&self) -> bool;

    /// Fills `out[k]` with the partner of `pose * src[k]` for every `k` (`out.len() ==
    /// src.len()`), with normals when `normals`. Returns the number of expensive queries made
    /// (statistics only).
    fn correspond(
        &self,
        src: &[DVec3],
        pose: &DAffine3,
        normals: bool,
        state: &mut Self::State,
        out: &mut [Match],
    ) -> Result<usize, ShapeDistError>;
}

/// A target without per-run state that answers one moved source point at a time and always
/// has normals. Every such type is an [`IcpTarget`] (one query per source point): a mesh surface
/// through [`FaceLocator`], the landmark detector's surface index.
pub trait PointTarget: Sync {
    /// The partner of the (moved) source point `q`, with its unit normal when `normals`.
    fn partner(&self, q: DVec3, normals: bool) -> Result<Match, ShapeDistError>;
}

impl<T: PointTarget> IcpTarget for T {
    type State = ();

    fn start(&self, _n: usize) -> Self::State {}

    fn has_normals(&self) -> bool {
        true
    }

    fn correspond(
        &self,
        src: &[DVec3],
        pose: &DAffine3,
        normals: bool,
        _state: &mut (),
        out: &mut [Match],
    ) -> Result<usize, ShapeDistError> {
        for (o, p) in out.iter_mut().zip(src) {
            *o = self.partner(pose.transform_point3(*p), normals)?;
        }
        Ok(src.len())
    }
}

/// How a trim fraction becomes the number of pairs kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum TrimRounding {
    /// Keep `ceil(n (1 - trim))` pairs (at least 3).
    #[default]
    Up,
    /// Keep `floor(n (1 - trim))` pairs (at least 3).
    Down,
}

/// When an ICP run stops before its iteration limit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Convergence {
    /// Before the step: stop at the current pose when the RMS of the kept pairs is zero or
    /// changed by at most `tolerance` times the previous RMS.
    RelativeRmse {
        /// Relative tolerance.
        tolerance: f64,
    },
    /// After the step: stop (at the new pose) when the RMS of the kept pairs at the pose the
    /// step started from changed by at most `tolerance * max(rms, 1e-12)` from the previous
    /// one.
    RelativeRmseAfterStep {
        /// Relative tolerance.
        tolerance: f64,
    },
    /// After the step: stop when the step rotated by less than `angle` radians and moved by
    /// less than `translation * (1 + |t|)` (`t` the new translation).
    StepSize {
        /// Rotation bound (radians).
        angle: f64,
        /// Relative translation bound.
        translation: f64,
    },
}

/// Tikhonov damping and pivot threshold of the point-to-plane normal equations: every
/// diagonal entry gets `factor * tr + floor`, where `tr` is the trace of the 6x6 matrix (or
/// its mean diagonal entry when `mean`); the system is singular when a pivot is at most
/// `rel_pivot` times its largest entry.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Damping {
    /// Multiplier of the trace.
    pub factor: f64,
    /// Use the mean diagonal entry (trace / 6) instead of the trace.
    pub mean: bool,
    /// Added to every diagonal entry.
    pub floor: f64,
    /// Relative pivot threshold of the solve.
    pub rel_pivot: f64,
}

impl Default for Damping {
    fn default() -> Self {
        Self {
            factor: 1e-12,
            mean: false,
            floor: f64::MIN_POSITIVE,
            rel_pivot: 1e-14,
        }
    }
}

/// Options of [`icp_to_target`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IcpLoopOptions {
    /// Point-to-point (closed form) or point-to-plane (needs target normals) steps.
    pub variant: IcpVariant,
    /// Maximum number of iterations (correspondence passes followed by a step).
    pub max_iterations: usize,
    /// Also estimate a translation (otherwise the translation is zero after the first step).
    pub translation: bool,
    /// Fraction of the gated pairs with the largest distances rejected at each iteration, in
    /// [0, 0.9].
    pub trim: f64,
    /// Rounding of the kept count.
    pub trim_rounding: TrimRounding,
    /// Distance gate: pairs with `d2 >= max_distance^2` are dropped.
    pub max_distance: Option<f64>,
    /// Normal gate: pairs whose target normal and rotated source normal have a dot product
    /// `<= min_normal_dot` are dropped (needs source normals).
    pub min_normal_dot: Option<f64>,
    /// Point-to-plane damping and solve.
    pub damping: Damping,
    /// Point-to-plane rotation steps of at most this angle (radians) are taken as the
    /// identity.
    pub min_step_angle: f64,
    /// Project the rotation back onto SO(3) after every point-to-plane step.
    pub orthonormalise_steps: bool,
    /// Stopping rule.
    pub convergence: Convergence,
    /// Stop (keeping the pose) when fewer pairs survive the gates.
    pub min_pairs: usize,
    /// When the run ends after a step, pair once more so that [`IcpResult::rmse`] is at the
    /// returned pose (otherwise it is the RMS of the last pass, before the last step).
    pub evaluate_final: bool,
}

impl Default for IcpLoopOptions {
    fn default() -> Self {
        Self {
            variant: IcpVariant::PointToPoint,
            max_iterations: 50,
            translation: false,
            trim: 0.0,
            trim_rounding: TrimRounding::Up,
            max_distance: None,
            min_normal_dot: None,
            damping: Damping::default(),
            min_step_angle: 0.0,
            orthonormalise_steps: true,
            convergence: Convergence::RelativeRmse { tolerance: 1e-6 },
            min_pairs: 3,
            evaluate_final: true,
        }
    }
}

/// Validates the options for `n` source points.
pub(crate) fn check(
    o: &IcpLoopOptions,
    n: usize,
    src_normals: Option<&[DVec3]>,
) -> Result<(), ShapeDistError> {
    let bad = |m: String| Err(ShapeDistError::InvalidOption(m));
    if !(0.0..=0.9).contains(&o.trim) {
        return bad(format!("trim fraction must be in [0, 0.9], got {}", o.trim));
    }
    let tol_ok = match o.convergence {
        Convergence::RelativeRmse { tolerance }
        | Convergence::RelativeRmseAfterStep { tolerance } => tolerance >= 0.0,
        Convergence::StepSize { angle, translation } => angle >= 0.0 && translation >= 0.0,
    };
    if !tol_ok || o.max_iterations == 0 {
        return bad("tolerance must be >= 0 and max_iterations >= 1".into());
    }
    if o.max_distance.is_some_and(f64::is_nan) || o.min_normal_dot.is_some_and(f64::is_nan) {
        return bad("the distance and normal gates must not be NaN".into());
    }
    if o.min_normal_dot.is_some() && src_normals.is_none_or(|s| s.len() != n) {
        return bad("a normal gate needs one source normal per source point".into());
    }
    Ok(())
}

/// Sums of the kept pairs `(a = partner, b = source point)`.
#[derive(Clone, Copy)]
pub(crate) struct Sums {
    pub(crate) n: f64,
    pub(crate) ss: f64,
    sa: DVec3,
    sb: DVec3,
    k: DMat3,
}

impl Sums {
    pub(crate) const ZERO: Sums = Sums {
        n: 0.0,
        ss: 0.0,
        sa: DVec3::ZERO,
        sb: DVec3::ZERO,
        k: DMat3::ZERO,
    };
    #[inline(always)]
    fn push(&mut self, a: DVec3, b: DVec3, d2: f64) {
        self.n += 1.0;
        self.ss += d2;
        self.sa += a;
        self.sb += b;
        self.k += outer(a, b);
    }
    fn add(self, o: Sums) -> Sums {
        Sums {
            n: self.n + o.n,
            ss: self.ss + o.ss,
            sa: self.sa + o.sa,
            sb: self.sb + o.sb,
            k: self.k + o.k,
        }
    }
}

/// Sums over the kept pairs (chunked, added in chunk order).
fn kept_sums(m: &[Match], src: &[DVec3], keep: &[bool], parallel: bool) -> Sums {
    let run = |((m, b), k): ((&[Match], &[DVec3]), &[bool])| {
        let mut s = Sums::ZERO;
        for ((m, b), k) in m.iter().zip(b).zip(k) {
            if *k {
                s.push(m.point, *b, m.d2);
            }
        }
        s
    };
    if parallel {
        let parts: Vec<Sums> = m
            .par_chunks(CHUNK)
            .zip(src.par_chunks(CHUNK))
            .zip(keep.par_chunks(CHUNK))
            .map(run)
            .collect();
        parts.into_iter().fold(Sums::ZERO, Sums::add)
    } else {
        m.chunks(CHUNK)
            .zip(src.chunks(CHUNK))
            .zip(keep.chunks(CHUNK))
            .map(run)
            .fold(Sums::ZERO, Sums::add)
    }
}

/// Marks the kept pairs (gates, then trimming of the gated pairs).
fn select(
    m: &[Match],
    src_normals: Option<&[DVec3]>,
    r: DMat3,
    o: &IcpLoopOptions,
    keep: &mut [bool],
    scratch: &mut Vec<f64>,
) {
    let tau2 = o.max_distance.map(|t| t * t);
    let mut gated = 0usize;
    for (k, (mk, kk)) in m.iter().zip(keep.iter_mut()).enumerate() {
        let far = tau2.is_some_and(|t| mk.d2 >= t);
        let turned = match (o.min_normal_dot, src_normals) {
            (Some(min), Some(sn)) => mk.normal.dot(r * sn[k]) <= min,
            _ => false,
        };
        *kk = !(far || turned);
        gated += usize::from(*kk);
    }
    if o.trim <= 0.0 {
        return;
    }
    let want = (gated as f64) * (1.0 - o.trim);
    let want = match o.trim_rounding {
        TrimRounding::Up => want.ceil(),
        TrimRounding::Down => want.floor(),
    };
    let n_keep = want.max(3.0) as usize;
    if n_keep >= gated {
        return;
    }
    scratch.clear();
    scratch.extend(m.iter().zip(keep.iter()).filter(|x| *x.1).map(|x| x.0.d2));
    let (_, kth, _) = scratch.select_nth_unstable_by(n_keep - 1, f64::total_cmp);
    let thr = *kth;
    for (mk, kk) in m.iter().zip(keep.iter_mut()) {
        *kk = *kk && mk.d2 <= thr;
    }
}

/// Closed-form point-to-point update from the sums of the kept pairs (`a ~ R b (+ t)`).
fn point_step(s: &Sums, translation: bool) -> (DMat3, DVec3) {
    if translation {
        let (ma, mb) = (s.sa / s.n, s.sb / s.n);
        let k = s.k - outer(ma, mb) * s.n;
        let (nr, _) = kabsch_rotation(k);
        (nr, ma - nr * mb)
    } else {
        (kabsch_rotation(s.k).0, DVec3::ZERO)
    }
}

/// Linearised point-to-plane update; `None` when the normal equations are singular. Also
/// returns the rotation angle and translation of the step.
fn plane_step(
    m: &[Match],
    src: &[DVec3],
    keep: &[bool],
    r: DMat3,
    t: DVec3,
    o: &IcpLoopOptions,
) -> Option<(DMat3, DVec3, f64, DVec3)> {
    // Residual (p - a).n + w.(p x n) + d.n, p = R b + t; unknowns w (and d).
    let mut ata = [[0.0; 6]; 6];
    let mut atb = [0.0; 6];
    for ((mk, b), k) in m.iter().zip(src).zip(keep) {
        if !*k {
            continue;
        }
        let (a, n) = (mk.point, mk.normal);
        let p = r * *b + t;
        let cr = p.cross(n);
        let row = [cr.x, cr.y, cr.z, n.x, n.y, n.z];
        let res = (p - a).dot(n);
        for u in 0..6 {
            for v in u..6 {
                ata[u][v] += row[u] * row[v];
            }
            atb[u] -= row[u] * res;
        }
    }
    for u in 0..6 {
        for v in 0..u {
            ata[u][v] = ata[v][u];
        }
    }
    let dm = &o.damping;
    let tr: f64 = (0..6).map(|i| ata[i][i]).sum();
    let tr = if dm.mean { tr / 6.0 } else { tr };
    let reg = dm.factor * tr + dm.floor;
    let (w, d) = if o.translation {
        let mut a = ata;
        (0..6).for_each(|i| a[i][i] += reg);
        let x = solve_sym_tol(a, atb, dm.rel_pivot)?;
        (DVec3::new(x[0], x[1], x[2]), DVec3::new(x[3], x[4], x[5]))
    } else {
        let mut a = [[0.0; 3]; 3];
        for u in 0..3 {
            for v in 0..3 {
                a[u][v] = ata[u][v];
            }
            a[u][u] += reg;
        }
        let x = solve_sym_tol(a, [atb[0], atb[1], atb[2]], dm.rel_pivot)?;
        (DVec3::new(x[0], x[1], x[2]), DVec3::ZERO)
    };
    let angle = w.length();
    let dr = if angle > o.min_step_angle {
        axis_angle(w, angle)
    } else {
        DMat3::IDENTITY
    };
    let nr = dr * r;
    let nr = if o.orthonormalise_steps {
        orthonormalise(nr)
    } else {
        nr
    };
    let nt = if o.translation {
        dr * t + d
    } else {
        DVec3::ZERO
    };
    Some((nr, nt, angle, d))
}

/// RMS of the kept pairs at the current correspondences.
fn rms_of(s: &Sums) -> f64 {
    (s.ss / s.n.max(1.0)).sqrt()
}

/// Runs ICP of the source points `src` onto `target` from the pose `init` (`partner ~ pose *
/// src`). `src_normals` (one per source point) are only needed by a normal gate.
///
/// Each iteration pairs every moved source point ([`IcpTarget::correspond`]), keeps the pairs
/// passing the gates and the trim, and takes one step; [`IcpLoopOptions::convergence`]
/// decides when to stop. Errors: invalid options, a point-to-plane variant on a target
/// without normals, or the target's own errors.
pub fn icp_to_target<T: IcpTarget + ?Sized>(
    target: &T,
    src: &[DVec3],
    src_normals: Option<&[DVec3]>,
    init: DAffine3,
    o: &IcpLoopOptions,
) -> Result<IcpResult, ShapeDistError> {
    check(o, src.len(), src_normals)?;
    let plane = o.variant == IcpVariant::PointToPlane;
    let normals = plane || o.min_normal_dot.is_some();
    if normals && !target.has_normals() {
        return Err(ShapeDistError::InvalidOption(
            "point-to-plane steps and normal gates need a target with normals".into(),
        ));
    }
    if !init.is_finite() {
        return Err(ShapeDistError::InvalidOption(
            "initial pose is not finite".into(),
        ));
    }
    let parallel = src.len() >= PAR_MIN;
    let mut r = init.matrix3;
    let mut t = init.translation;
    let mut state = target.start(src.len());
    let mut m = vec![Match::NONE; src.len()];
    let mut keep = vec![true; src.len()];
    let mut scratch = Vec::new();
    let mut queries = 0;
    let mut passes = 0;
    let mut prev_rmse = f64::INFINITY;
    let mut rmse = f64::INFINITY;
    let mut iterations = 0;
    let mut converged = false;
    let mut moved = false;
    while iterations < o.max_iterations {
        let pose = DAffine3::from_mat3_translation(r, t);
        queries += target.correspond(src, &pose, normals, &mut state, &mut m)?;
        passes += 1;
        iterations += 1;
        moved = false;
        select(&m, src_normals, r, o, &mut keep, &mut scratch);
        let kept = kept_sums(&m, src, &keep, parallel);
        rmse = rms_of(&kept);
        if let Convergence::RelativeRmse { tolerance } = o.convergence {
            if rmse == 0.0
                || (prev_rmse.is_finite() && (prev_rmse - rmse).abs() <= tolerance * prev_rmse)
            {
                converged = true;
                break;
            }
            prev_rmse = rmse;
        }
        if kept.n < o.min_pairs.max(3) as f64 {
            break;
        }
        let (angle, dt) = if plane {
            let Some((nr, nt, angle, d)) = plane_step(&m, src, &keep, r, t, o) else {
                break;
            };
            (r, t) = (nr, nt);
            (angle, d)
        } else {
            let (nr, nt) = point_step(&kept, o.translation);
            (r, t) = (nr, nt);
            (f64::NAN, DVec3::NAN)
        };
        moved = true;
        match o.convergence {
            Convergence::RelativeRmse { .. } => {}
            Convergence::RelativeRmseAfterStep { tolerance } => {
                if (prev_rmse - rmse).abs() <= tolerance * rmse.max(1e-12) {
                    converged = true;
                    break;
                }
                prev_rmse = rmse;
            }
            Convergence::StepSize {
                angle: a_tol,
                translation: t_tol,
            } => {
                if angle < a_tol && dt.length() < t_tol * (1.0 + t.length()) {
                    converged = true;
                    break;
                }
            }
        }
    }
    if moved && o.evaluate_final {
        // Report the error at the returned pose.
        let pose = DAffine3::from_mat3_translation(r, t);
        queries += target.correspond(src, &pose, normals, &mut state, &mut m)?;
        passes += 1;
        select(&m, src_normals, r, o, &mut keep, &mut scratch);
        rmse = rms_of(&kept_sums(&m, src, &keep, parallel));
    }
    Ok(IcpResult {
        motion: DAffine3::from_mat3_translation(r, t),
        iterations,
        rmse,
        converged,
        coarse_iterations: 0,
        pair_searches: src.len() * passes,
        tree_queries: queries,
    })
}

/// Closest points on the triangles of a mesh (exact, [`FaceLocator::nearest`]); normals are
/// the unit face normals.
impl PointTarget for FaceLocator<'_> {
    fn partner(&self, q: DVec3, normals: bool) -> Result<Match, ShapeDistError> {
        let (sp, d) = self.nearest(q)?;
        let mesh = self.mesh();
        Ok(Match {
            d2: d * d,
            point: mesh.point_position(&sp)?,
            normal: if normals {
                mesh.face_normal(sp.face)
            } else {
                DVec3::ZERO
            },
        })
    }
}
