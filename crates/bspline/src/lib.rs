//! Least-squares cubic B-spline fitting of ordered (noisy) 3D polylines.
//!
//! Implements `docs/algorithms.md` §3 of the shared specification:
//!
//! * data parameters by chord length or centripetal spacing (NURBS Book eqs. 9.4–9.6),
//!   normalised to `[0, 1]` (open) or `[0, 1)` (closed, the closing chord included);
//! * **open** curves: clamped cubic B-spline, interior knots placed by averaging the data
//!   parameters (eqs. 9.68–9.69, so every knot span holds data: Schoenberg–Whitney);
//! * **closed** curves: uniform periodic cubic B-spline with `N_c` control points;
//! * least squares with a P-spline second-difference penalty (Eilers & Marx):
//!   `(NᵀN + λ DᵀD) P = NᵀQ`, `λ = smoothing · trace(NᵀN) / trace(DᵀD)` (dimensionless; for open
//!   curves `D` takes divided differences over the Greville abscissae so that straight lines
//!   traversed at constant speed are not penalised), solved
//!   by a (banded) Cholesky factorisation written here (no linear-algebra dependency);
//! * evaluation, analytic first and second derivatives, closest-point projection by Newton
//!   iterations.
//!
//! ```
//! use bspline::{BSpline3, FitOptions};
//! use glam::DVec3;
//! let pts: Vec<DVec3> = (0..40)
//!     .map(|i| {
//!         let a = i as f64 / 40.0 * std::f64::consts::TAU;
//!         DVec3::new(a.cos(), a.sin(), 0.0)
//!     })
//!     .collect();
//! let opts = FitOptions { closed: true, ..FitOptions::default() };
//! let c = BSpline3::fit(&pts, &opts).unwrap();
//! let u = c.params()[5];
//! assert!((c.eval(u).length() - 1.0).abs() < 1e-3);
//! ```

use glam::DVec3;
use thiserror::Error;

/// Degree of every curve built by this crate (cubic).
pub const DEGREE: usize = 3;

/// How data parameters are spaced along the polyline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Parametrization {
    /// Parameter increments proportional to chord lengths (exponent 1). The default.
    #[default]
    ChordLength,
    /// Parameter increments proportional to the square root of chord lengths (exponent 0.5);
    /// safer when the point spacing varies a lot.
    Centripetal,
}
meshcore::choice!(Parametrization, "parametrization", BSplineError {
    ChordLength = "chord-length" | "chord",
    Centripetal = "centripetal",
});

impl Parametrization {
    fn exponent(self) -> f64 {
        match self {
            Parametrization::ChordLength => 1.0,
            Parametrization::Centripetal => 0.5,
        }
    }
}

/// Options of [`BSpline3::fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Fit a closed periodic curve (the first point is *not* repeated at the end).
    pub closed: bool,
    /// Spacing of the data parameters.
    pub parametrization: Parametrization,
    /// Number of control points. Takes precedence over `control_spacing`. Open curves need
    /// `4 <= n <= number of points`; closed curves the same.
    pub n_control: Option<usize>,
    /// Target distance between control points (same unit as the points). When neither this nor
    /// `n_control` is given, 4 × the median chord length of the polyline is used. The resulting
    /// count is clamped to `[4, max(4, points / 2)]`.
    pub control_spacing: Option<f64>,
    /// Dimensionless weight of the second-difference penalty (`λ_rel`); `0` gives a pure least
    /// squares fit. Default `1e-3` (a light regulariser).
    pub smoothing: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            closed: false,
            parametrization: Parametrization::ChordLength,
            n_control: None,
            control_spacing: None,
            smoothing: 1e-3,
        }
    }
}

/// Errors of the fitting routines.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum BSplineError {
    /// Fewer points than the fit needs.
    #[error("too few points: got {got}, need at least {need}")]
    TooFewPoints {
        /// Number of points given.
        got: usize,
        /// Minimum number needed.
        need: usize,
    },
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFinite {
        /// Index of the offending point.
        index: usize,
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
    },
    /// Two consecutive points coincide (zero chord length), so the parameterisation is
    /// degenerate. For closed curves `index == 0` means the last point repeats the first one
    /// (a closed polyline must not repeat its first point). Use [`dedup_consecutive`] first.
    #[error("points {prev} and {index} coincide (zero chord length)")]
    CoincidentPoints {
        /// Index of the point equal to its predecessor.
        index: usize,
        /// Index of the predecessor.
        prev: usize,
    },
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Explicit parameters are not usable (wrong count, not finite, not increasing or outside
    /// the domain).
    #[error("invalid parameters: {0}")]
    InvalidParams(String),
    /// The normal equations are not positive definite (only possible with `smoothing == 0` and
    /// badly distributed parameters).
    #[error("the least-squares system is singular (pivot {pivot}); add smoothing or use fewer control points")]
    Singular {
        /// Index of the failing pivot.
        pivot: usize,
    },
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
}

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

/// Removes consecutive points closer than `tol` to the previously kept point (and, when
/// `closed`, a last point within `tol` of the first). Returns the kept points and, for each
/// kept point, its index in the input.
pub fn dedup_consecutive(points: &[DVec3], tol: f64, closed: bool) -> (Vec<DVec3>, Vec<usize>) {
    let mut out: Vec<DVec3> = Vec::with_capacity(points.len());
    let mut idx = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        if let Some(&q) = out.last() {
            if p.distance(q) <= tol {
                continue;
            }
        }
        out.push(p);
        idx.push(i);
    }
    if closed {
        while out.len() > 1 && out[out.len() - 1].distance(out[0]) <= tol {
            out.pop();
            idx.pop();
        }
    }
    (out, idx)
}

/// Data parameters of a polyline (chord length or centripetal), normalised to `[0, 1]` for open
/// curves, `[0, 1)` for closed ones (closing chord included).
pub fn data_params(
    points: &[DVec3],
    closed: bool,
    parametrization: Parametrization,
) -> Result<Vec<f64>, BSplineError> {
    check_points(points, closed, 2)?;
    let e = parametrization.exponent();
    let n = points.len();
    let mut acc = Vec::with_capacity(n);
    let mut s = 0.0;
    acc.push(0.0);
    for k in 1..n {
        s += chord(points[k - 1], points[k]).powf(e);
        acc.push(s);
    }
    let total = if closed {
        s + chord(points[n - 1], points[0]).powf(e)
    } else {
        s
    };
    if total.is_nan() || total <= 0.0 {
        return Err(BSplineError::CoincidentPoints { index: 1, prev: 0 });
    }
    for a in acc.iter_mut() {
        *a /= total;
    }
    if !closed {
        acc[n - 1] = 1.0;
    }
    Ok(acc)
}

fn chord(a: DVec3, b: DVec3) -> f64 {
    a.distance(b)
}

fn check_points(points: &[DVec3], closed: bool, need: usize) -> Result<(), BSplineError> {
    if points.len() < need {
        return Err(BSplineError::TooFewPoints {
            got: points.len(),
            need,
        });
    }
    for (i, p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(BSplineError::NonFinite {
                index: i,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
    }
    // Scale-relative coincidence test.
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let tol = 1e-14 * (hi - lo).length().max(f64::MIN_POSITIVE);
    for i in 1..points.len() {
        if points[i].distance(points[i - 1]) <= tol {
            return Err(BSplineError::CoincidentPoints {
                index: i,
                prev: i - 1,
            });
        }
    }
    if closed && points[0].distance(points[points.len() - 1]) <= tol {
        return Err(BSplineError::CoincidentPoints {
            index: 0,
            prev: points.len() - 1,
        });
    }
    Ok(())
}

/// Non-zero basis functions and their first two derivatives at `u` in knot span `span`
/// (NURBS Book A2.3, p = 3, n = 2). Returns `[values, first, second]`, each for basis
/// `span-3 ..= span`.
fn ders_basis(knots: &[f64], span: usize, u: f64) -> [[f64; 4]; 3] {
    const P: usize = DEGREE;
    let mut ndu = [[0.0f64; P + 1]; P + 1];
    let mut left = [0.0f64; P + 1];
    let mut right = [0.0f64; P + 1];
    ndu[0][0] = 1.0;
    for j in 1..=P {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = if ndu[j][r] != 0.0 {
                ndu[r][j - 1] / ndu[j][r]
            } else {
                0.0
            };
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    let mut ders = [[0.0f64; P + 1]; 3];
    for j in 0..=P {
        ders[0][j] = ndu[j][P];
    }
    let mut a = [[0.0f64; P + 1]; 2];
    for r in 0..=P {
        let (mut s1, mut s2) = (0usize, 1usize);
        a[0][0] = 1.0;
        for k in 1..=2usize {
            let mut d = 0.0;
            let rk = r as isize - k as isize;
            let pk = P - k;
            if r >= k {
                let rk = rk as usize;
                let den = ndu[pk + 1][rk];
                a[s2][0] = if den != 0.0 { a[s1][0] / den } else { 0.0 };
                d = a[s2][0] * ndu[rk][pk];
            }
            let j1: usize = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2: usize = if (r as isize - 1) <= pk as isize {
                k - 1
            } else {
                P - r
            };
            for j in j1..=j2 {
                let col = (rk + j as isize) as usize;
                let den = ndu[pk + 1][col];
                a[s2][j] = if den != 0.0 {
                    (a[s1][j] - a[s1][j - 1]) / den
                } else {
                    0.0
                };
                d += a[s2][j] * ndu[col][pk];
            }
            if r as isize <= pk as isize {
                let col = r;
                let den = ndu[pk + 1][col];
                a[s2][k] = if den != 0.0 { -a[s1][k - 1] / den } else { 0.0 };
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut fac = P as f64;
    for (k, row) in ders.iter_mut().enumerate().skip(1) {
        for v in row.iter_mut() {
            *v *= fac;
        }
        fac *= (P - k) as f64;
    }
    ders
}

/// Knot span index for `u` on a clamped knot vector with `n_ctrl` control points (A2.1); at the
/// right end returns the last non-empty span.
fn find_span(knots: &[f64], n_ctrl: usize, u: f64) -> usize {
    let n = n_ctrl - 1;
    if u >= knots[n + 1] {
        return n;
    }
    if u <= knots[DEGREE] {
        return DEGREE;
    }
    // Largest i in [p, n] with knots[i] <= u.
    let (mut lo, mut hi) = (DEGREE, n + 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if u < knots[mid] {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

/// Uniform periodic cubic basis at local parameter t ∈ [0,1): values, first and second
/// derivatives with respect to t.
fn periodic_basis(t: f64) -> [[f64; 4]; 3] {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    [
        [
            s * s * s / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ],
        [
            -s * s / 2.0,
            (3.0 * t2 - 4.0 * t) / 2.0,
            (-3.0 * t2 + 2.0 * t + 1.0) / 2.0,
            t2 / 2.0,
        ],
        [s, 3.0 * t - 2.0, -3.0 * t + 1.0, t],
    ]
}

/// Cholesky factorisation (in place, lower triangle) of a symmetric positive definite matrix
/// stored densely (row-major, `n × n`) whose non-zeros lie within `bw` of the diagonal (pass
/// `n - 1` for a full matrix); then solves for three right-hand sides.
fn cholesky_solve(
    a: &mut [f64],
    n: usize,
    bw: usize,
    rhs: &mut [DVec3],
) -> Result<(), BSplineError> {
    // Relative pivot threshold against the largest diagonal entry.
    let max_diag = (0..n).map(|i| a[i * n + i]).fold(0.0f64, f64::max);
    let tiny = max_diag * 1e-14;
    for j in 0..n {
        let j0 = j.saturating_sub(bw);
        let mut d = a[j * n + j];
        for k in j0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= tiny {
            return Err(BSplineError::Singular { pivot: j });
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        let i_end = (j + bw + 1).min(n);
        for i in j + 1..i_end {
            let i0 = i.saturating_sub(bw).max(j0);
            let mut s = a[i * n + j];
            for k in i0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    // Forward: L y = b.
    for i in 0..n {
        let i0 = i.saturating_sub(bw);
        let mut s = rhs[i];
        for k in i0..i {
            s -= a[i * n + k] * rhs[k];
        }
        rhs[i] = s / a[i * n + i];
    }
    // Backward: Lᵀ x = y.
    for i in (0..n).rev() {
        let i_end = (i + bw + 1).min(n);
        let mut s = rhs[i];
        for k in i + 1..i_end {
            s -= a[k * n + i] * rhs[k];
        }
        rhs[i] = s / a[i * n + i];
    }
    Ok(())
}

/// Rows of the second-difference penalty matrix `D`: control indices and weights.
///
/// Closed (uniform knots): `P_i − 2P_{i+1} + P_{i+2}` (indices mod n). Open: second *divided*
/// differences with respect to the Greville abscissae `ξ_i` (the knot averages), scaled by the
/// mean abscissa spacing, so that the penalty vanishes exactly on curves that are linear in
/// `u` (with uniform knots this is the usual P-spline second difference).
fn penalty_rows(knots: &[f64], n: usize, closed: bool) -> Vec<([usize; 3], [f64; 3])> {
    if closed {
        return (0..n)
            .map(|i| ([i % n, (i + 1) % n, (i + 2) % n], [1.0, -2.0, 1.0]))
            .collect();
    }
    if n < 3 {
        return Vec::new();
    }
    let xi: Vec<f64> = (0..n)
        .map(|i| (knots[i + 1] + knots[i + 2] + knots[i + 3]) / 3.0)
        .collect();
    let mean = (xi[n - 1] - xi[0]) / (n - 1) as f64;
    let tiny = mean * 1e-9;
    (0..n - 2)
        .map(|i| {
            let d0 = (xi[i + 1] - xi[i]).max(tiny);
            let d1 = (xi[i + 2] - xi[i + 1]).max(tiny);
            let w0 = mean / d0;
            let w1 = mean / d1;
            ([i, i + 1, i + 2], [w0, -(w0 + w1), w1])
        })
        .collect()
}

/// Adds `λ DᵀD` to the dense `n × n` matrix `a`.
fn add_penalty(a: &mut [f64], n: usize, lambda: f64, rows: &[([usize; 3], [f64; 3])]) {
    for (idx, w) in rows {
        for r in 0..3 {
            for c in 0..3 {
                a[idx[r] * n + idx[c]] += lambda * w[r] * w[c];
            }
        }
    }
}

/// `trace(DᵀD)`: the sum of squared weights.
fn penalty_trace(rows: &[([usize; 3], [f64; 3])]) -> f64 {
    rows.iter()
        .map(|(_, w)| w.iter().map(|x| x * x).sum::<f64>())
        .sum()
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

/// Clamped knot vector by averaging (algorithms.md §3.3): `n+1 = nc` control points, `m+1` data
/// parameters.
fn averaged_knots(params: &[f64], nc: usize) -> Vec<f64> {
    let p = DEGREE;
    let n = nc - 1;
    let m = params.len() - 1;
    let mut knots = vec![0.0; nc + p + 1];
    let (lo, hi) = (params[0].min(0.0), params[m].max(1.0));
    for k in knots.iter_mut().take(p + 1) {
        *k = lo;
    }
    for k in knots.iter_mut().skip(n + 1) {
        *k = hi;
    }
    let d = (m + 1) as f64 / (n - p + 1) as f64;
    for j in 1..=(n - p) {
        let jd = j as f64 * d;
        let i = (jd.floor() as usize).clamp(1, m);
        let alpha = jd - i as f64;
        knots[p + j] = (1.0 - alpha) * params[i - 1] + alpha * params[i];
    }
    knots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_open_and_closed() {
        let params: Vec<f64> = (0..20).map(|i| (i as f64 / 19.0).powf(1.3)).collect();
        let knots = averaged_knots(&params, 9);
        for i in 0..=200 {
            let u = i as f64 / 200.0;
            let span = find_span(&knots, 9, u);
            let b = ders_basis(&knots, span, u);
            assert!((b[0].iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(b[1].iter().sum::<f64>().abs() < 1e-9);
            assert!(b[2].iter().sum::<f64>().abs() < 1e-7);
            let pb = periodic_basis(u);
            assert!((pb[0].iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(pb[1].iter().sum::<f64>().abs() < 1e-12);
            assert!(pb[2].iter().sum::<f64>().abs() < 1e-12);
        }
    }

    #[test]
    fn knots_are_clamped_and_nondecreasing() {
        let params: Vec<f64> = (0..30).map(|i| i as f64 / 29.0).collect();
        for nc in 4..=30 {
            let k = averaged_knots(&params, nc);
            assert_eq!(k.len(), nc + 4);
            assert!(k[..4].iter().all(|&x| x == 0.0));
            assert!(k[nc..].iter().all(|&x| x == 1.0));
            assert!(k.windows(2).all(|w| w[0] <= w[1]), "{k:?}");
            // Every span contains a data parameter (Schoenberg-Whitney).
            for s in 3..nc {
                if k[s + 1] > k[s] {
                    assert!(params.iter().any(|&u| u >= k[s] && u <= k[s + 1]));
                }
            }
        }
    }

    #[test]
    fn cholesky_solves_banded_and_full() {
        // SPD tridiagonal-ish 6x6.
        let n = 6;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i * n + i] = 4.0;
            if i + 1 < n {
                a[i * n + i + 1] = 1.0;
                a[(i + 1) * n + i] = 1.0;
            }
        }
        let x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(i as f64, 1.0 - i as f64, 0.5 * i as f64))
            .collect();
        let b: Vec<DVec3> = (0..n)
            .map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum())
            .collect();
        for bw in [1, 3, n - 1] {
            let mut m = a.clone();
            let mut r = b.clone();
            cholesky_solve(&mut m, n, bw, &mut r).unwrap();
            for i in 0..n {
                assert!((r[i] - x[i]).length() < 1e-12);
            }
        }
        let mut sing = vec![0.0; 4];
        let mut r = vec![DVec3::ONE; 2];
        assert!(matches!(
            cholesky_solve(&mut sing, 2, 1, &mut r),
            Err(BSplineError::Singular { pivot: 0 })
        ));
    }
}
