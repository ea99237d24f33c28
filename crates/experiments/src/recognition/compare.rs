//! The five scores of a probe against a gallery face, and their single-thread timings.

use super::describe::{describe_face, DescribeOptions, Described};
use super::metrics::median;
use super::Lm;
use crate::pipeline::{dist, single_thread};
use crate::walk::Walker;
use anyhow::Result;
use facecurves::nose::{facial_distance, iso_distance_from};
use facecurves::ElasticOptions;
use meshcore::linalg::fit_rigid;
use meshcore::{DVec3, FaceLocator, TriMesh};
use rayon::prelude::*;
use shapedist::{IcpOptions, IcpVariant};
use std::time::Instant;

/// The ICP of the iso-curvature networks, started from the landmark alignment: 10
/// point-to-point iterations on a 500-point subsample, then at most 10 on all points (the
/// other settings those of `shapedist`'s global refinement).
const ISO_ICP: IcpOptions = IcpOptions {
    variant: IcpVariant::PointToPoint,
    max_iterations: 10,
    tolerance: 1e-6,
    trim: 0.0,
    translation: false,
    coarse_iterations: 10,
};

/// Iterations of the recognition ICP ([`shapedist::landmark_icp_rms`]: started from the
/// landmark alignment, scored by the RMS closest-point distance of all probe points).
const ICP_ITERATIONS: usize = 6;

/// About `n` vertices of a probe for ICP, evenly strided ([`shapedist::strided_points`]).
pub(super) fn icp_points(mesh: &TriMesh, n: usize) -> Vec<DVec3> {
    shapedist::strided_points(mesh.positions(), n)
}

/// The bipolar distance of a probe `x` to a gallery face `y` by each pole pair (NaN where a
/// side has no descriptions or the distance fails) and the kinds of the fallbacks the comparison
/// took: [`facematch::compare`] as with `y`'s template (view matching against its stored view
/// nearest the probe's scanner direction; per pair the least over the probe's own and moved
/// descriptors).
fn bipolar_pairs(x: &Described, y: &Described) -> PairDistances {
    let (Ok(xd), Ok(yd)) = (&x.bip, &y.bip) else {
        return ([f64::NAN; 3], Vec::new());
    };
    let template = facematch::Template {
        identity: String::new(),
        source: String::new(),
        settings: String::new(),
        description: yd.clone(),
        views: y.views.as_ref().map_or(Vec::new(), |v| v.0.clone()),
        notes: Vec::new(),
    };
    let o = facematch::MatchOptions {
        view: y.views.as_ref().map(|v| v.1.clone()),
        ..x.matching.clone()
    };
    let c = facematch::compare(xd, &template, &o);
    (c.pairs.map(|u| u.distance), c.fallback_kinds())
}

/// The bipolar distances of one comparison by each pole pair, and the kinds of its fallbacks.
pub(super) type PairDistances = ([f64; 3], Vec<String>);

/// The bipolar score of a probe `x` from its distances by each pair `d` ([`bipolar_pairs`]):
/// [`facematch::pair_score`] with the probe's pair and its options.
fn bipolar_score(x: &Described, d: [f64; 3]) -> f64 {
    match &x.bip {
        Ok(xd) => {
            facematch::pair_score(d, xd.pair, x.matching.least_pair, x.matching.second_weight).0
        }
        Err(_) => f64::NAN,
    }
}

/// Score `k` of [`SCORES`](super::metrics::SCORES) of a probe (its description `x` and ICP points
/// `pts`) against a gallery face (`y`, its surface `loc`); NaN when a description is missing or the
/// score fails.
fn score_one(
    k: usize,
    x: &Described,
    pts: &[DVec3],
    y: &Described,
    loc: &FaceLocator<'_>,
    elastic: &ElasticOptions,
) -> f64 {
    match k {
        0 => bipolar_score(x, bipolar_pairs(x, y).0),
        1 => dist(&x.pol, &y.pol).unwrap_or(f64::NAN),
        2 => shapedist::landmark_icp_rms(pts, &x.lm_pos, loc, &y.lm_pos, ICP_ITERATIONS),
        3 => match (&x.facial, &y.facial) {
            (Ok(a), Ok(b)) => facial_distance(a, b, elastic).unwrap_or(f64::NAN),
            _ => f64::NAN,
        },
        _ => match (&x.iso, &y.iso) {
            (Ok(a), Ok(b)) => fit_rigid(&x.lm_pos, &y.lm_pos, None).map_or(f64::NAN, |m| {
                iso_distance_from(b, a, m.matrix3, &ISO_ICP).unwrap_or(f64::NAN)
            }),
            _ => f64::NAN,
        },
    }
}

/// Scores of one probe against every gallery face, per score of [`SCORES`](super::metrics::SCORES)
/// (NaN where either side has no description or the score fails).
pub(super) type Row = [Vec<f64>; 5];

/// Scores of one probe (its description and ICP points) against every gallery face: bipolar,
/// single pole, ICP, facial curves (elastic distance with `elastic`) and iso-curvature (ICP of
/// the networks' points from the landmark alignment); with the bipolar distance by each pair
/// and the comparison's fallbacks ([`bipolar_pairs`]).
fn score_row(
    probe: Option<&Described>,
    pts: &[DVec3],
    gallery: &[Option<(&Described, &FaceLocator<'_>)>],
    elastic: &ElasticOptions,
) -> (Row, Vec<PairDistances>) {
    let pairs: Vec<PairDistances> = gallery
        .iter()
        .map(|g| match (probe, g) {
            (Some(x), Some((y, _))) => bipolar_pairs(x, y),
            _ => ([f64::NAN; 3], Vec::new()),
        })
        .collect();
    let row = std::array::from_fn(|k| {
        gallery
            .iter()
            .zip(&pairs)
            .map(|(g, d)| match (probe, g) {
                (Some(x), Some(_)) if k == 0 => bipolar_score(x, d.0),
                (Some(x), Some((y, loc))) => score_one(k, x, pts, y, loc, elastic),
                _ => f64::NAN,
            })
            .collect()
    });
    (row, pairs)
}

/// The score rows of a set of probes, their bipolar distances by pair and each score's mean
/// single-thread time per comparison (ms).
pub(super) type ScoredSet = (Vec<Row>, Vec<Vec<PairDistances>>, [f64; 5]);

/// The scores of `probes` (description, ICP points) against `gallery` (description, surface):
/// the rows and bipolar pair distances of [`score_row`], in parallel,
/// and each score's mean single-thread time over up to [`TIMED_PAIRS`] of the pairs.
pub(super) fn score_set(
    probes: &[(Option<&Described>, &[DVec3])],
    gallery: &[Option<(&Described, &FaceLocator<'_>)>],
    elastic: &ElasticOptions,
) -> Result<ScoredSet> {
    let (rows, pairs) = probes
        .par_iter()
        .map(|(p, pts)| score_row(*p, pts, gallery, elastic))
        .unzip();
    let ms = time_comparisons(&timed_pairs(probes, gallery), elastic)?;
    Ok((rows, pairs, ms))
}

/// Faces whose descriptions are timed (single thread).
pub(super) const TIMED_FACES: usize = 6;

/// Pairs timed per landmark set (single thread).
pub(super) const TIMED_PAIRS: usize = 24;

/// Mean single-thread wall time (ms) of each score of [`SCORES`](super::metrics::SCORES) over
/// `pairs` (probe, its ICP points, gallery face, its surface), run on a one-thread pool after the
/// parallel scoring.
fn time_comparisons(
    pairs: &[(&Described, &[DVec3], &Described, &FaceLocator<'_>)],
    elastic: &ElasticOptions,
) -> Result<[f64; 5]> {
    let (ms, _) = single_thread(|| {
        std::array::from_fn(|k| {
            let t = Instant::now();
            for (x, pts, y, loc) in pairs {
                std::hint::black_box(score_one(k, x, pts, y, loc, elastic));
            }
            1e3 * t.elapsed().as_secs_f64() / pairs.len().max(1) as f64
        })
    })?;
    Ok(ms)
}

/// Up to [`TIMED_PAIRS`] probe x gallery pairs where both faces are described: probes in
/// order, each against the gallery faces in turn.
fn timed_pairs<'a>(
    probes: &[(Option<&'a Described>, &'a [DVec3])],
    gallery: &[Option<(&'a Described, &'a FaceLocator<'a>)>],
) -> Vec<(
    &'a Described,
    &'a [DVec3],
    &'a Described,
    &'a FaceLocator<'a>,
)> {
    let mut out = Vec::new();
    for (i, (p, pts)) in probes.iter().enumerate() {
        let Some(p) = p else { continue };
        let g = gallery
            .iter()
            .skip(i % gallery.len().max(1))
            .flatten()
            .next();
        if let Some((y, loc)) = g {
            out.push((*p, *pts, *y, *loc));
        }
        if out.len() == TIMED_PAIRS {
            break;
        }
    }
    out
}

/// Median single-thread wall time (ms) of each description (bipolar, single pole, facial
/// curves, iso-curvature: their fields and builds) over `faces`, described again on a
/// one-thread pool.
pub(super) fn time_descriptions(
    faces: &[(&TriMesh, Lm)],
    method: geodesic::Method,
    o: &DescribeOptions,
) -> Result<[f64; 4]> {
    let (secs, _) = single_thread(|| -> Result<Vec<[f64; 4]>> {
        let mut v = Vec::new();
        for (mesh, lm) in faces {
            let solver = geodesic::new_solver(mesh, method)?;
            let walker = Walker::new(mesh);
            if let Ok(d) = describe_face(mesh, solver.as_ref(), &walker, *lm, o) {
                v.push(d.secs);
            }
        }
        Ok(v)
    })?;
    let secs = secs?;
    Ok(std::array::from_fn(|k| {
        1e3 * median(secs.iter().map(|s| s[k]).collect())
    }))
}
