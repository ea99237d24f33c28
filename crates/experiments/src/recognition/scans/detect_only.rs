//! `--detect-only`: the landmark detection on the run's scans, without describing or comparing.

use super::super::metrics::median;
use super::p95;
use crate::report::{par_map, Report, Series};
use crate::scans::{detection_errors, scan_raw, FaceSpec};
use anyhow::Result;
use facemodel::FaceModel;
use landmarks::GenericModel;

/// One scan: its outcome, each landmark's error (`None`: not placed) and the reasons.
struct Outcome {
    status: &'static str,
    err: [Option<f64>; 3],
    confidence: Option<f64>,
    why: String,
}

/// `--detect-only`: scans, cleans and detects every face, writes `detection.csv` (per scan its
/// yaw, noise, each detected landmark's distance from its ground truth or why it is unseen, and
/// the detector's error when it found nothing) and a report with the errors and the share of
/// landmarks placed against the yaw (table and figures), and prints the count and every
/// failure.
pub(super) fn detect_only(
    model: &FaceModel,
    generic: &GenericModel,
    specs: &[&FaceSpec],
    prep: &facematch::MatchOptions,
    out: &std::path::Path,
) -> Result<()> {
    let outcomes = detect_all(model, generic, specs, prep);
    let found = outcomes.iter().filter(|o| o.status == "found").count();
    let rows = detection_rows(specs, &outcomes);
    let mut rep = Report::new(out, "Landmark detection on the recognition's scans")?;
    rep.para(&format!(
        "`--detect-only`: landmarks found on {found} of {} scans (gallery, probes and sweeps of the run; `facematch::prepare`: cleaned, `landmarks::detect_visible` seen from the scanner, cropped around the detected nose tip, detected again). Errors are distances from the ground truth carried through the scanner (mm); a landmark not placed (not found, or unseen) has none.",
        outcomes.len()
    ));
    rep.csv(
        "detection.csv",
        &[
            "scan",
            "yaw (degrees)",
            "noise (mm)",
            "detection",
            "outer eye right (mm)",
            "outer eye left (mm)",
            "nose tip (mm)",
            "confidence",
            "why not found or unseen; what prepare substituted",
        ],
        &rows,
    )?;
    yaw_section(&mut rep, specs, &outcomes)?;
    let failures: Vec<String> = rows
        .iter()
        .filter(|r| r[3] != "found" || !r[8].is_empty())
        .map(|r| format!("{}: {}: {}", r[0], r[3], r[8]))
        .collect();
    if !failures.is_empty() {
        rep.heading(2, "Not found or not placed");
        rep.list(&failures);
    }
    rep.png_twins()?;
    let path = rep.finish()?;
    eprintln!("landmarks found on {found} of {} scans", rows.len());
    for f in &failures {
        eprintln!("  {f}");
    }
    println!("{}", path.display());
    Ok(())
}

/// Scans and prepares every face (in parallel, in order): what was detected, each reference
/// landmark's error and why one is unseen.
fn detect_all(
    model: &FaceModel,
    generic: &GenericModel,
    specs: &[&FaceSpec],
    prep: &facematch::MatchOptions,
) -> Vec<Outcome> {
    par_map(
        specs,
        "scan, prepare (clean, detect, crop, detect)",
        |spec| {
            let r = scan_raw(model, spec).map(|(raw, _)| {
                let p =
                    facematch::prepare_with(facematch::ScanInput::Grid(&raw.grid), generic, prep);
                (raw, p)
            });
            let failed = |status, why| Outcome {
                status,
                err: [None; 3],
                confidence: None,
                why,
            };
            match r {
                Err(e) => failed("scan failed", format!("{e:#}")),
                Ok((_, Err(e))) => failed("not found", e.to_string()),
                Ok((raw, Ok(p))) => {
                    let errs = detection_errors(&raw.landmarks, &p.detected);
                    let why: Vec<String> = (errs.iter().filter_map(|e| e.clone().err()))
                        .chain(p.notes.iter().cloned())
                        .collect();
                    Outcome {
                        status: "found",
                        err: errs.map(Result::ok),
                        confidence: Some(p.detected.confidence),
                        why: why.join("; "),
                    }
                }
            }
        },
    )
}

/// The lines of `detection.csv`, one per scan.
fn detection_rows(specs: &[&FaceSpec], outcomes: &[Outcome]) -> Vec<Vec<String>> {
    specs
        .iter()
        .zip(outcomes)
        .map(|(spec, o)| {
            let mut row = vec![
                spec.name.clone(),
                format!("{}", spec.settings.yaw_deg),
                format!("{}", spec.settings.noise_mm),
                o.status.to_string(),
            ];
            row.extend(o.err.iter().map(|e| match (e, o.status) {
                (Some(e), _) => format!("{e:.2}"),
                (None, "found") => "unseen".into(),
                (None, _) => String::new(),
            }));
            row.push(o.confidence.map_or(String::new(), |c| format!("{c:.3}")));
            row.push(o.why.clone());
            row
        })
        .collect()
}

/// The errors and the share of landmarks placed against the yaw: a table and two figures.
fn yaw_section(rep: &mut Report, specs: &[&FaceSpec], outcomes: &[Outcome]) -> Result<()> {
    // Against the yaw, in 10-degree bins (centres -40 ... 40; 45 degrees counts as 40).
    let bin = |yaw: f64| ((yaw / 10.0).round() as i64).clamp(-4, 4) * 10;
    let bins: std::collections::BTreeMap<i64, Vec<&Outcome>> =
        specs
            .iter()
            .zip(outcomes)
            .fold(Default::default(), |mut m, (spec, o)| {
                m.entry(bin(spec.settings.yaw_deg)).or_default().push(o);
                m
            });
    let mut table = Vec::new();
    let mut med_series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 3];
    let mut placed_series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 3];
    for (&b, os) in &bins {
        let mut row = vec![format!("{b}"), os.len().to_string()];
        for k in 0..3 {
            let errs: Vec<f64> = os.iter().filter_map(|o| o.err[k]).collect();
            let placed = errs.len() as f64 / os.len() as f64;
            let med = median(errs.clone());
            row.push(format!("{:.0} %", 100.0 * placed));
            row.push(if errs.is_empty() {
                "-".into()
            } else {
                format!("{med:.2} / {:.2}", p95(errs.clone()))
            });
            placed_series[k].push((b as f64, 100.0 * placed));
            if !errs.is_empty() {
                med_series[k].push((b as f64, med));
            }
        }
        table.push(row);
    }
    rep.table(
        &[
            "yaw bin (degrees)",
            "scans",
            "right outer corner placed",
            "its error median / p95 (mm)",
            "left outer corner placed",
            "its error median / p95 (mm)",
            "nose tip placed",
            "its error median / p95 (mm)",
        ],
        &table,
    );
    let names = ["right outer corner", "left outer corner", "nose tip"];
    let figures = [
        (
            "detection-error-yaw.svg",
            "Detection error against yaw (median over the landmarks placed)",
            "median error (mm)",
            med_series,
            "Median detection error per yaw bin",
        ),
        (
            "detection-placed-yaw.svg",
            "Landmarks placed against yaw",
            "placed (% of the bin's scans)",
            placed_series,
            "Share of scans on which each landmark was placed (not found or unseen: not placed)",
        ),
    ];
    for (file, title, y_label, per_landmark, caption) in figures {
        let series: Vec<Series> = per_landmark
            .into_iter()
            .zip(names)
            .map(|(pts, n)| Series::new(n, pts))
            .collect();
        let x_label = "yaw (degrees, 10-degree bins)";
        rep.plot(file, (title, x_label, y_label), &series, caption)?;
    }
    Ok(())
}
