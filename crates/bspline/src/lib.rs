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

mod basis;
mod curve;
mod params;
mod solve;

pub use curve::BSpline3;
pub use params::{data_params, dedup_consecutive};

use thiserror::Error;

/// Degree of every curve built by this crate (cubic).
pub const DEGREE: usize = 3;

meshcore::choice! {
    /// How data parameters are spaced along the polyline.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub enum Parametrization: "parametrization", BSplineError {
        /// Parameter increments proportional to chord lengths (exponent 1). The default.
        #[default]
        ChordLength = "chord-length" | "chord",
        /// Parameter increments proportional to the square root of chord lengths (exponent 0.5);
        /// safer when the point spacing varies a lot.
        Centripetal = "centripetal",
    }
}

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
