//! `landmarks-eval` on meshes: detection on faces sampled from the ICT model against its
//! landmark vertices (errors, outcomes, the scores of correct detections, per-face rows).

use super::stats::{error_histogram, print_table, quantile, sorted, stats, text, Stats};
use super::{sample_faces, test_seed, training_seed, Args};
use crate::pipeline::bar;
use crate::report::{write_csv, write_json};
use anyhow::Result;
use facemodel::{FaceModel, LANDMARK_NAMES};
use landmarks::eval::{canonical_errors, pose_only_errors, weakest_agreement};
use landmarks::{detect_with, DetectOptions, GenericModel, LandmarkName, Landmarks};
use meshcore::{DVec3, TriMesh};
use rayon::prelude::*;
use std::path::Path;

/// What detection did on one test face.
struct Outcome {
    /// Per landmark the error (mm; infinite: not found).
    errors: Vec<f64>,
    /// CPU time of the detection (ms).
    cpu_ms: f64,
    /// The detector's error message.
    error: Option<String>,
    /// Confidence of the detection.
    confidence: f64,
    /// Symmetry of the detection.
    symmetry: f64,
    /// The weakest local template agreement of a landmark.
    local: f64,
    /// The 12 per-face CSV columns of a detection (empty when not found): pose-only errors,
    /// outer-eye distances, canonical error vectors.
    row: Vec<String>,
}

impl Outcome {
    /// Found, with every landmark within 10 mm.
    fn correct(&self) -> bool {
        self.error.is_none() && self.errors.iter().all(|&e| e <= 10.0)
    }
}

/// Detects the landmarks of `mesh` (truth `gt`) and measures the errors in mm (`unit_mm`: mm
/// per mesh unit).
fn detect_face(
    mesh: &TriMesh,
    gt: &[DVec3; 5],
    generic: &GenericModel,
    dopt: &DetectOptions,
    unit_mm: f64,
) -> Outcome {
    let c0 = thread_cpu_ns();
    let r = detect_with(mesh, generic, dopt);
    // CPU time of this thread (wall-clock time is meaningless on a loaded machine);
    // falls back to wall-clock time where /proc is unavailable.
    let cpu_ms = match (c0, thread_cpu_ns()) {
        (Some(a), Some(b)) => (b - a) as f64 * 1e-6,
        _ => f64::NAN,
    };
    match r {
        Ok(lm) => Outcome {
            errors: LandmarkName::ALL
                .iter()
                .map(|&n| (lm.get(n).position - gt[n as usize]).length() * unit_mm)
                .collect(),
            cpu_ms,
            error: None,
            confidence: lm.confidence,
            symmetry: lm.symmetry,
            local: weakest_agreement(lm.confidence, LandmarkName::ALL.map(|n| lm.get(n))),
            row: detection_row(&lm, gt, generic, unit_mm),
        },
        Err(e) => Outcome {
            errors: vec![f64::INFINITY; 5],
            cpu_ms,
            error: Some(e.to_string()),
            confidence: 0.0,
            symmetry: 0.0,
            local: 0.0,
            row: vec![String::new(); 12],
        },
    }
}

/// The per-face columns of a detection: errors of the landmarks predicted by the fitted pose
/// alone (before the local refinement), the true and detected outer-eye distances, and the
/// error vectors in the canonical frame of the model (x: right to left eye, y: up, z: out of
/// the face).
fn detection_row(
    lm: &Landmarks,
    gt: &[DVec3; 5],
    generic: &GenericModel,
    unit_mm: f64,
) -> Vec<String> {
    let pose_only = pose_only_errors(lm, gt, generic).map(|e| format!("{:.2}", e * unit_mm));
    let od = |p: [DVec3; 5]| format!("{:.2}", (p[3] - p[0]).length() * unit_mm);
    let xyz = canonical_errors(lm, gt).map(|v| {
        let dv = v * unit_mm;
        format!("{:.2} {:.2} {:.2}", dv.x, dv.y, dv.z)
    });
    pose_only
        .into_iter()
        .chain([od(*gt), od(lm.positions())])
        .chain(xyz)
        .collect()
}

/// The evaluation on meshes: detects the landmarks of the test faces (or the training faces
/// with `--on-training`), prints the statistics and writes `summary.json`, `per-face.csv` and
/// the error histogram into `out`.
pub(super) fn run_meshes(
    args: &Args,
    ict: &FaceModel,
    generic: &GenericModel,
    dopt: &DetectOptions,
    out: &Path,
) -> Result<()> {
    let unit_mm = if ict.units() == "cm" { 10.0 } else { 1.0 };
    let (mut test, mut labels) = if args.on_training {
        sample_faces(ict, args.train, training_seed(args.seed), true)?
    } else {
        sample_faces(ict, args.faces, test_seed(args.seed), !args.neutral)?
    };
    // Index of each evaluated face in its stream.
    let mut face_ids: Vec<usize> = (0..test.len()).collect();
    if let Some(i) = args.only {
        anyhow::ensure!(i < test.len(), "--only {i}: only {} test faces", test.len());
        test = vec![test.swap_remove(i)];
        labels = vec![labels.swap_remove(i)];
        face_ids = vec![i];
    }
    let pb = bar(test.len(), "detecting");
    let results: Vec<Outcome> = test
        .par_iter()
        .map(|(mesh, gt)| {
            let o = detect_face(mesh, gt, generic, dopt, unit_mm);
            pb.inc(1);
            o
        })
        .collect();
    pb.finish_and_clear();
    let mut per: Vec<Vec<f64>> = vec![Vec::new(); 5];
    for r in &results {
        for (p, &e) in per.iter_mut().zip(&r.errors) {
            p.push(e);
        }
    }
    let names: Vec<&str> = LandmarkName::ALL.iter().map(|n| n.key()).collect();
    let st: Vec<Stats> = names.iter().zip(&per).map(|(n, e)| stats(n, e)).collect();
    let summary = print_summary(args, generic, &results, &st);
    write_json(&out.join("summary.json"), &summary)?;
    write_per_face(&out.join("per-face.csv"), &results, &face_ids, &labels)?;
    error_histogram(
        &out.join("errors-histogram.svg"),
        "Landmark errors on sampled ICT faces",
        names
            .iter()
            .zip(per)
            .map(|(n, e)| (n.to_string(), e))
            .collect(),
    )?;
    println!("{}", out.display());
    Ok(())
}

/// Prints the statistics, the CPU times, the failures, the outcomes, the scores of the correct
/// detections and the worst faces; returns the summary written to `summary.json`.
fn print_summary(
    args: &Args,
    generic: &GenericModel,
    results: &[Outcome],
    st: &[Stats],
) -> serde_json::Value {
    let times = sorted(results.iter().map(|r| r.cpu_ms).collect());
    let failures: Vec<(usize, String)> = results
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.error.clone().map(|e| (i, e)))
        .collect();
    println!(
        "{} test faces ({}), generic model from {} training faces; errors in mm",
        results.len(),
        if args.neutral {
            "neutral"
        } else {
            "random expressions"
        },
        generic.n_training
    );
    print_table(st, false, None);
    let tmed = quantile(&times, 0.5);
    let tp95 = times[((times.len() - 1) as f64 * 0.95) as usize];
    println!("CPU time per face (thread CPU time, release): median {tmed:.1} ms, p95 {tp95:.1} ms");
    for (i, e) in failures.iter().take(20) {
        println!("face {i}: {e}");
    }
    println!("failures: {}", failures.len());
    // Outcome per face: correct (every landmark within 10 mm), rejected (NotFound) or silently
    // wrong (a detection with some landmark beyond 10 mm).
    let n = results.len() as f64;
    let correct = results.iter().filter(|r| r.correct()).count();
    let silent_wrong = results
        .iter()
        .filter(|r| r.error.is_none() && r.errors.iter().any(|&e| e > 10.0))
        .count();
    let not_found = failures.len();
    println!(
        "outcomes: correct {correct} ({:.1} %), not found {not_found} ({:.1} %), silent wrong (> 10 mm) {silent_wrong} ({:.1} %)",
        100.0 * correct as f64 / n,
        100.0 * not_found as f64 / n,
        100.0 * silent_wrong as f64 / n
    );
    print_scores_and_worst(results);
    serde_json::json!({
        "faces": results.len(),
        "training_faces": generic.n_training,
        "seed": args.seed,
        "expressions": !args.neutral,
        "units_of_errors": "mm",
        "landmark_vertices": LANDMARK_NAMES,
        "per_landmark": st,
        "cpu_time_ms_per_face": {"median": tmed, "p95": tp95},
        "outcomes": {"correct": correct, "not_found": not_found, "silent_wrong_over_10mm": silent_wrong},
        "failures": failures.iter().map(|(i, e)| serde_json::json!({"face": i, "error": e})).collect::<Vec<_>>(),
    })
}

/// Prints the low quantiles of the confidence, symmetry and local agreement of the correct
/// detections, and the faces with a landmark beyond 10 mm.
fn print_scores_and_worst(results: &[Outcome]) {
    for (what, get) in [
        (
            "confidence",
            (|r: &Outcome| r.confidence) as fn(&Outcome) -> f64,
        ),
        ("symmetry", |r| r.symmetry),
        ("local template agreement", |r| r.local),
    ] {
        let v = sorted(results.iter().filter(|r| r.correct()).map(get).collect());
        if !v.is_empty() {
            let [a, b, c, d] = [0.0, 0.01, 0.05, 0.5].map(|p| quantile(&v, p));
            println!(
                "{what} of correct detections: min {a:.3}, p1 {b:.3}, p5 {c:.3}, median {d:.3}"
            );
        }
    }
    let worst: Vec<(usize, f64, f64, f64, f64)> = results
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let largest = r.errors.iter().copied().fold(0.0, f64::max);
            (i, largest, r.confidence, r.symmetry, r.local)
        })
        .filter(|w| w.1 > 10.0 && w.1.is_finite())
        .collect();
    for (i, e, c, sy, lo) in worst.iter().take(20) {
        let each: Vec<String> = results[*i]
            .errors
            .iter()
            .map(|x| format!("{x:.1}"))
            .collect();
        println!(
            "face {i}: largest error {e:.1} mm (per landmark {}), confidence {c:.2}, symmetry {sy:.2}, local {lo:.2}",
            each.join(" ")
        );
    }
}

/// One row per face: errors, pose-only errors, canonical error vectors, expression.
fn write_per_face(
    path: &Path,
    results: &[Outcome],
    face_ids: &[usize],
    labels: &[String],
) -> Result<()> {
    let names: Vec<&str> = LandmarkName::ALL.iter().map(|n| n.key()).collect();
    let suffixed = |s: &'static str| names.iter().map(move |n| format!("{n}{s}"));
    let header: Vec<String> = std::iter::once("face".to_string())
        .chain(suffixed(""))
        .chain(suffixed("_pose_only"))
        .chain(["outer_eye_distance_true", "outer_eye_distance_detected"].map(String::from))
        .chain(suffixed("_xyz"))
        .chain(
            [
                "cpu_ms",
                "confidence",
                "symmetry",
                "local",
                "error",
                "expression",
            ]
            .map(String::from),
        )
        .collect();
    let rows: Vec<Vec<String>> = results
        .iter()
        .zip(face_ids.iter().zip(labels))
        .map(|(r, (id, label))| {
            let mut row = vec![id.to_string()];
            row.extend(r.errors.iter().map(|x| format!("{x:.2}")));
            row.extend(r.row.iter().cloned());
            row.push(format!("{:.1}", r.cpu_ms));
            row.extend([r.confidence, r.symmetry, r.local].map(|x| format!("{x:.3}")));
            row.extend([text(r.error.as_deref().unwrap_or("")), label.clone()]);
            row
        })
        .collect();
    write_csv(path, &header, &rows)
}

/// CPU time consumed by the calling thread so far (ns), from `/proc/thread-self/schedstat`.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}
