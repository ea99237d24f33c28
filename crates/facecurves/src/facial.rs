//! Facial curves (Samir, Srivastava, Daoudi and Klassen; Srivastava et al.; the paper's
//! section 6.2): a face as the indexed collection of level curves of the geodesic distance
//! from the nose tip, compared curve by curve with the elastic distance.
//!
//! Curve `i` is the level set `U = i * step` of the distance field `U` from the nose tip,
//! extracted by [`levelcurves::isolines_uniform`]. A level set crossing a hole or the border
//! of the mesh (an eye or the mouth of a face scan) falls into several pieces; the descriptor
//! keeps the longest piece of each level (closed or open). Two faces are compared over the
//! levels both have: each pair of curves by [`elastic_distance`], and the per-curve distances
//! combined by [`Aggregate`] (the papers' product metric is the root of the sum of squares).

use crate::elastic::{elastic_distance, ElasticMatch, ElasticOptions};
use crate::FaceCurvesError;
use geodesic::{GeodesicSolver, SolveOptions, Source};
use glam::DVec3;
use meshcore::Surface;

meshcore::choice! {
    /// How the per-curve distances of two faces are combined.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Aggregate: "curve aggregate", crate::FaceCurvesError {
        /// `sqrt(sum d_i^2)`: the distance in the product of the curves' shape spaces (Samir et
        /// al.).
        RootSumSquare = "rss" | "root-sum-square",
        /// `sum d_i`.
        Sum = "sum",
    }
}

/// Options of [`describe_facial_curves`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacialCurvesOptions {
    /// Geodesic distance between consecutive curves (mesh units, positive, finite).
    pub step: f64,
    /// Number of curves (levels `1..=levels`, at least 1).
    pub levels: u32,
}

/// One facial curve.
#[derive(Debug, Clone, PartialEq)]
pub struct FacialCurve {
    /// Its level `i` (1-based): the curve lies at geodesic distance `i * step` from the nose
    /// tip.
    pub level: u32,
    /// Ordered points on mesh edges (a closed curve does not repeat its first point).
    pub points: Vec<DVec3>,
    /// True for a closed loop.
    pub closed: bool,
    /// Pieces the level set had (1 when it is a single curve).
    pub pieces: usize,
}

/// The facial curves of a face: at most one curve per level, sorted by level.
#[derive(Debug, Clone, PartialEq)]
pub struct FacialCurvesDescriptor {
    /// The curves, sorted by level; levels that cross nothing are absent.
    pub curves: Vec<FacialCurve>,
    /// The options it was built with.
    pub options: FacialCurvesOptions,
}

/// The result of [`facial_curves_distance`].
#[derive(Debug, Clone, PartialEq)]
pub struct FacialDistance {
    /// The aggregated distance.
    pub distance: f64,
    /// Per shared level: the level and the elastic match of its two curves.
    pub per_curve: Vec<(u32, ElasticMatch)>,
    /// Levels present in only one of the two descriptors (not compared).
    pub unmatched: usize,
}

fn check_options(o: &FacialCurvesOptions) -> Result<(), FaceCurvesError> {
    if !(o.step.is_finite() && o.step > 0.0) {
        return Err(FaceCurvesError::InvalidOption(format!(
            "facial curve step {} (must be positive and finite)",
            o.step
        )));
    }
    if o.levels == 0 || o.levels > 10_000 {
        return Err(FaceCurvesError::InvalidOption(format!(
            "facial curve levels {} (must be in 1..=10000)",
            o.levels
        )));
    }
    Ok(())
}

/// The facial curves of `surface` from a precomputed geodesic distance `field` from the nose
/// tip (one value per vertex, `+inf` where unreachable or cut off).
///
/// Errors: invalid options, a field of the wrong length or with a NaN / `-inf` value, or no
/// level crossing the surface.
pub fn describe_facial_curves(
    surface: &Surface,
    field: &[f64],
    options: &FacialCurvesOptions,
) -> Result<FacialCurvesDescriptor, FaceCurvesError> {
    check_options(options)?;
    let mesh = surface.mesh();
    if field.len() != mesh.n_vertices() {
        return Err(FaceCurvesError::VertexCount {
            what: "field",
            expected: mesh.n_vertices(),
            got: field.len(),
        });
    }
    if let Some((vertex, &value)) = field
        .iter()
        .enumerate()
        .find(|(_, x)| x.is_nan() || **x == f64::NEG_INFINITY)
    {
        return Err(FaceCurvesError::NonFiniteField { vertex, value });
    }
    let lines = levelcurves::isolines_uniform(
        mesh,
        surface.topology(),
        field,
        options.step,
        options.levels,
    )?;
    let mut curves = Vec::new();
    for (li, pieces) in lines.into_iter().enumerate() {
        let count = pieces.len();
        // The longest piece; ties (equal lengths) keep the first in the isolines' order.
        let best =
            pieces
                .into_iter()
                .map(|p| (p.length(), p))
                .reduce(|a, b| if b.0 > a.0 { b } else { a });
        if let Some((len, p)) = best {
            let enough = if p.closed { 3 } else { 2 };
            if len > 0.0 && p.points.len() >= enough {
                curves.push(FacialCurve {
                    level: li as u32 + 1,
                    points: p.points,
                    closed: p.closed,
                    pieces: count,
                });
            }
        }
    }
    if curves.is_empty() {
        return Err(FaceCurvesError::NoCurves(format!(
            "no level {} x i (i = 1..={}) of the distance field crosses the surface",
            options.step, options.levels
        )));
    }
    Ok(FacialCurvesDescriptor {
        curves,
        options: *options,
    })
}

/// [`describe_facial_curves`] with the field computed by `solver` from `nose`, cut off just
/// beyond the last level (the cut-off never changes a value it keeps).
pub fn describe_facial_curves_from(
    surface: &Surface,
    solver: &dyn GeodesicSolver,
    nose: Source,
    options: &FacialCurvesOptions,
) -> Result<FacialCurvesDescriptor, FaceCurvesError> {
    check_options(options)?;
    let mesh = surface.mesh();
    let longest = mesh.longest_edge();
    let cutoff = options.step * options.levels as f64 + longest;
    let field = solver.distances(
        &[nose],
        &SolveOptions {
            max_distance: Some(cutoff),
        },
    )?;
    describe_facial_curves(surface, &field, options)
}

/// Distance of two faces by their facial curves: the curves of each level present in both
/// are compared by [`elastic_distance`] with `elastic`, and the distances combined by
/// `aggregate`. Levels present in one descriptor only are counted in
/// [`FacialDistance::unmatched`].
///
/// Errors: no shared level, or an error of the elastic distance (invalid options).
pub fn facial_curves_distance(
    a: &FacialCurvesDescriptor,
    b: &FacialCurvesDescriptor,
    aggregate: Aggregate,
    elastic: &ElasticOptions,
) -> Result<FacialDistance, FaceCurvesError> {
    let mut per_curve = Vec::new();
    let (mut i, mut j) = (0, 0);
    let mut unmatched = 0;
    while i < a.curves.len() && j < b.curves.len() {
        let (ca, cb) = (&a.curves[i], &b.curves[j]);
        match ca.level.cmp(&cb.level) {
            std::cmp::Ordering::Less => {
                unmatched += 1;
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                unmatched += 1;
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                let m = elastic_distance(&ca.points, ca.closed, &cb.points, cb.closed, elastic)?;
                per_curve.push((ca.level, m));
                i += 1;
                j += 1;
            }
        }
    }
    unmatched += (a.curves.len() - i) + (b.curves.len() - j);
    if per_curve.is_empty() {
        return Err(FaceCurvesError::NoSharedCurves {
            first: a.curves.len(),
            second: b.curves.len(),
        });
    }
    let distance = match aggregate {
        Aggregate::Sum => per_curve.iter().map(|(_, m)| m.distance).sum(),
        Aggregate::RootSumSquare => per_curve
            .iter()
            .map(|(_, m)| m.distance * m.distance)
            .sum::<f64>()
            .sqrt(),
    };
    Ok(FacialDistance {
        distance,
        per_curve,
        unmatched,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_parse() {
        meshcore::choice::check_choice::<Aggregate>("max").unwrap();
    }
}
