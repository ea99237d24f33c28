//! The fitted curve: least-squares fit, evaluation, derivatives, closest point.

use crate::basis::{ders_basis, find_span, periodic_basis};
use crate::params::{averaged_knots, check_points, data_params};
use crate::solve::{add_penalty, cholesky_solve, penalty_rows, penalty_trace};
use crate::{BSplineError, FitOptions, DEGREE};
use glam::DVec3;

/// A fitted cubic B-spline curve in 3D: open clamped on `[0, 1]` or closed periodic with
/// period 1.
#[derive(Debug, Clone, PartialEq)]
pub struct BSpline3 {
    closed: bool,
    /// Open: clamped knot vector (length `n_ctrl + 4`). Closed: empty (uniform knots implied).
    knots: Vec<f64>,
    ctrl: Vec<DVec3>,
    params: Vec<f64>,
}

impl BSpline3 {
    /// Fits a cubic B-spline to the ordered `points` (see the crate docs for the method).
    ///
    /// Errors: fewer than 4 points, a non-finite coordinate, two consecutive coincident points
    /// (for closed curves also last = first), `n_control` out of range, a non-positive or
    /// non-finite `control_spacing` or a negative/non-finite `smoothing`, and (only with
    /// `smoothing == 0`) a singular system.
    pub fn fit(points: &[DVec3], opts: &FitOptions) -> Result<BSpline3, BSplineError> {
        check_points(points, opts.closed, DEGREE + 1)?;
        let params = data_params(points, opts.closed, opts.parametrization)?;
        Self::fit_impl(points, params, opts)
    }

    /// Like [`BSpline3::fit`] but with caller-given data parameters: strictly increasing, in
    /// `[0, 1]` for open curves (first 0 and last 1 are *not* required) and in `[0, 1)` for
    /// closed ones. `opts.parametrization` is ignored.
    pub fn fit_with_params(
        points: &[DVec3],
        params: &[f64],
        opts: &FitOptions,
    ) -> Result<BSpline3, BSplineError> {
        check_points(points, opts.closed, DEGREE + 1)?;
        if params.len() != points.len() {
            return Err(BSplineError::InvalidParams(format!(
                "{} parameters for {} points",
                params.len(),
                points.len()
            )));
        }
        for (i, &u) in params.iter().enumerate() {
            let hi_ok = if opts.closed { u < 1.0 } else { u <= 1.0 };
            if !u.is_finite() || u < 0.0 || !hi_ok {
                return Err(BSplineError::InvalidParams(format!(
                    "parameter {i} = {u} is outside the domain"
                )));
            }
            if i > 0 && u <= params[i - 1] {
                return Err(BSplineError::InvalidParams(format!(
                    "parameters are not strictly increasing at {i} ({} then {u})",
                    params[i - 1]
                )));
            }
        }
        Self::fit_impl(points, params.to_vec(), opts)
    }

    fn n_control_for(points: &[DVec3], opts: &FitOptions) -> Result<usize, BSplineError> {
        let m = points.len();
        if let Some(n) = opts.n_control {
            if n < DEGREE + 1 || n > m {
                return Err(BSplineError::InvalidOption(format!(
                    "n_control = {n} must be in [4, number of points = {m}]"
                )));
            }
            return Ok(n);
        }
        let mut chords: Vec<f64> = points.windows(2).map(|w| w[0].distance(w[1])).collect();
        if opts.closed {
            chords.push(points[m - 1].distance(points[0]));
        }
        let length: f64 = chords.iter().sum();
        let h = match opts.control_spacing {
            Some(h) => {
                if !(h.is_finite() && h > 0.0) {
                    return Err(BSplineError::InvalidOption(format!(
                        "control_spacing = {h} must be finite and positive"
                    )));
                }
                h
            }
            None => {
                chords.sort_by(f64::total_cmp);
                4.0 * chords[chords.len() / 2]
            }
        };
        let spans = (length / h).round();
        let raw = if opts.closed {
            spans
        } else {
            spans + DEGREE as f64
        };
        let hi = (m / 2).max(DEGREE + 1) as f64;
        Ok(raw.clamp((DEGREE + 1) as f64, hi) as usize)
    }

    fn fit_impl(
        points: &[DVec3],
        params: Vec<f64>,
        opts: &FitOptions,
    ) -> Result<BSpline3, BSplineError> {
        if !(opts.smoothing.is_finite() && opts.smoothing >= 0.0) {
            return Err(BSplineError::InvalidOption(format!(
                "smoothing = {} must be finite and >= 0",
                opts.smoothing
            )));
        }
        let nc = Self::n_control_for(points, opts)?;
        let knots = if opts.closed {
            Vec::new()
        } else {
            averaged_knots(&params, nc)
        };
        let mut curve = BSpline3 {
            closed: opts.closed,
            knots,
            ctrl: vec![DVec3::ZERO; nc],
            params,
        };
        // Normal equations.
        let mut a = vec![0.0f64; nc * nc];
        let mut rhs = vec![DVec3::ZERO; nc];
        for (k, &u) in curve.params.iter().enumerate() {
            let (cols, basis) = curve.basis_at(u);
            for r in 0..4 {
                rhs[cols[r]] += basis[0][r] * points[k];
                for c in 0..4 {
                    a[cols[r] * nc + cols[c]] += basis[0][r] * basis[0][c];
                }
            }
        }
        if opts.smoothing > 0.0 {
            let rows = penalty_rows(&curve.knots, nc, opts.closed);
            let ptr = penalty_trace(&rows);
            if ptr > 0.0 {
                let tr: f64 = (0..nc).map(|i| a[i * nc + i]).sum();
                let lambda = opts.smoothing * tr / ptr;
                add_penalty(&mut a, nc, lambda, &rows);
            }
        }
        let bw = if opts.closed { nc - 1 } else { DEGREE };
        cholesky_solve(&mut a, nc, bw, &mut rhs)?;
        curve.ctrl = rhs;
        Ok(curve)
    }

    /// Columns (control point indices) and basis values/derivatives (with respect to u) of the
    /// four basis functions non-zero at `u` (already wrapped/clamped).
    fn basis_at(&self, u: f64) -> ([usize; 4], [[f64; 4]; 3]) {
        let nc = self.ctrl.len();
        if self.closed {
            let u = u - u.floor();
            let x = u * nc as f64;
            let s = (x.floor() as usize).min(nc - 1);
            let t = x - s as f64;
            let mut b = periodic_basis(t);
            let f = nc as f64;
            for v in b[1].iter_mut() {
                *v *= f;
            }
            for v in b[2].iter_mut() {
                *v *= f * f;
            }
            ([s % nc, (s + 1) % nc, (s + 2) % nc, (s + 3) % nc], b)
        } else {
            let u = u.clamp(0.0, 1.0);
            let span = find_span(&self.knots, nc, u);
            let b = ders_basis(&self.knots, span, u);
            ([span - 3, span - 2, span - 1, span], b)
        }
    }

    fn combine(&self, u: f64, order: usize) -> DVec3 {
        let (cols, b) = self.basis_at(u);
        let mut s = DVec3::ZERO;
        for r in 0..4 {
            s += b[order][r] * self.ctrl[cols[r]];
        }
        s
    }

    /// Whether the curve is closed (periodic with period 1).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The parameter of each input point (same order and count as the fitted points).
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// Parameter domain: `(0, 1)`. Closed curves are periodic with period 1 and accept any `u`.
    pub fn domain(&self) -> (f64, f64) {
        (0.0, 1.0)
    }

    /// Point at parameter `u` (clamped to the domain for open curves, wrapped for closed ones).
    pub fn eval(&self, u: f64) -> DVec3 {
        self.combine(u, 0)
    }

    /// First derivative `dC/du` at `u`.
    pub fn derivative(&self, u: f64) -> DVec3 {
        self.combine(u, 1)
    }

    /// Second derivative `d²C/du²` at `u`.
    pub fn second_derivative(&self, u: f64) -> DVec3 {
        self.combine(u, 2)
    }

    /// Unit tangent at `u` (zero vector when the derivative vanishes).
    pub fn tangent(&self, u: f64) -> DVec3 {
        self.derivative(u).normalize_or_zero()
    }

    /// Control points.
    pub fn control_points(&self) -> &[DVec3] {
        &self.ctrl
    }

    /// Knot vector of an open curve (clamped, length `control points + 4`); empty for closed
    /// curves, whose knots are uniform with spacing `1 / control points`.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    fn wrap(&self, u: f64) -> f64 {
        if self.closed {
            u - u.floor()
        } else {
            u.clamp(0.0, 1.0)
        }
    }

    /// Parameter of the curve point closest to `p`: the nearest of a dense uniform sampling,
    /// then Newton iterations (see [`BSpline3::closest_param_from`]).
    pub fn closest_param(&self, p: DVec3) -> f64 {
        let n = (16 * self.ctrl.len()).max(64);
        let mut best = (f64::INFINITY, 0.0);
        let last = if self.closed { n } else { n + 1 };
        for i in 0..last {
            let u = i as f64 / n as f64;
            let d = self.eval(u).distance_squared(p);
            if d < best.0 {
                best = (d, u);
            }
        }
        self.closest_param_from(p, best.1)
    }

    /// Newton projection of `p` onto the curve starting from `u0`:
    /// `u ← u − ⟨C−p, C'⟩ / (|C'|² + ⟨C−p, C''⟩)`, clamped (open) or wrapped (closed), with step
    /// halving so the distance never increases; at most 30 iterations.
    pub fn closest_param_from(&self, p: DVec3, u0: f64) -> f64 {
        let mut u = self.wrap(u0);
        let mut dist = self.eval(u).distance_squared(p);
        for _ in 0..30 {
            let c = self.eval(u) - p;
            let d1 = self.derivative(u);
            let d2 = self.second_derivative(u);
            let g = c.dot(d1);
            let mut h = d1.length_squared() + c.dot(d2);
            if h.is_nan() || h <= 0.0 {
                h = d1.length_squared().max(f64::MIN_POSITIVE);
            }
            let mut step = -g / h;
            if !step.is_finite() {
                break;
            }
            let mut improved = false;
            for _ in 0..20 {
                let un = self.wrap(u + step);
                let dn = self.eval(un).distance_squared(p);
                if dn <= dist {
                    improved = dn < dist || un == u;
                    let moved = (un - u).abs();
                    u = un;
                    dist = dn;
                    if moved < 1e-15 {
                        improved = false;
                    }
                    break;
                }
                step *= 0.5;
            }
            if !improved || step.abs() < 1e-14 {
                break;
            }
        }
        u
    }
}
