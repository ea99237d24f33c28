//! `landmarks-eval --beyond`: detection on the faces of [`super::beyond`] (outside the ICT
//! model's span) and on non-faces; per kind the faces not found, the weak detections and the
//! errors, and per non-face whether it was refused.

use super::beyond::{make, non_faces, BeyondFace, Kind};
use super::stats::{stats, Stats};
use crate::pipeline::bar;
use crate::report::write_json;
use anyhow::{Context, Result};
use facemodel::FaceModel;
use landmarks::{detect_visible, DetectOptions, GenericModel, LandmarkName, VisibleLandmarks};
use rayon::prelude::*;
use std::path::Path;

/// What detection did on one face.
struct Outcome {
    kind: Kind,
    name: String,
    label: String,
    /// Per landmark: the error in mm (`inf`: not placed), or why the truth is not on the surface.
    errors: [Result<f64, String>; 5],
    /// For a landmark reported unseen whose truth is on the surface: how far its prediction is.
    predicted_unseen: Vec<(LandmarkName, f64)>,
    /// The detection, or the error message.
    found: Result<Found, String>,
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

/// The numbers of a detection `v` under options `o`.
fn found(v: &VisibleLandmarks, o: &DetectOptions) -> Found {
    let weakest = v
        .landmarks
        .iter()
        .flatten()
        .map(|l| l.confidence / v.confidence.max(1e-12))
        .fold(1.0, f64::min);
    Found {
        confidence: v.confidence,
        symmetry: v.symmetry,
        weakest,
        weak: v.weak_evidence(o).iter().map(|w| w.to_string()).collect(),
    }
}

/// Detects the landmarks of one generated face.
fn detect_one(f: BeyondFace, kind: Kind, generic: &GenericModel, dopt: &DetectOptions) -> Outcome {
    let t0 = std::time::Instant::now();
    let r = options_for(&f.mesh, generic, dopt, f.toward_viewer)
        .and_then(|o| detect_visible(&f.mesh, generic, &o).map(|v| (v, o)));
    let detect_ms = t0.elapsed().as_secs_f64() * 1e3;
    let errors = LandmarkName::ALL.map(|n| match (&f.truth[n as usize], &r) {
        (Err(why), _) => Err(why.clone()),
        (Ok(t), Ok((v, _))) => Ok(v
            .get(n)
            .map_or(f64::INFINITY, |l| (l.position - *t).length())),
        (Ok(_), Err(_)) => Ok(f64::INFINITY),
    });
    let predicted_unseen = match &r {
        Ok((v, _)) => LandmarkName::ALL
            .iter()
            .filter(|&&n| v.get(n).is_err())
            .filter_map(|&n| {
                let t = f.truth[n as usize].as_ref().ok()?;
                Some((n, (v.predicted[n as usize] - *t).length()))
            })
            .collect(),
        Err(_) => Vec::new(),
    };
    Outcome {
        kind,
        name: f.name,
        label: f.label,
        errors,
        predicted_unseen,
        found: r.map(|(v, o)| found(&v, &o)).map_err(|e| e.to_string()),
        vertices: f.mesh.n_vertices(),
        detect_ms,
    }
}

/// Median and 95th percentile of `v` (NaN when empty).
fn median_p95(v: &[f64]) -> (f64, f64) {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let q = |p: f64| {
        v.get(((v.len().max(1) - 1) as f64 * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    (q(0.5), q(0.95))
}

/// Prints and returns the table row of one kind.
fn kind_summary(kind: Kind, rows: &[&Outcome]) -> serde_json::Value {
    let n = rows.len();
    let not_found: Vec<&&Outcome> = rows.iter().filter(|o| o.found.is_err()).collect();
    let weak = rows
        .iter()
        .filter(|o| o.found.as_ref().is_ok_and(|f| !f.weak.is_empty()))
        .count();
    let per: Vec<Stats> = LandmarkName::ALL
        .iter()
        .map(|&l| {
            let e: Vec<f64> = rows
                .iter()
                .filter_map(|o| o.errors[l as usize].as_ref().ok().copied())
                .collect();
            stats(l.key(), &e)
        })
        .collect();
    let outer: Vec<f64> = rows
        .iter()
        .flat_map(|o| [&o.errors[0], &o.errors[3]])
        .filter_map(|e| e.as_ref().ok().copied())
        .collect();
    let (om, op) = median_p95(&outer);
    let silent = rows
        .iter()
        .filter(|o| o.found.is_ok())
        .flat_map(|o| o.errors.iter())
        .filter(|e| matches!(e, Ok(x) if x.is_finite() && *x > 10.0))
        .count();
    let pred: Vec<f64> = rows
        .iter()
        .flat_map(|o| o.predicted_unseen.iter())
        .filter(|(l, _)| matches!(l, LandmarkName::OuterEyeRight | LandmarkName::OuterEyeLeft))
        .map(|x| x.1)
        .collect();
    let (pm, pp) = median_p95(&pred);
    let ms: Vec<f64> = rows.iter().map(|o| o.detect_ms).collect();
    let (tm, _) = median_p95(&ms);
    println!(
        "{:<18} {:>4} {:>5} {:>5} {:>7.2} {:>7.2} {:>7.2} {:>7.2} {:>7.2} {:>7} {:>4} {:>12} {:>7.0}",
        kind.name(),
        n,
        not_found.len(),
        weak,
        om,
        op,
        per[4].median_mm,
        per[1].median_mm.max(per[2].median_mm),
        per[0].max_mm.max(per[3].max_mm),
        silent,
        pred.len(),
        format!("{pm:.2}/{pp:.2}"),
        tm
    );
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
    println!(
        "{:<18} {:>4} {:>5} {:>5} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>4} {:>12} {:>7}",
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
        "detect"
    );
    println!(
        "{:<18} {:>4} {:>5} {:>5} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>4} {:>12} {:>7}",
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
        "ms"
    );
    let mut kinds_json = Vec::new();
    for &k in &kinds {
        let rows: Vec<&Outcome> = outcomes.iter().filter(|o| o.kind == k).collect();
        kinds_json.push(kind_summary(k, &rows));
    }
    let refused = run_non_faces(ict, generic, dopt, args.seed)?;
    write_csv(&outcomes, &out.join("per-face.csv"))?;
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
            mesh_units_per_model_unit: generic_mm_factor(generic)?,
            ..*dopt
        };
        let r = detect_visible(&mesh, generic, &o);
        let what = match &r {
            Ok(v) => format!(
                "LET THROUGH (confidence {}, symmetry {})",
                v.confidence, v.symmetry
            ),
            Err(e) => format!("refused: {e}"),
        };
        println!("non-face {name}: {what}");
        out.push(serde_json::json!({"non_face": name, "refused": r.is_err(), "outcome": what}));
    }
    Ok(out)
}

/// Millimetres per unit of the generic model (its units label read, or refused).
fn generic_mm_factor(generic: &GenericModel) -> Result<f64> {
    let u: meshcore::units::Units = generic
        .units
        .trim()
        .parse()
        .map_err(|e| anyhow::anyhow!("the generic model's units {:?}: {e}", generic.units))?;
    Ok(u.factor_to(meshcore::units::Units::Millimetre))
}

/// One row per face.
fn write_csv(outcomes: &[Outcome], path: &Path) -> Result<()> {
    let names: Vec<&str> = LandmarkName::ALL.iter().map(|n| n.key()).collect();
    let mut csv = format!(
        "face,kind,{},confidence,symmetry,weakest_agreement,weak,vertices,detect_ms,error,label\n",
        names.join(",")
    );
    for o in outcomes {
        let e: Vec<String> = o
            .errors
            .iter()
            .map(|e| match e {
                Ok(x) => format!("{x:.3}"),
                Err(w) => format!("truth not on the surface: {w}").replace(',', ";"),
            })
            .collect();
        let (c, s, w, weak, err) = match &o.found {
            Ok(f) => (
                f.confidence.to_string(),
                f.symmetry.to_string(),
                f.weakest.to_string(),
                f.weak.join("; "),
                String::new(),
            ),
            Err(e) => (
                String::new(),
                String::new(),
                String::new(),
                String::new(),
                e.clone(),
            ),
        };
        csv += &format!(
            "{},{},{},{c},{s},{w},{},{},{:.0},{},{}\n",
            o.name,
            o.kind.name(),
            e.join(","),
            weak.replace(',', ";"),
            o.vertices,
            o.detect_ms,
            err.replace(',', ";"),
            o.label.replace(',', ";")
        );
    }
    std::fs::write(path, csv).with_context(|| format!("writing {}", path.display()))
}
