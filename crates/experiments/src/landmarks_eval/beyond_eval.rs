//! `landmarks-eval --beyond`: detection on the faces of [`super::beyond`] (outside the ICT
//! model's span) and on non-faces; per kind the faces not found, the weak detections and the
//! errors, and per non-face whether it was refused.

use super::beyond::{make, mm_per, non_faces, BeyondFace, Kind};
use super::stats::{quantile, scored_stats, sorted, text};
use crate::pipeline::bar;
use crate::report::{write_csv, write_json};
use anyhow::{Context, Result};
use facemodel::FaceModel;
use landmarks::eval::{landmark_coverage, score, weakest_agreement, Scored};
use landmarks::{detect_visible, DetectOptions, GenericModel, LandmarkName, VisibleLandmarks};
use rayon::prelude::*;
use std::path::Path;

/// What detection did on one face.
struct Outcome {
    kind: Kind,
    name: String,
    label: String,
    /// The detection scored against the truth.
    scored: Scored,
    /// The detection, or the error message.
    found: Result<Found, String>,
    /// A face refused: its detection without the coverage guard, if that finds it, and that
    /// detection's largest landmark error (infinite: a landmark not placed).
    unguarded: Option<(Found, f64)>,
    vertices: usize,
    detect_ms: f64,
}

/// The numbers of a detection.
struct Found {
    confidence: f64,
    symmetry: f64,
    /// The weakest local template agreement of a placed landmark.
    weakest: f64,
    /// Why the evidence is weak (empty: strong).
    weak: Vec<String>,
    /// Per landmark, the share of its template that finds the surface (`None`: not placed).
    coverage: [Option<f64>; 5],
}

/// Detection options for a face of `mesh`: the caller's with the mesh's units and viewpoint.
fn options_for(
    mesh: &meshcore::TriMesh,
    generic: &GenericModel,
    dopt: &DetectOptions,
    toward_viewer: Option<meshcore::DVec3>,
) -> Result<DetectOptions, landmarks::LandmarkError> {
    Ok(DetectOptions {
        mesh_units_per_model_unit: landmarks::mesh_units_per_model_unit(mesh, generic)?,
        toward_viewer,
        ..*dopt
    })
}

/// The numbers of a detection `v` of `mesh` under options `o`.
fn found(
    v: &VisibleLandmarks,
    o: &DetectOptions,
    mesh: &meshcore::TriMesh,
    generic: &GenericModel,
) -> Found {
    Found {
        confidence: v.confidence,
        symmetry: v.symmetry,
        weakest: weakest_agreement(v.confidence, v.landmarks.iter().flatten()),
        weak: v.weak_evidence(o).iter().map(|w| w.to_string()).collect(),
        coverage: landmark_coverage(mesh, generic, v, o).unwrap_or([None; 5]),
    }
}

/// `o` without the graded pass's coverage guard (`DetectOptions::graded_coverage` 0): a face
/// or non-face refused with it is detected again so that the guard's effect is measured.
fn without_coverage_guard(o: &DetectOptions) -> DetectOptions {
    DetectOptions {
        graded_coverage: 0.0,
        ..*o
    }
}

/// Detects the landmarks of one generated face.
fn detect_one(f: BeyondFace, kind: Kind, generic: &GenericModel, dopt: &DetectOptions) -> Outcome {
    let t0 = std::time::Instant::now();
    let r = options_for(&f.mesh, generic, dopt, f.toward_viewer)
        .and_then(|o| detect_visible(&f.mesh, generic, &o).map(|v| (v, o)));
    let detect_ms = t0.elapsed().as_secs_f64() * 1e3;
    let scored = score(&f.truth, r.as_ref().map(|(v, _)| v));
    // Refused: what the detection would be without the coverage guard (its coverages).
    let unguarded = r.as_ref().err().and_then(|_| {
        let o = without_coverage_guard(&options_for(&f.mesh, generic, dopt, f.toward_viewer).ok()?);
        let v = detect_visible(&f.mesh, generic, &o).ok()?;
        let errors = score(&f.truth, Ok::<_, ()>(&v)).errors;
        let worst = errors.iter().flatten().fold(0.0, |w: f64, &e| w.max(e));
        Some((found(&v, &o, &f.mesh, generic), worst))
    });
    Outcome {
        kind,
        name: f.name,
        label: f.label,
        scored,
        found: r
            .map(|(v, o)| found(&v, &o, &f.mesh, generic))
            .map_err(|e| e.to_string()),
        unguarded,
        vertices: f.mesh.n_vertices(),
        detect_ms,
    }
}

/// Median and 95th percentile of `v` (NaN when empty).
fn median_p95(v: Vec<f64>) -> (f64, f64) {
    let v = sorted(v);
    (quantile(&v, 0.5), quantile(&v, 0.95))
}

/// Prints one row of the table of kinds (13 cells).
fn print_row(c: [&str; 13]) {
    println!(
        "{:<18} {:>4} {:>5} {:>5} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>4} {:>12} {:>7}",
        c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9], c[10], c[11], c[12]
    );
}

/// Prints and returns the table row of one kind.
fn kind_summary(kind: Kind, rows: &[&Outcome]) -> serde_json::Value {
    let n = rows.len();
    let not_found: Vec<&&Outcome> = rows.iter().filter(|o| o.found.is_err()).collect();
    let weak = rows
        .iter()
        .filter(|o| o.found.as_ref().is_ok_and(|f| !f.weak.is_empty()))
        .count();
    let scored: Vec<&Scored> = rows.iter().map(|o| &o.scored).collect();
    let per = scored_stats(&scored);
    let outer = scored.iter().flat_map(|o| [&o.errors[0], &o.errors[3]]);
    let (om, op) = median_p95(outer.filter_map(|e| e.as_ref().ok().copied()).collect());
    let silent = rows
        .iter()
        .filter(|o| o.found.is_ok())
        .flat_map(|o| o.scored.errors.iter())
        .filter(|e| matches!(e, Ok(x) if x.is_finite() && *x > 10.0))
        .count();
    // The outer eye corners reported unseen whose truth is on the surface.
    let pred: Vec<f64> = scored
        .iter()
        .flat_map(|o| o.predicted_unseen.iter())
        .filter(|p| {
            p.truth_on_surface
                && matches!(
                    p.name,
                    LandmarkName::OuterEyeRight | LandmarkName::OuterEyeLeft
                )
        })
        .map(|p| p.distance)
        .collect();
    let (pm, pp) = median_p95(pred.clone());
    let (tm, _) = median_p95(rows.iter().map(|o| o.detect_ms).collect());
    let f2 = |x: f64| format!("{x:.2}");
    print_row([
        kind.name(),
        &n.to_string(),
        &not_found.len().to_string(),
        &weak.to_string(),
        &f2(om),
        &f2(op),
        &f2(per[4].median_mm),
        &f2(per[1].median_mm.max(per[2].median_mm)),
        &f2(per[0].max_mm.max(per[3].max_mm)),
        &silent.to_string(),
        &pred.len().to_string(),
        &format!("{pm:.2}/{pp:.2}"),
        &format!("{tm:.0}"),
    ]);
    for o in not_found.iter().take(6) {
        println!(
            "    {}: {}",
            o.name,
            o.found.as_ref().err().map_or("", |e| e)
        );
    }
    serde_json::json!({
        "kind": kind.name(), "faces": n, "not_found": not_found.len(), "weak": weak,
        "outer_corners_median_mm": om, "outer_corners_p95_mm": op, "per_landmark": per,
        "landmarks_over_10mm_placed": silent,
        "unseen_outer_corners_predicted": {"n": pred.len(), "median_mm": pm, "p95_mm": pp},
        "median_detect_ms": tm,
    })
}

/// `--beyond`: `args.beyond_faces` faces of every kind (stream of `args.seed`) and the
/// non-faces.
pub(super) fn run_beyond(
    args: &super::Args,
    ict: &FaceModel,
    generic: &GenericModel,
    dopt: &DetectOptions,
    out: &Path,
) -> Result<()> {
    let t0 = std::time::Instant::now();
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let kinds: Vec<Kind> = match &args.beyond_kind {
        Some(k) => vec![*Kind::ALL.iter().find(|x| x.name() == k).with_context(|| {
            format!("--beyond-kind {k}: none of strong-expression, warp, remesh, depth-camera")
        })?],
        None => Kind::ALL.to_vec(),
    };
    let jobs: Vec<(Kind, usize)> = kinds
        .iter()
        .flat_map(|&k| (0..args.beyond_faces).map(move |i| (k, i)))
        .filter(|(_, i)| args.only.is_none_or(|o| o == *i))
        .collect();
    let pb = bar(jobs.len(), "making and detecting");
    let outcomes: Vec<Outcome> = jobs
        .par_iter()
        .map(|&(k, i)| {
            let r = make(ict, k, i, args.seed)
                .map(|f| detect_one(f, k, generic, dopt))
                .with_context(|| format!("{} face {i}", k.name()));
            pb.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    println!(
        "faces beyond the ICT model (seed {}, {} per kind); errors in mm; a landmark not placed counts as infinite",
        args.seed, args.beyond_faces
    );
    print_row([
        "kind",
        "n",
        "n.f.",
        "weak",
        "outer",
        "outer",
        "nose",
        "inner",
        "outer",
        ">10mm",
        "uns.",
        "predicted",
        "detect",
    ]);
    print_row([
        "",
        "",
        "",
        "",
        "median",
        "p95",
        "median",
        "median",
        "max",
        "placed",
        "out.",
        "median/p95",
        "ms",
    ]);
    let mut kinds_json = Vec::new();
    for &k in &kinds {
        let rows: Vec<&Outcome> = outcomes.iter().filter(|o| o.kind == k).collect();
        kinds_json.push(kind_summary(k, &rows));
    }
    let refused = run_non_faces(ict, generic, dopt, args.seed)?;
    write_per_face(&outcomes, &out.join("per-face.csv"))?;
    let summary = serde_json::json!({
        "seed": args.seed, "faces_per_kind": args.beyond_faces, "kinds": kinds_json,
        "non_faces": refused, "seconds": t0.elapsed().as_secs_f64(),
    });
    write_json(&out.join("summary.json"), &summary)?;
    println!("wall time {:.1} s", t0.elapsed().as_secs_f64());
    println!("{}", out.display());
    Ok(())
}

/// Detection on the non-faces: each must be refused.
fn run_non_faces(
    ict: &FaceModel,
    generic: &GenericModel,
    dopt: &DetectOptions,
    seed: u64,
) -> Result<Vec<serde_json::Value>> {
    let mut out = Vec::new();
    for (name, mesh) in non_faces(ict, seed)? {
        // In mm, given: what is tested is the face check, not the units check.
        let o = DetectOptions {
            mesh_units_per_model_unit: mm_per(&generic.units, "the generic model")?,
            ..*dopt
        };
        let r = detect_visible(&mesh, generic, &o);
        let unguarded = detect_visible(&mesh, generic, &without_coverage_guard(&o)).is_ok();
        let what = match &r {
            Ok(v) => format!(
                "LET THROUGH (confidence {}, symmetry {})",
                v.confidence, v.symmetry
            ),
            Err(e) => format!(
                "refused: {e}; without the coverage guard {}",
                if unguarded { "LET THROUGH" } else { "refused" }
            ),
        };
        println!("non-face {name}: {what}");
        out.push(serde_json::json!({"non_face": name, "refused": r.is_err(), "refused_without_coverage_guard": !unguarded, "outcome": what}));
    }
    Ok(out)
}

/// The per-face CSV's coverage columns, in [`LandmarkName::ALL`] order.
const COVERAGE_COLUMNS: [&str; 5] = [
    "coverage_outer_eye_right",
    "coverage_inner_eye_right",
    "coverage_inner_eye_left",
    "coverage_outer_eye_left",
    "coverage_nose_tip",
];

/// One row per face: errors, the detection's numbers (unrounded), the share of each placed
/// landmark's template that finds the surface (for a refused face, of its detection without
/// the coverage guard when that finds it, with that detection's largest landmark error), time
/// and error.
fn write_per_face(outcomes: &[Outcome], path: &Path) -> Result<()> {
    let header: Vec<&str> = ["face", "kind"]
        .into_iter()
        .chain(LandmarkName::ALL.iter().map(|n| n.key()))
        .chain([
            "confidence",
            "symmetry",
            "weakest_agreement",
            "weak",
            "vertices",
        ])
        .chain(COVERAGE_COLUMNS)
        .chain(["coverage_from", "without_coverage_guard_max_error"])
        .chain(["detect_ms", "error", "label"])
        .collect();
    let rows: Vec<Vec<String>> = outcomes
        .iter()
        .map(|o| {
            let e = o.scored.errors.iter().map(|e| match e {
                Ok(x) => format!("{x:.3}"),
                Err(w) => text(&format!("truth not on the surface: {w}")),
            });
            let (found, error) = match &o.found {
                Ok(f) => {
                    let numbers = [f.confidence, f.symmetry, f.weakest].map(|x| x.to_string());
                    let weak = text(&f.weak.join("; "));
                    (numbers.into_iter().chain([weak]).collect(), String::new())
                }
                Err(e) => (vec![String::new(); 4], text(e)),
            };
            let mut row: Vec<String> = vec![o.name.clone(), o.kind.name().into()];
            row.extend(e.chain(found));
            row.push(o.vertices.to_string());
            // The coverages unrounded: of the detection, or of a refused face's detection
            // without the coverage guard.
            let (coverage, from, worst) = match (&o.found, &o.unguarded) {
                (Ok(f), _) => (Some(f.coverage), "detection", None),
                (Err(_), Some((u, w))) => {
                    (Some(u.coverage), "without the coverage guard", Some(*w))
                }
                (Err(_), None) => (None, "", None),
            };
            let cell = |c: Option<f64>| c.map_or_else(String::new, |c| c.to_string());
            row.extend(coverage.unwrap_or([None; 5]).map(cell));
            row.extend([from.to_string(), cell(worst), format!("{:.0}", o.detect_ms)]);
            row.extend([error, text(&o.label)]);
            row
        })
        .collect();
    write_csv(path, &header, &rows)
}
