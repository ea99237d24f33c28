//! Figure 15: the single-pole descriptor's rings rotated about their centroids, scored by each
//! family of distance (keyed L2, elastic over curves, ICP).

use crate::pipeline::dist;
use crate::polar;
use crate::robustness::pole::rotate_rings;
use anyhow::Result;
use bipolar::PolarDescriptor;
use facecurves::{facial_curves_distance, Aggregate, ElasticOptions, FaceCurvesError};
use facecurves::{FacialCurve, FacialCurvesDescriptor, FacialCurvesOptions, FacialDistance};
use meshcore::DVec3;

/// Figure-15 scores: `(distance name, rotated copy, other person)`.
pub(super) type Fig15 = Vec<(&'static str, f64, f64)>;

/// The polar descriptor's rings (levels `1..=levels` with at least 3 points) as closed facial
/// curves, points in sector order.
fn rings(s: &PolarDescriptor, levels: u32) -> FacialCurvesDescriptor {
    let curves = (1..=levels)
        .filter_map(|level| {
            let mut pts: Vec<(u32, DVec3)> = s
                .points
                .iter()
                .filter(|p| p.key.level == level)
                .map(|p| (p.key.sector, p.position))
                .collect();
            pts.sort_by_key(|p| p.0);
            (pts.len() >= 3).then(|| FacialCurve {
                level,
                points: pts.into_iter().map(|p| p.1).collect(),
                closed: true,
                pieces: 1,
            })
        })
        .collect();
    let options = FacialCurvesOptions {
        step: s.options.step,
        levels,
    };
    FacialCurvesDescriptor { curves, options }
}

/// Elastic root-sum-square distance over the rings two polar descriptors share
/// (`facecurves::facial_curves_distance`, as the facial curves are compared).
fn ring_elastic(
    a: &PolarDescriptor,
    b: &PolarDescriptor,
    levels: u32,
) -> Result<FacialDistance, FaceCurvesError> {
    let e = ElasticOptions::default();
    facial_curves_distance(
        &rings(a, levels),
        &rings(b, levels),
        Aggregate::RootSumSquare,
        &e,
    )
}

/// Rings of `s` rotated one by one (seed `seed`), scored by the keyed, ring-wise elastic and
/// ICP distances against the same distance to `other` (the nearest other person); also each
/// ring's elastic distance to its rotated copy.
pub(super) fn figure15(
    s: &PolarDescriptor,
    other: Option<&PolarDescriptor>,
    seed: u64,
    levels: u32,
) -> Result<(Fig15, Vec<(u32, f64)>)> {
    let s1 = rotate_rings(s, seed);
    let rotated = ring_elastic(s, &s1, levels)?;
    let per_ring = rotated.per_curve.iter().map(|(l, m)| (*l, m.distance));
    let o = other.cloned().unwrap_or_else(|| polar::empty(&s.options));
    let icp = |a: &PolarDescriptor, b: &PolarDescriptor| -> f64 {
        shapedist::icp_distance_points(&a.positions(), &b.positions(), &Default::default())
            .map_or(f64::NAN, |d| d.stats.rms_normalised)
    };
    let table = vec![
        (
            "keyed L2 (bipolar, single pole)",
            dist(s, &s1).unwrap_or(f64::NAN),
            dist(s, &o).unwrap_or(f64::NAN),
        ),
        (
            "elastic, root sum of squares over rings (facial curves)",
            rotated.distance,
            ring_elastic(s, &o, levels).map_or(f64::NAN, |d| d.distance),
        ),
        (
            "ICP closest points (iso-curvature)",
            icp(s, &s1),
            icp(s, &o),
        ),
    ];
    Ok((table, per_ring.collect()))
}
