//! Validation and elementary statistics of point sets.

use glam::{DMat3, DVec3};

use crate::error::{ShapeDistError, Which};
use meshcore::linalg::sym_eigen3;

/// Checks that a set is non-empty and finite.
pub fn validate(points: &[DVec3], which: Which) -> Result<(), ShapeDistError> {
    if points.is_empty() {
        return Err(ShapeDistError::Empty(which));
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(ShapeDistError::NonFinite { which, index });
    }
    Ok(())
}

/// Arithmetic mean of the points (zero for an empty slice).
pub fn centroid(points: &[DVec3]) -> DVec3 {
    if points.is_empty() {
        return DVec3::ZERO;
    }
    // Two-pass mean for accuracy with large offsets.
    let first = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    first + points.iter().map(|&p| p - first).sum::<DVec3>() / points.len() as f64
}

/// Points translated so that their centroid is the origin, and the centroid.
pub fn centred(points: &[DVec3]) -> (Vec<DVec3>, DVec3) {
    let c = centroid(points);
    (points.iter().map(|&p| p - c).collect(), c)
}

/// `max |p|` over centred points (the radius `rho` of the normalisations).
pub fn radius(centred: &[DVec3]) -> f64 {
    centred.iter().fold(0.0f64, |m, p| m.max(p.length()))
}

/// Eigenvalues (descending) and axes of the scatter matrix `sum p p^T` of centred points.
pub fn principal_axes(centred: &[DVec3]) -> ([f64; 3], [DVec3; 3]) {
    let s = centred.iter().fold(DMat3::ZERO, |acc, &p| {
        acc + DMat3::from_cols(p * p.x, p * p.y, p * p.z)
    });
    sym_eigen3(s)
}

/// Relative threshold under which a principal extent counts as zero.
pub const DEGENERACY_RATIO: f64 = 1e-10;

/// Errors with [`ShapeDistError::Degenerate`] when the centred points are coincident or
/// collinear (second principal extent below [`DEGENERACY_RATIO`] of the first, in length).
pub fn check_spread(centred: &[DVec3], which: Which) -> Result<(), ShapeDistError> {
    let (vals, _) = principal_axes(centred);
    let scale = centred.iter().map(|p| p.length_squared()).sum::<f64>();
    if scale.is_nan() || scale <= 0.0 || vals[0] <= 0.0 {
        return Err(ShapeDistError::Degenerate {
            which,
            detail: format!("all {} points coincide", centred.len()),
        });
    }
    if vals[1].max(0.0) <= vals[0] * DEGENERACY_RATIO * DEGENERACY_RATIO {
        return Err(ShapeDistError::Degenerate {
            which,
            detail: format!("the {} points are collinear", centred.len()),
        });
    }
    Ok(())
}

/// Outer product `a b^T`.
#[inline]
pub fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}
