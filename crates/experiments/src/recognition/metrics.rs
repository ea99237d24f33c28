//! The tables, summary and figures of the recognition benchmarks: the identification and
//! verification figures of each score matrix (`facematch::metrics`: rank-1, EER, ROC, the
//! paired McNemar test) as the report shows them.

use super::compare::Row;
use super::Args;
use crate::report::{f4, quantile, sorted, Report, Series};
use anyhow::Result;
use facematch::metrics::{discordant, mcnemar_exact, score_figures};

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
    /// Per probe, in the run's probe order: identified at rank 1
    /// ([`facematch::metrics::identified`]); in
    /// `summary.json`, so that runs of several seeds can be pooled probe by probe.
    pub(super) identified: Vec<bool>,
}

impl Metrics {
    /// `descriptor (landmarks)`: the score's name in tables and figures.
    pub(super) fn label(&self) -> String {
        format!("{} ({})", self.descriptor, self.landmarks)
    }

    /// The score's line through `points` in a figure, dashed for the detected landmarks.
    pub(super) fn series(&self, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: self.label(),
            points,
            dashed: self.landmarks == "detected",
        }
    }
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
                    let (nb, no) = discordant(&b.identified, &o.identified);
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

/// The nearest-rank quantile `p` of the finite values ([`quantile`]: the median of an even
/// count is the upper middle value; NaN when there is none).
pub(super) fn finite_quantile(mut v: Vec<f64>, p: f64) -> f64 {
    v.retain(|x| x.is_finite());
    quantile(&sorted(v), p)
}

/// Median of the finite values ([`finite_quantile`]).
pub(super) fn median(v: Vec<f64>) -> f64 {
    finite_quantile(v, 0.5)
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
            let f = score_figures(&m, probe_id, gallery_id);
            Metrics {
                descriptor: dname.to_string(),
                landmarks: landmarks.to_string(),
                rank1: f.rank1,
                eer: f.eer.rate,
                genuine_mean: f.genuine_mean,
                impostor_mean: f.impostor_mean,
                failures: f.failures,
                ms_per_comparison: ms_comparison[j],
                ms_per_description: DESCRIPTION_OF[j].map_or(f64::NAN, |k| ms_description[k]),
                roc: f.roc,
                identified: f.identified,
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
    rep.table_csv(csv, &hdr, &rows)
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
    let series: Vec<Series> = all.iter().map(|m| m.series(m.roc.clone())).collect();
    let labels = (title, "false accept rate", "true accept rate");
    rep.plot(
        file,
        labels,
        &series,
        &format!("{title}; dashed: detected landmarks"),
    )
}
