//! Figure 15: the single-pole descriptor's rings rotated about their centroids, scored by each
//! family of distance (keyed L2, elastic over curves, ICP).

use crate::pipeline::dist;
use crate::polar;
use crate::robustness::pole::rotate_rings;
use anyhow::Result;
use bipolar::PolarDescriptor;
use facecurves::{elastic_distance, ElasticOptions};
use meshcore::DVec3;

/// Figure-15 scores: `(distance name, rotated copy, other person)`.
pub(super) type Fig15 = Vec<(&'static str, f64, f64)>;

/// The polar descriptor's rings as closed curves (points of a ring in sector order).
fn rings(s: &PolarDescriptor, levels: u32) -> Vec<(u32, Vec<DVec3>)> {
    (1..=levels)
        .filter_map(|lvl| {
            let mut pts: Vec<(u32, DVec3)> = s
                .points
                .iter()
                .filter(|p| p.key.level == lvl)
                .map(|p| (p.key.sector, p.position))
                .collect();
            pts.sort_by_key(|p| p.0);
            (pts.len() >= 3).then(|| (lvl, pts.into_iter().map(|p| p.1).collect()))
        })
        .collect()
}

/// Elastic root-sum-square distance over the rings two polar descriptors share.
/// Also returns each shared ring's elastic distance.
fn ring_elastic(
    a: &PolarDescriptor,
    b: &PolarDescriptor,
    levels: u32,
) -> Result<(f64, Vec<(u32, f64)>)> {
    let (ra, rb) = (rings(a, levels), rings(b, levels));
    let mut per = Vec::new();
    for (la, pa) in &ra {
        if let Some((_, pb)) = rb.iter().find(|(lb, _)| lb == la) {
            let m = elastic_distance(pa, true, pb, true, &ElasticOptions::default())?;
            per.push((*la, m.distance));
        }
    }
    Ok((per.iter().map(|p| p.1 * p.1).sum::<f64>().sqrt(), per))
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
            rotated.0,
            ring_elastic(s, &o, levels)?.0,
        ),
        (
            "ICP closest points (iso-curvature)",
            icp(s, &s1),
            icp(s, &o),
        ),
    ];
    Ok((table, rotated.1))
}
