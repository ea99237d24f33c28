//! Identification and verification figures of distance scores (lower: more alike), as the
//! benchmarks report them and as [`crate::VERIFY_THRESHOLD`] is calibrated: rank-1, the rank
//! of a probe's own identity, the equal error rate with its threshold, the ROC, the error
//! rates at a threshold, and the two tests the figures are read with (exact McNemar, Wilson
//! interval).
//!
//! A score that is not finite is a failed comparison: it counts as infinitely far, so it never
//! identifies a probe and is never accepted.

/// A score as the figures count it: a failed comparison (not finite) is infinitely far.
pub(crate) fn worst_if_failed(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::INFINITY
    }
}

/// The scores with failures infinitely far, sorted.
fn sorted(v: &[f64]) -> Vec<f64> {
    let mut s: Vec<f64> = v.iter().map(|&x| worst_if_failed(x)).collect();
    s.sort_by(f64::total_cmp);
    s
}

/// Share of the sorted `v` at or below `t` (0 for no scores).
fn share_at_or_below(v: &[f64], t: f64) -> f64 {
    v.partition_point(|x| *x <= t) as f64 / v.len().max(1) as f64
}

/// The error rates at threshold `t` (a pair is accepted when its score is at or below it):
/// `(false reject rate, false accept rate)`, the shares of `genuine` scores refused and of
/// `impostor` scores accepted. A failed score is refused at every threshold.
pub fn error_rates(genuine: &[f64], impostor: &[f64], t: f64) -> (f64, f64) {
    let (g, i) = (sorted(genuine), sorted(impostor));
    (1.0 - share_at_or_below(&g, t), share_at_or_below(&i, t))
}

/// The equal error rate of a set of genuine and impostor scores and the threshold where it is
/// reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eer {
    /// The mean of the false accept and false reject rates at the threshold where they are
    /// closest (the lowest such threshold on ties); 1 when no score is finite.
    pub rate: f64,
    /// That threshold (a score; at or below it: the same person); NaN when no score is finite.
    pub threshold: f64,
}

/// The ROC points (false accept rate, true accept rate) at every finite score taken as the
/// threshold, ascending, between (0, 0) and (1, 1), and the [`Eer`] among those thresholds.
/// Failed scores are never accepted (no threshold is infinite).
pub fn roc_eer(genuine: &[f64], impostor: &[f64]) -> (Vec<(f64, f64)>, Eer) {
    let (g, i) = (sorted(genuine), sorted(impostor));
    let mut thresholds: Vec<f64> = g
        .iter()
        .chain(&i)
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    thresholds.sort_by(f64::total_cmp);
    thresholds.dedup();
    let mut roc = vec![(0.0, 0.0)];
    let mut eer = Eer {
        rate: 1.0,
        threshold: f64::NAN,
    };
    let mut best_gap = f64::INFINITY;
    for &t in &thresholds {
        let far = share_at_or_below(&i, t);
        let tar = share_at_or_below(&g, t);
        roc.push((far, tar));
        let frr = 1.0 - tar;
        let gap = (far - frr).abs();
        if gap < best_gap {
            best_gap = gap;
            eer = Eer {
                rate: 0.5 * (far + frr),
                threshold: t,
            };
        }
    }
    roc.push((1.0, 1.0));
    (roc, eer)
}

/// The equal error rate of `genuine` and `impostor` scores ([`roc_eer`]'s).
pub fn eer(genuine: &[f64], impostor: &[f64]) -> Eer {
    roc_eer(genuine, impostor).1
}

/// Per probe (a row of `scores`, one score per gallery entry): whether its nearest gallery
/// entry (the lowest index on ties; failures last) has a finite score and the probe's identity.
pub fn identified<I: PartialEq>(
    scores: &[Vec<f64>],
    probe_id: &[I],
    gallery_id: &[I],
) -> Vec<bool> {
    scores
        .iter()
        .zip(probe_id)
        .map(|(row, id)| {
            let s = |k: usize| worst_if_failed(row[k]);
            (0..row.len())
                .min_by(|&a, &b| s(a).total_cmp(&s(b)).then(a.cmp(&b)))
                .is_some_and(|b| gallery_id[b] == *id && row[b].is_finite())
        })
        .collect()
}

/// Where a probe's own identity ranks in one row of scores ([`genuine_rank`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenuineRank<I> {
    /// 1 + the finite impostor scores strictly below the genuine one (1: identified); `None`
    /// when no genuine score is finite.
    pub rank: Option<usize>,
    /// The least genuine score (NaN when none is finite).
    pub genuine: f64,
    /// The identity and score of the nearest impostor (finite scores only; ties: the lesser
    /// identity).
    pub best_impostor: Option<(I, f64)>,
}

/// The rank of identity `id` among the gallery entries of one probe's `row` of scores.
pub fn genuine_rank<I: Ord + Copy>(row: &[f64], gallery_id: &[I], id: I) -> GenuineRank<I> {
    let genuine = row
        .iter()
        .zip(gallery_id)
        .filter(|(_, g)| **g == id)
        .map(|(v, _)| *v)
        .fold(f64::NAN, f64::min);
    let impostors = || {
        row.iter()
            .zip(gallery_id)
            .filter(|(v, g)| **g != id && v.is_finite())
    };
    let best_impostor = impostors()
        .min_by(|a, b| a.0.total_cmp(b.0).then(a.1.cmp(b.1)))
        .map(|(v, g)| (*g, *v));
    let rank = genuine
        .is_finite()
        .then(|| 1 + impostors().filter(|(v, _)| **v < genuine).count());
    GenuineRank {
        rank,
        genuine,
        best_impostor,
    }
}

/// The figures of one probes x gallery score matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoreFigures {
    /// Share of the probes identified at rank 1 ([`identified`]).
    pub rank1: f64,
    /// Per probe, identified at rank 1.
    pub identified: Vec<bool>,
    /// The equal error rate over every probe x gallery pair ([`roc_eer`]).
    pub eer: Eer,
    /// The ROC of those pairs.
    pub roc: Vec<(f64, f64)>,
    /// Mean of the finite genuine scores (NaN when none).
    pub genuine_mean: f64,
    /// Mean of the finite impostor scores (NaN when none).
    pub impostor_mean: f64,
    /// Pairs whose score failed (not finite).
    pub failures: usize,
}

/// Rank-1, EER, ROC, mean scores and failures of a probes x gallery score matrix (a pair is
/// genuine when the probe's and the gallery entry's identities are equal).
pub fn score_figures<I: PartialEq>(
    scores: &[Vec<f64>],
    probe_id: &[I],
    gallery_id: &[I],
) -> ScoreFigures {
    let identified = identified(scores, probe_id, gallery_id);
    let (mut genuine, mut impostor) = (Vec::new(), Vec::new());
    for (row, id) in scores.iter().zip(probe_id) {
        for (v, g) in row.iter().zip(gallery_id) {
            let to = if g == id { &mut genuine } else { &mut impostor };
            to.push(worst_if_failed(*v));
        }
    }
    let (roc, eer) = roc_eer(&genuine, &impostor);
    let mean = |v: &[f64]| {
        let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        f.iter().sum::<f64>() / f.len().max(1) as f64
    };
    ScoreFigures {
        rank1: identified.iter().filter(|&&i| i).count() as f64 / scores.len().max(1) as f64,
        eer,
        roc,
        genuine_mean: mean(&genuine),
        impostor_mean: mean(&impostor),
        failures: scores.iter().flatten().filter(|v| !v.is_finite()).count(),
        identified,
    }
}

/// The probes (by position) that only `a` identifies and that only `b` identifies.
pub fn discordant(a: &[bool], b: &[bool]) -> (usize, usize) {
    let only = |x: &[bool], y: &[bool]| x.iter().zip(y).filter(|(p, q)| **p && !**q).count();
    (only(a, b), only(b, a))
}

/// Exact two-sided McNemar test of two classifiers on the same probes, `b` of them identified
/// by the first only and `c` by the second only: the probability, were both equally good
/// (each discordant probe a fair coin), of a split at least as uneven,
/// `min(1, 2 P(X <= min(b, c)))` with `X ~ Binomial(b + c, 1/2)`; 1 without discordant probes.
pub fn mcnemar_exact(b: usize, c: usize) -> f64 {
    let n = b + c;
    let k = b.min(c);
    // ln C(n, i) - n ln 2, summed term by term.
    let mut ln_term = -(n as f64) * std::f64::consts::LN_2;
    let mut tail = ln_term.exp();
    for i in 1..=k {
        ln_term += ((n - i + 1) as f64).ln() - (i as f64).ln();
        tail += ln_term.exp();
    }
    (2.0 * tail).min(1.0)
}

/// Wilson score interval (95 %) of `k` successes in `n` trials (NaN for no trials).
pub fn wilson95(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let z = 1.959_963_984_540_054_f64;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eer_and_rank1_on_known_scores() {
        // 2 gallery ids, 2 probes each; probe 3 is misidentified.
        let gid = [0, 1];
        let pid = [0, 0, 1, 1];
        let s = vec![
            vec![0.1, 0.5],
            vec![0.2, 0.6],
            vec![0.7, 0.3],
            vec![0.4, 0.45],
        ];
        let f = score_figures(&s, &pid, &gid);
        assert!((f.rank1 - 0.75).abs() < 1e-12);
        assert!((f.genuine_mean - (0.1 + 0.2 + 0.3 + 0.45) / 4.0).abs() < 1e-12);
        assert!((f.impostor_mean - (0.5 + 0.6 + 0.7 + 0.4) / 4.0).abs() < 1e-12);
        assert_eq!(f.failures, 0);
        // Threshold 0.4: FAR 1/4, FRR 1/4 -> EER 0.25.
        assert!((f.eer.rate - 0.25).abs() < 1e-12, "{:?}", f.eer);
        assert_eq!(f.eer.threshold, 0.4);
        assert_eq!(f.roc.first(), Some(&(0.0, 0.0)));
        assert_eq!(f.roc.last(), Some(&(1.0, 1.0)));
        // Perfect separation gives EER 0; NaN counts as a failure.
        let g = score_figures(&[vec![0.1, f64::NAN], vec![0.9, 0.2]], &[0, 1], &gid);
        assert_eq!((g.rank1, g.eer.rate, g.failures), (1.0, 0.0, 1));
        assert_eq!(f.identified, [true, true, true, false]);
        // A probe whose every score failed is not identified, even of the first identity.
        assert_eq!(identified(&[vec![f64::NAN, f64::NAN]], &[0], &gid), [false]);
    }

    #[test]
    fn eer_of_separated_overlapping_and_failed_scores() {
        assert_eq!(eer(&[0.1, 0.2], &[0.5, 0.6]).rate, 0.0);
        // One genuine above one impostor of two each: one error each side at the best threshold.
        let e = eer(&[0.1, 0.55], &[0.5, 0.6]);
        assert!((e.rate - 0.5).abs() < 1e-12 && e.threshold == 0.5, "{e:?}");
        // Failures are never accepted: with no finite score there is no threshold.
        let e = eer(&[f64::INFINITY], &[f64::NAN]);
        assert!(e.rate == 1.0 && e.threshold.is_nan(), "{e:?}");
        // A failed genuine score is refused at every threshold.
        assert_eq!(error_rates(&[0.1, f64::NAN], &[0.5], 1.0), (0.5, 1.0));
        assert_eq!(error_rates(&[0.1, 0.3], &[0.2, 0.5], 0.2), (0.5, 0.5));
    }

    #[test]
    fn the_genuine_rank_counts_nearer_impostors() {
        let gid = [0, 1, 2, 1];
        let r = genuine_rank(&[0.5, 0.4, 0.2, f64::NAN], &gid, 1);
        assert_eq!(r.rank, Some(2));
        assert_eq!(r.genuine, 0.4);
        assert_eq!(r.best_impostor, Some((2, 0.2)));
        let failed = genuine_rank(&[0.5, f64::NAN], &[0, 1], 1);
        assert_eq!((failed.rank, failed.best_impostor), (None, Some((0, 0.5))));
        assert!(failed.genuine.is_nan());
    }

    #[test]
    fn the_mcnemar_p_value_is_the_two_sided_binomial_tail() {
        // 10 discordant probes split 9 : 1: 2 (1 + 10) / 1024.
        assert!((mcnemar_exact(9, 1) - 22.0 / 1024.0).abs() < 1e-15);
        assert!((mcnemar_exact(1, 9) - 22.0 / 1024.0).abs() < 1e-15);
        // 10 : 0: 2 / 1024; an even split and no discordant probe: 1.
        assert!((mcnemar_exact(10, 0) - 2.0 / 1024.0).abs() < 1e-15);
        assert_eq!(mcnemar_exact(5, 5), 1.0);
        assert_eq!(mcnemar_exact(0, 0), 1.0);
        // 6 : 2 (the figure of a 50-identity run): 2 (1 + 8 + 28) / 256.
        assert!((mcnemar_exact(6, 2) - 74.0 / 256.0).abs() < 1e-14);
        // Many probes, no underflow: 2 sum_{i <= 200} C(500, i) / 2^500 = 8.9401e-6 (exact
        // integer sum).
        let p = mcnemar_exact(300, 200);
        assert!((p / 8.940066542253267e-6 - 1.0).abs() < 1e-9, "{p}");
        assert_eq!(
            discordant(&[true, true, false], &[false, true, true]),
            (1, 1)
        );
    }

    #[test]
    fn wilson_interval_matches_known_values() {
        // 90 of 100: 0.825 - 0.945 (Wilson, z = 1.96).
        let (lo, hi) = wilson95(90, 100);
        assert!(
            (lo - 0.8256).abs() < 5e-4 && (hi - 0.9448).abs() < 5e-4,
            "{lo} {hi}"
        );
        // All or none: one end at the bound.
        assert!((wilson95(10, 10).1 - 1.0).abs() < 1e-12);
        assert!(wilson95(0, 10).0.abs() < 1e-12);
        assert!(wilson95(0, 0).0.is_nan());
    }
}
