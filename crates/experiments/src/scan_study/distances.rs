//! The distances of two scans: each bipolar variant, the three pole pairs by `facematch`
//! (plain, view-matched and with the reference-point search), the single pole and ICP.

use super::description::{Described, Matched};
use super::variants::{PairCombine, VARIANTS};
use super::Args;
use crate::pipeline::{dist, landmark_icp_rms};
use facematch::{Comparison, MatchOptions, Pair, TemplateView};
use meshcore::{FaceLocator, TriMesh};

/// Name of the view-matched distance (the [`LEAST`](super::variants::LEAST) variant with `facematch`'s view matching:
/// each scan in turn the probe, the other described as the probe's scanner would have measured
/// it when their directions differ by at least `ViewOptions::min_angle_deg`).
pub(super) const VIEW_MATCHED: &str =
    "bipolar All, band and incidence over 60 degrees left out, three pole pairs, least, view-matched";

/// Name of the distance of the [`LEAST`](super::variants::LEAST) variant with the reference-point search
/// ([`searched_distance`]).
pub(super) const SEARCHED: &str =
    "bipolar All, band and incidence over 60 degrees left out, three pole pairs, least, reference-point search";

/// Names of the distances: the bipolar variants, the view-matched one, the searched one with
/// `args.ref_search_mm` > 0, then the single pole and ICP.
pub(super) fn methods(args: &Args) -> Vec<&'static str> {
    VARIANTS
        .iter()
        .map(|v| v.name)
        .chain([VIEW_MATCHED])
        .chain((args.ref_search_mm > 0.0).then_some(SEARCHED))
        .chain(["single pole", "ICP (mm)"])
        .collect()
}

/// The distances of two scans, in the order of [`methods`], and the kinds of the fallbacks
/// their `facematch` comparisons took (each prefixed by its distance's short name). `loc_a`
/// and `loc_b` locate the two scans' surfaces (ICP).
pub(super) fn pair_distances(
    a: &Described,
    b: &Described,
    loc_a: &FaceLocator<'_>,
    loc_b: &FaceLocator<'_>,
    args: &Args,
) -> (Vec<f64>, Vec<String>) {
    let o = super::matching(args);
    let mut fallbacks = Vec::new();
    let mut d: Vec<f64> = (0..VARIANTS.len())
        .map(|k| variant_distance(a, b, k, &o))
        .collect();
    let (view, kinds) = view_matched_distance(a, b, &o);
    fallbacks.extend(kinds.into_iter().map(|k| format!("view-matched: {k}")));
    d.push(view);
    if args.ref_search_mm > 0.0 {
        let (searched, kinds) = searched_distance(a, b, &o);
        fallbacks.extend(kinds.into_iter().map(|k| format!("searched: {k}")));
        d.push(searched);
    }
    d.push(dist(&a.polar, &b.polar).unwrap_or(f64::NAN));
    d.push(0.5 * (icp_score(a, b, loc_b) + icp_score(b, a, loc_a)));
    (d, fallbacks)
}

/// ICP of `a`'s probe points onto `b`'s surface from the landmark alignment: RMS closest-point
/// distance (mm) over all probe points at the final pose (`pipeline::landmark_icp_rms`, at
/// most 10 iterations).
fn icp_score(a: &Described, b: &Described, b_loc: &FaceLocator<'_>) -> f64 {
    landmark_icp_rms(&a.icp_probe, &a.landmarks, b_loc, &b.landmarks, 10)
}

/// The distance of two scans by variant `k` of [`VARIANTS`] (NaN where either has no
/// descriptor or the distance fails): the keyed distance of the corners' descriptors, or for a
/// three-pole-pair variant the mean or the least ([`facematch::pair_score`] with `o`) of the
/// three pairs' distances of `facematch`'s descriptions ([`facematch::compare`], `a` the probe,
/// without search or views: a distance of own descriptors, the same both ways up to rounding).
pub(super) fn variant_distance(a: &Described, b: &Described, k: usize, o: &MatchOptions) -> f64 {
    let Some(combine) = VARIANTS[k].side_pairs else {
        return match (&a.bip[k], &b.bip[k]) {
            (Some(x), Some(y)) => dist(x, y).unwrap_or(f64::NAN),
            _ => f64::NAN,
        };
    };
    let (Ok(ma), Ok(mb)) = (&a.matched, &b.matched) else {
        return f64::NAN;
    };
    let plain = MatchOptions {
        view: None,
        ..o.clone()
    };
    let c = facematch::compare(&ma.template.description, &mb.template, &plain);
    match combine {
        PairCombine::Mean => c.pairs.iter().map(|u| u.distance).sum::<f64>() / 3.0,
        PairCombine::Least => c.score,
    }
}

/// Two comparisons of a pair of scans, each scan the probe once (`one(x, y)`: `x` the probe,
/// `y` the template), combined symmetrically: per pole pair the lesser of the two distances
/// (NaN ones skipped), then [`facematch::pair_score`] with `o`'s rule. Also the kinds of the
/// fallbacks both comparisons took ([`Comparison::fallback_kinds`]). NaN when a scan has no
/// `facematch` description.
fn both_ways(
    a: &Described,
    b: &Described,
    o: &MatchOptions,
    one: impl Fn(&Described, &Matched, &Described, &Matched) -> Comparison,
) -> (f64, Vec<String>) {
    let (Ok(ma), Ok(mb)) = (&a.matched, &b.matched) else {
        return (f64::NAN, Vec::new());
    };
    let (ab, ba) = (one(a, ma, b, mb), one(b, mb, a, ma));
    let d = Pair::ALL.map(|p| {
        let i = p as usize;
        ab.pairs[i].distance.min(ba.pairs[i].distance)
    });
    let own = ma.template.description.pair;
    let score = facematch::pair_score(d, own, o.least_pair, o.second_weight).0;
    let mut kinds = ab.fallback_kinds();
    kinds.extend(ba.fallback_kinds());
    (score, kinds)
}

/// The [`LEAST`](super::variants::LEAST) distance with `facematch`'s view matching, each scan the probe once
/// ([`both_ways`]): the template is the other scan with one view, described
/// ([`facematch::describe_view`]) on the faces a scanner from the probe's direction would
/// have measured (the probe's scanner carried into the template's frame by the rigid fit of
/// the probe's landmarks onto the template's, [`facematch::probe_direction`]) when the two
/// directions differ by at least the view options' minimum angle; below it, or when the fit
/// fails, the template's own description ([`facematch::compare`] says which, and counts a view
/// or a pair's descriptor that failed as a fallback). No search: the probes' own descriptors.
pub(super) fn view_matched_distance(
    a: &Described,
    b: &Described,
    o: &MatchOptions,
) -> (f64, Vec<String>) {
    both_ways(a, b, o, |_, x, y_scan, y| {
        let probe = &x.template.description;
        let mut template = y.template.clone();
        template.views.extend(view_from(probe, &y_scan.mesh, y, o));
        facematch::compare(probe, &template, o)
    })
}

/// The view of the template `y` from the probe's scanner direction (see
/// [`view_matched_distance`]; `mesh` is the template's scan); `None` when the directions are within the minimum angle or the
/// fit fails.
fn view_from(
    probe: &facematch::Description,
    mesh: &TriMesh,
    y: &Matched,
    o: &MatchOptions,
) -> Option<TemplateView> {
    let v = o.view.as_ref()?;
    let t = &y.template.description;
    let toward = facematch::probe_direction(&probe.landmarks, probe.scanner, &t.landmarks)?;
    if toward.angle_between(t.scanner).to_degrees() < v.min_angle_deg {
        return None;
    }
    let sets = facematch::describe_view(mesh, y.poles, t.scanner, toward, o, v);
    Some(TemplateView {
        yaw_deg: f64::NAN,
        toward,
        sets,
    })
}

/// The [`LEAST`](super::variants::LEAST) distance with the reference-point search, each scan the probe once
/// ([`both_ways`]): per pole pair `facematch::compare`'s least over the probe's own and moved
/// descriptors against the template's own, the lesser of the two ways; so per pair the least
/// of own against own and each side's moved against the other's own, as
/// `bipolar::least_searched_distance` of the two scans. NaN where a scan has no `facematch`
/// description; the probe's own descriptor when the search was not run.
pub(super) fn searched_distance(
    a: &Described,
    b: &Described,
    o: &MatchOptions,
) -> (f64, Vec<String>) {
    let plain = MatchOptions {
        view: None,
        ..o.clone()
    };
    both_ways(a, b, o, |_, x, _, y| {
        let probe = x.searched.as_ref().unwrap_or(&x.template.description);
        facematch::compare(probe, &y.template, &plain)
    })
}
