//! `landmarks-eval --scans`: detection on range scans of sampled ICT faces against the ground
//! truth the scanner projected.

use super::stats::{print_table, quantile, scored_histogram, scored_stats, sorted, text, Stats};

use super::{test_seed, Args};
use crate::pipeline::bar;
use crate::report::{write_csv, write_json};
use crate::scans::{sample_weights, scan_faces, scan_seed, FaceSpec, ScanSetOptions, ScanSettings};
use anyhow::{Context, Result};
use facemodel::FaceModel;
use landmarks::eval::{score, Scored};
use landmarks::{DetectOptions, GenericModel, LandmarkName};
use meshcore::DVec3;
use std::path::Path;
use std::time::Instant;

/// Outcome of one scanned test face: the detection scored against the truth the scanner
/// projected (only the outer eye corners' predictions are kept), the detector's error message,
/// the scan's size and the detection time.
struct ScanOutcome {
    name: String,
    scored: Scored,
    not_found: Option<String>,
    valid_samples: usize,
    vertices: usize,
    detect_ms: f64,
}

/// `--scans`: detection on range scans of the test faces against the ground truth the scanner
/// projected.
pub(super) fn run_scans(
    args: &Args,
    ict: &FaceModel,
    generic: &GenericModel,
    dopt: &DetectOptions,
    out: &Path,
) -> Result<()> {
    let t0 = Instant::now();
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let settings = args.scan.settings();
    let specs = scan_specs(args, ict, settings)?;
    let (outcomes, scan_failures) = scan_and_detect(args, ict, generic, dopt, &specs);
    anyhow::ensure!(
        !outcomes.is_empty(),
        "no scan could be made: {}",
        scan_failures.join("; ")
    );
    let s = Summary::of(&outcomes);
    print_summary(args, settings, generic, &s, &scan_failures);
    let targets = s.targets();
    for (what, ok) in &targets {
        println!("target {what}: {}", if *ok { "met" } else { "NOT met" });
    }
    let secs = t0.elapsed().as_secs_f64();
    println!("wall time {secs:.1} s");
    let summary = serde_json::json!({
        "faces": s.n,
        "seed": args.seed,
        "expressions": !args.neutral,
        "scan": settings.label(),
        "crop_radius_mm": args.scan.crop_radius,
        "units_of_errors": "mm",
        "median_valid_samples": s.med_valid,
        "median_vertices_after_cleaning": s.med_vertices,
        "median_detect_ms": s.med_detect,
        "per_landmark": s.st,
        "not_found": s.not_found.iter().map(|(f, e)| serde_json::json!({"face": f, "error": e})).collect::<Vec<_>>(),
        "not_found_rate": s.nf_rate,
        "silent_wrong": s.silent.iter().map(|(f, w)| serde_json::json!({"face": f, "what": w})).collect::<Vec<_>>(),
        "truth_not_on_cleaned_scan": s.unseen,
        "reported_unseen": {"truth_not_on_scan": s.unseen_right, "truth_on_scan": s.unseen_missed},
        "unseen_outer_corners_predicted_mm": s.predicted_quantiles().map(|[m, p, x]| serde_json::json!({"n": s.predicted.len(), "median": m, "p95": p, "max": x})),
        "scan_failures": scan_failures,
        "targets": targets.iter().map(|(w, ok)| serde_json::json!({"target": w, "met": ok})).collect::<Vec<_>>(),
        "seconds": secs,
    });
    write_json(&out.join("summary.json"), &summary)?;
    write_per_face(&out.join("per-face.csv"), &outcomes)?;
    let scored: Vec<&Scored> = outcomes.iter().map(|o| &o.scored).collect();
    scored_histogram(
        &out.join("errors-histogram.svg"),
        &format!("Landmark errors on range scans ({})", settings.label()),
        &scored,
    )?;
    println!("{}", out.display());
    Ok(())
}

/// The test faces to scan (the test stream of `--seed`; only `--only` if given).
fn scan_specs(args: &Args, ict: &FaceModel, settings: ScanSettings) -> Result<Vec<FaceSpec>> {
    let seed = test_seed(args.seed);
    let weights = sample_weights(ict, args.faces, 2, seed);
    let mut specs: Vec<FaceSpec> = weights
        .into_iter()
        .enumerate()
        .map(|(i, (w, ex))| FaceSpec {
            name: format!("face{i:03}"),
            identity: i,
            identity_weights: w,
            expression_weights: if args.neutral {
                Vec::new()
            } else {
                ex[1].clone()
            },
            settings,
            seed: scan_seed(seed, i as u64),
        })
        .collect();
    if let Some(i) = args.only {
        anyhow::ensure!(
            i < specs.len(),
            "--only {i}: only {} test faces",
            specs.len()
        );
        specs = vec![specs.swap_remove(i)];
    }
    Ok(specs)
}

/// Scans, cleans (cropped around the nose tip) and detects every spec; returns the outcomes
/// and the scans that failed.
fn scan_and_detect(
    args: &Args,
    ict: &FaceModel,
    generic: &GenericModel,
    dopt: &DetectOptions,
    specs: &[FaceSpec],
) -> (Vec<ScanOutcome>, Vec<String>) {
    let pb = bar(specs.len(), "scanning and detecting");
    let opts = ScanSetOptions {
        clean: scanprep::CleanOptions {
            crop: Some(scanprep::Crop {
                centre: DVec3::ZERO,
                radius_mm: args.scan.crop_radius,
            }),
            ..scanprep::CleanOptions::default()
        },
        detect: Some(*dopt),
        ..ScanSetOptions::default()
    };
    let faces = scan_faces(ict, generic, specs, &opts, &pb);
    pb.finish_and_clear();
    let mut scan_failures = Vec::new();
    let mut outcomes = Vec::new();
    for (spec, f) in specs.iter().zip(faces) {
        let f = match f {
            Ok(f) => f,
            Err(e) => {
                scan_failures.push(e);
                continue;
            }
        };
        let truth = f.truth.each_ref().map(|t| {
            let why = t.vertex.as_ref().err().cloned();
            (t.position, why)
        });
        let mut scored = score(&truth, f.detected.as_ref());
        let outer = [LandmarkName::OuterEyeRight, LandmarkName::OuterEyeLeft];
        scored.predicted_unseen.retain(|p| outer.contains(&p.name));
        outcomes.push(ScanOutcome {
            name: spec.name.clone(),
            scored,
            not_found: f.detected.as_ref().err().cloned(),
            valid_samples: f.valid_samples,
            vertices: f.mesh.n_vertices(),
            detect_ms: f.times.detect.as_secs_f64() * 1e3,
        });
    }
    (outcomes, scan_failures)
}

/// The figures of the scanned faces.
struct Summary<'a> {
    /// Faces scanned.
    n: usize,
    /// Per landmark, the errors where the truth is on the cleaned scan (inf: not found).
    st: Vec<Stats>,
    /// Silent wrong landmarks (face, what): reported more than 10 mm off, or reported where the
    /// truth is not on the cleaned scan.
    silent: Vec<(String, String)>,
    /// Faces not found, with the detector's message.
    not_found: Vec<(&'a str, &'a str)>,
    /// Share of the faces not found.
    nf_rate: f64,
    /// Landmarks of found faces reported unseen whose truth is not on the cleaned scan.
    unseen_right: usize,
    /// Landmarks of found faces reported unseen whose truth is on it.
    unseen_missed: usize,
    /// Ground-truth landmarks not on the cleaned scan.
    unseen: usize,
    /// Median valid samples per scan.
    med_valid: f64,
    /// Median vertices after cleaning.
    med_vertices: f64,
    /// Median detection wall time (ms).
    med_detect: f64,
    /// Distances of the predictions of the outer eye corners reported unseen from the truth
    /// (mm), sorted.
    predicted: Vec<f64>,
}

impl<'a> Summary<'a> {
    /// Median, 95th percentile and maximum of [`Summary::predicted`] (`None`: no unseen outer
    /// eye corner).
    fn predicted_quantiles(&self) -> Option<[f64; 3]> {
        let v = &self.predicted;
        (!v.is_empty()).then(|| [0.5, 0.95, 1.0].map(|p| quantile(v, p)))
    }

    fn of(outcomes: &'a [ScanOutcome]) -> Self {
        let scored: Vec<&Scored> = outcomes.iter().map(|o| &o.scored).collect();
        // Silent wrong landmarks: reported more than 10 mm off, or reported where the truth is
        // not on the cleaned scan (occluded, outside the grid or the crop).
        let silent: Vec<(String, String)> = outcomes
            .iter()
            .filter(|o| o.not_found.is_none())
            .flat_map(|o| {
                let s = &o.scored;
                LandmarkName::ALL
                    .iter()
                    .filter(|&&n| s.unseen[n as usize].is_none())
                    .filter_map(|&n| match &s.errors[n as usize] {
                        Ok(e) if *e > 10.0 => Some((o.name.clone(), format!("{n} {e:.1} mm off"))),
                        Err(why) => Some((o.name.clone(), format!("{n} reported but {why}"))),
                        _ => None,
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        let not_found: Vec<(&str, &str)> = outcomes
            .iter()
            .filter_map(|o| o.not_found.as_deref().map(|e| (o.name.as_str(), e)))
            .collect();
        let n = outcomes.len();
        // Landmarks of found faces reported unseen: where the truth is not on the cleaned scan
        // (right) and where it is (a landmark not found).
        let count = |f: &dyn Fn(&Scored, usize) -> bool| -> usize {
            scored
                .iter()
                .map(|o| (0..5).filter(|&k| f(o, k)).count())
                .sum()
        };
        let reported = |on: bool| count(&|o, k| o.unseen[k].is_some() && o.errors[k].is_ok() == on);
        let med =
            |f: fn(&ScanOutcome) -> f64| quantile(&sorted(outcomes.iter().map(f).collect()), 0.5);
        let predicted = scored
            .iter()
            .flat_map(|o| o.predicted_unseen.iter().map(|p| p.distance));
        Summary {
            n,
            st: scored_stats(&scored),
            silent,
            nf_rate: not_found.len() as f64 / n as f64,
            not_found,
            unseen_right: reported(false),
            unseen_missed: reported(true),
            unseen: count(&|o, k| o.errors[k].is_err()),
            med_valid: med(|o| o.valid_samples as f64),
            med_vertices: med(|o| o.vertices as f64),
            med_detect: med(|o| o.detect_ms),
            predicted: sorted(predicted.collect()),
        }
    }

    /// Silent wrong landmarks of `n`.
    fn silent_of(&self, n: LandmarkName) -> usize {
        self.silent
            .iter()
            .filter(|(_, w)| w.starts_with(n.key()))
            .count()
    }

    /// The accuracy targets and whether each is met.
    fn targets(&self) -> [(&'static str, bool); 5] {
        let by = |n: LandmarkName| &self.st[n as usize];
        let corners = [
            by(LandmarkName::OuterEyeRight),
            by(LandmarkName::OuterEyeLeft),
        ];
        [
            (
                "outer eye corners median < 2 mm",
                corners.iter().all(|s| s.median_mm < 2.0),
            ),
            (
                "outer eye corners p95 < 4 mm",
                corners.iter().all(|s| s.p95_mm < 4.0),
            ),
            (
                "nose tip median < 2 mm",
                by(LandmarkName::NoseTip).median_mm < 2.0,
            ),
            ("not found < 2 %", self.nf_rate < 0.02),
            (
                "no outer corner or nose tip > 10 mm off unreported",
                [
                    LandmarkName::OuterEyeRight,
                    LandmarkName::OuterEyeLeft,
                    LandmarkName::NoseTip,
                ]
                .iter()
                .all(|&n| self.silent_of(n) == 0),
            ),
        ]
    }
}

/// Prints the set-up, the per-landmark table, the faces not found, the unseen landmarks, the
/// silent wrong landmarks and the scans that failed.
fn print_summary(
    args: &Args,
    settings: ScanSettings,
    generic: &GenericModel,
    s: &Summary<'_>,
    scan_failures: &[String],
) {
    let n = s.n;
    println!(
        "{n} scanned test faces ({}; {}), generic model from {} training faces; errors in mm",
        if args.neutral {
            "neutral"
        } else {
            "random expressions"
        },
        settings.label(),
        generic.n_training
    );
    println!(
        "median {:.0} valid samples, {:.0} vertices after cleaning; detection wall time median {:.0} ms",
        s.med_valid, s.med_vertices, s.med_detect
    );
    let silent = LandmarkName::ALL.map(|n| s.silent_of(n));
    print_table(&s.st, true, Some((">10 silent", &silent)));
    println!(
        "not found: {} of {n} faces ({:.1} %); ground-truth landmarks not on the cleaned scan: {}; scans that failed: {}",
        s.not_found.len(),
        100.0 * s.nf_rate,
        s.unseen,
        scan_failures.len()
    );
    for (name, e) in s.not_found.iter().take(20) {
        println!("  {name}: {e}");
    }
    println!(
        "landmarks of found faces reported unseen: {} whose truth is not on the cleaned scan, {} whose truth is (counted as not found above)",
        s.unseen_right, s.unseen_missed
    );
    if let Some(q) = s.predicted_quantiles() {
        println!(
            "unseen outer eye corners: {}, predicted {:.2} mm from the truth (median), {:.2} mm (p95), {:.2} mm (max)",
            s.predicted.len(),
            q[0],
            q[1],
            q[2]
        );
    }
    println!("silent wrong landmarks: {}", s.silent.len());
    for (name, w) in s.silent.iter().take(20) {
        println!("  {name}: {w}");
    }
    for e in scan_failures.iter().take(20) {
        println!("  scan failed: {e}");
    }
}

/// One row per scanned face: the errors (or why the truth is not on the scan, and why a
/// landmark was reported unseen), the scan's size, the detection time and its error.
fn write_per_face(path: &Path, outcomes: &[ScanOutcome]) -> Result<()> {
    let names = LandmarkName::ALL.iter().map(|n| n.key());
    let header: Vec<&str> = std::iter::once("face")
        .chain(names)
        .chain(["valid_samples", "vertices", "detect_ms", "error"])
        .collect();
    let rows: Vec<Vec<String>> = outcomes
        .iter()
        .map(|o| {
            let s = &o.scored;
            let e = s.errors.iter().zip(&s.unseen).map(|(e, u)| {
                let reported = u
                    .as_ref()
                    .map(|u| format!(" (reported unseen: {u})"))
                    .unwrap_or_default();
                text(&match e {
                    Ok(x) => format!("{x:.2}{reported}"),
                    Err(why) => format!("unseen: {why}{reported}"),
                })
            });
            std::iter::once(o.name.clone())
                .chain(e)
                .chain([o.valid_samples.to_string(), o.vertices.to_string()])
                .chain([format!("{:.0}", o.detect_ms)])
                .chain([text(o.not_found.as_deref().unwrap_or(""))])
                .collect()
        })
        .collect();
    write_csv(path, &header, &rows)
}
