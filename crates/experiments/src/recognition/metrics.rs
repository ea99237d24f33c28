//! The figures of the recognition benchmarks: identification and verification metrics of a
//! score matrix (rank-1, EER, ROC), the paired comparison of two scores (McNemar), and their
//! tables, summary and figures.

use super::compare::Row;
use super::Args;
use crate::report::{f4, line_plot, Report, Series};
use anyhow::Result;

/// Identification/verification figures of one score matrix.
#[derive(Debug, Clone, serde::Serialize)]
pub(super) struct Metrics {
    pub(super) descriptor: String,
    pub(super) landmarks: String,
    pub(super) rank1: f64,
    pub(super) eer: f64,
    pub(super) genuine_mean: f64,
    pub(super) impostor_mean: f64,
    pub(super) failures: usize,
    /// Mean single-thread wall time of one comparison (ms), over
    /// [`TIMED_PAIRS`](super::compare::TIMED_PAIRS) pairs.
    pub(super) ms_per_comparison: f64,
    /// Median single-thread wall time of one description (ms): its geodesic fields and its
    /// build; NaN for ICP, which compares the meshes themselves.
    pub(super) ms_per_description: f64,
    #[serde(skip)]
    pub(super) roc: Vec<(f64, f64)>,
    /// Per probe, in the run's probe order: identified at rank 1 ([`identified`]); in
    /// `summary.json`, so that runs of several seeds can be pooled probe by probe.
    pub(super) identified: Vec<bool>,
}

/// (rank-1 rate, EER, ROC points, mean genuine score, mean impostor score, failed pairs).
pub(super) type Figures = (f64, f64, Vec<(f64, f64)>, f64, f64, usize);

/// Rank-1 rate, EER and ROC from a probes x gallery score matrix (NaN = failure = worst).
pub(super) fn metrics(scores: &[Vec<f64>], probe_id: &[usize], gallery_id: &[usize]) -> Figures {
    let correct = identified(scores, probe_id, gallery_id)
        .into_iter()
        .filter(|&i| i)
        .count();
    let mut gen = Vec::new();
    let mut imp = Vec::new();
    let mut failures = 0;
    for (p, row) in scores.iter().enumerate() {
        let clean: Vec<f64> = row
            .iter()
            .map(|v| if v.is_finite() { *v } else { f64::INFINITY })
            .collect();
        failures += row.iter().filter(|v| !v.is_finite()).count();
        for (g, v) in clean.iter().enumerate() {
            if gallery_id[g] == probe_id[p] {
                gen.push(*v);
            } else {
                imp.push(*v);
            }
        }
    }
    let rank1 = correct as f64 / scores.len().max(1) as f64;
    let (eer, roc) = eer_roc(&gen, &imp);
    let fmean = |v: &[f64]| {
        let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        f.iter().sum::<f64>() / f.len().max(1) as f64
    };
    (rank1, eer, roc, fmean(&gen), fmean(&imp), failures)
}

/// Per probe (row of `scores`, NaN = failure): its nearest gallery face (the lowest index on
/// ties) is finite and of its own identity.
pub(super) fn identified(
    scores: &[Vec<f64>],
    probe_id: &[usize],
    gallery_id: &[usize],
) -> Vec<bool> {
    scores
        .iter()
        .zip(probe_id)
        .map(|(row, &id)| {
            let clean = |v: f64| if v.is_finite() { v } else { f64::INFINITY };
            (0..row.len())
                .min_by(|&a, &b| clean(row[a]).total_cmp(&clean(row[b])).then(a.cmp(&b)))
                .is_some_and(|b| gallery_id[b] == id && row[b].is_finite())
        })
        .collect()
}

/// Exact two-sided McNemar test of two classifiers on the same probes, `b` of them identified
/// by the first only and `c` by the second only: the probability, were both equally good
/// (each discordant probe a fair coin), of a split at least as uneven,
/// `min(1, 2 P(X <= min(b, c)))` with `X ~ Binomial(b + c, 1/2)`; 1 without discordant probes.
pub(super) fn mcnemar_exact(b: usize, c: usize) -> f64 {
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

/// Probes (by position) that only `a` identifies and that only `b` identifies.
pub(super) fn discordant(a: &Metrics, b: &Metrics) -> (usize, usize) {
    let only = |x: &Metrics, y: &Metrics| {
        x.identified
            .iter()
            .zip(&y.identified)
            .filter(|(a, b)| **a && !**b)
            .count()
    };
    (only(a, b), only(b, a))
}

/// Appends the paired comparison of bipolar with every other score on the same probes, per
/// landmark set: the probes only one of the two identifies and the exact McNemar p-value
/// ([`mcnemar_exact`]), so that a difference in rank-1 can be told from chance.
pub(super) fn paired_table(rep: &mut Report, all: &[Metrics]) {
    let rows: Vec<Vec<String>> = all
        .iter()
        .filter(|b| b.descriptor == "bipolar")
        .flat_map(|b| {
            all.iter()
                .filter(move |o| o.landmarks == b.landmarks && o.descriptor != "bipolar")
                .map(move |o| {
                    let (nb, no) = discordant(b, o);
                    vec![
                        b.landmarks.clone(),
                        o.descriptor.clone(),
                        format!("{:.3} / {:.3}", b.rank1, o.rank1),
                        nb.to_string(),
                        no.to_string(),
                        match mcnemar_exact(nb, no) {
                            p if p < 1e-3 => format!("{p:.1e}"),
                            p => format!("{p:.3}"),
                        },
                    ]
                })
        })
        .collect();
    rep.para("Paired comparison on the same probes: how many only bipolar identifies at rank 1, how many only the other score, and the exact two-sided McNemar p-value (the chance of a split at least as uneven were the two equally good; small values mean the difference in rank-1 is not luck of the probes).");
    rep.table(
        &[
            "landmarks",
            "against",
            "rank-1 (bipolar / other)",
            "only bipolar",
            "only the other",
            "McNemar p",
        ],
        &rows,
    );
}

/// Equal error rate and ROC points (false accept rate, true accept rate) for distance scores:
/// a pair is accepted when its score is <= the threshold.
pub(super) fn eer_roc(gen: &[f64], imp: &[f64]) -> (f64, Vec<(f64, f64)>) {
    let mut thr: Vec<f64> = gen
        .iter()
        .chain(imp)
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    thr.sort_by(f64::total_cmp);
    thr.dedup();
    let mut g = gen.to_vec();
    let mut i = imp.to_vec();
    g.sort_by(f64::total_cmp);
    i.sort_by(f64::total_cmp);
    let frac_le = |v: &[f64], t: f64| v.partition_point(|x| *x <= t) as f64 / v.len().max(1) as f64;
    let mut roc = vec![(0.0, 0.0)];
    let mut eer = 1.0;
    let mut best_gap = f64::INFINITY;
    for &t in &thr {
        let far = frac_le(&i, t);
        let tar = frac_le(&g, t);
        roc.push((far, tar));
        let frr = 1.0 - tar;
        let gap = (far - frr).abs();
        if gap < best_gap {
            best_gap = gap;
            eer = 0.5 * (far + frr);
        }
    }
    roc.push((1.0, 1.0));
    (eer, roc)
}

/// Names of the five scores of [`score_row`](super::compare::score_row).
pub(super) const SCORES: [&str; 5] = [
    "bipolar",
    "single_pole",
    "icp_raw_mesh",
    "facial_curves",
    "iso_curvature",
];

/// Index in [`Described::secs`](super::describe::Described::secs) of each score's description (ICP
/// has none).
pub(super) const DESCRIPTION_OF: [Option<usize>; 5] = [Some(0), Some(1), None, Some(2), Some(3)];

/// The element at `pick(len)` of the sorted finite values (NaN when there is none).
pub(super) fn order_stat(mut v: Vec<f64>, pick: impl Fn(usize) -> usize) -> f64 {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[pick(v.len())]
    }
}

/// Median of the finite values (the upper one of an even count; NaN when there is none).
pub(super) fn median(v: Vec<f64>) -> f64 {
    order_stat(v, |n| n / 2)
}

/// The figures of the five score matrices of one landmark set (rows from
/// [`score_row`](super::compare::score_row)), with the times per comparison
/// ([`time_comparisons`](super::compare::time_comparisons)) and per description
/// ([`time_descriptions`](super::compare::time_descriptions); ICP has none).
pub(super) fn summarize(
    rows: &[Row],
    ms_comparison: &[f64; 5],
    ms_description: &[f64; 4],
    probe_id: &[usize],
    gallery_id: &[usize],
    landmarks: &str,
) -> Vec<Metrics> {
    SCORES
        .iter()
        .enumerate()
        .map(|(j, dname)| {
            let m: Vec<Vec<f64>> = rows.iter().map(|r| r[j].clone()).collect();
            let (rank1, eer, roc, gm, im, failures) = metrics(&m, probe_id, gallery_id);
            let identified = identified(&m, probe_id, gallery_id);
            Metrics {
                descriptor: dname.to_string(),
                landmarks: landmarks.to_string(),
                rank1,
                eer,
                genuine_mean: gm,
                impostor_mean: im,
                failures,
                ms_per_comparison: ms_comparison[j],
                ms_per_description: DESCRIPTION_OF[j].map_or(f64::NAN, |k| ms_description[k]),
                roc,
                identified,
            }
        })
        .collect()
}

/// Appends the table of `all` (rank-1, EER, mean scores, failed pairs, times) to the report
/// and writes it as the CSV file `csv`.
pub(super) fn results_table(rep: &mut Report, all: &[Metrics], csv: &str) -> Result<()> {
    let ms = |x: f64| {
        if x.is_finite() {
            format!("{x:.3}")
        } else {
            "-".to_string()
        }
    };
    let rows: Vec<Vec<String>> = all
        .iter()
        .map(|m| {
            vec![
                m.descriptor.clone(),
                m.landmarks.clone(),
                format!("{:.3}", m.rank1),
                format!("{:.3}", m.eer),
                f4(m.genuine_mean),
                f4(m.impostor_mean),
                m.failures.to_string(),
                ms(m.ms_per_comparison),
                ms(m.ms_per_description),
            ]
        })
        .collect();
    let hdr = [
        "descriptor",
        "landmarks",
        "rank-1",
        "EER",
        "mean genuine score",
        "mean impostor score",
        "failed pairs",
        "ms per comparison",
        "ms per description",
    ];
    rep.table(&hdr, &rows);
    rep.csv(csv, &hdr, &rows)
}

/// Writes `summary.json` into `out` and prints the results ([`print_results`]). The summary
/// holds the settings both benchmarks share (`sampled`: identities, faces per identity, gallery
/// and probe faces; the seed, the geodesic method, the resolution and the curve settings), the
/// task's own `fields` and the `results`.
pub(super) fn write_summary(
    out: &std::path::Path,
    args: &Args,
    sampled: [usize; 4],
    method: geodesic::Method,
    fields: serde_json::Value,
    results: &[Metrics],
) -> Result<()> {
    let [identities, expressions, gallery, probes] = sampled;
    let mut summary = serde_json::json!({
        "identities": identities,
        "faces_per_identity": expressions,
        "seed": args.seed,
        "gallery": gallery,
        "probes": probes,
        "geodesic_method": method.name(),
        "levels": args.res.levels,
        "sectors": args.res.sectors,
        "iso_levels": args.iso_levels,
        "curve_samples": args.curve_samples,
        "results": results,
    });
    if let (Some(s), serde_json::Value::Object(f)) = (summary.as_object_mut(), fields) {
        s.extend(f);
    }
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    print_results(results);
    Ok(())
}

/// One line per result on stderr (the end of a run).
pub(super) fn print_results(all: &[Metrics]) {
    for m in all {
        eprintln!(
            "{:<14} {:<13} rank-1 {:.3}  EER {:.3}  failed pairs {}  {:.3} ms/comparison  {:.1} ms/description",
            m.descriptor, m.landmarks, m.rank1, m.eer, m.failures, m.ms_per_comparison, m.ms_per_description
        );
    }
}

/// Draws the ROC curves of `all` into `file` and appends the figure to the report.
pub(super) fn roc_figure(rep: &mut Report, all: &[Metrics], file: &str, title: &str) -> Result<()> {
    let series: Vec<Series> = all
        .iter()
        .map(|m| Series {
            name: format!("{} ({})", m.descriptor, m.landmarks),
            points: m.roc.clone(),
            dashed: m.landmarks == "detected",
        })
        .collect();
    line_plot(
        &rep.path(file),
        title,
        "false accept rate",
        "true accept rate",
        &series,
    )?;
    rep.figure(file, &format!("{title}; dashed: detected landmarks"));
    Ok(())
}
