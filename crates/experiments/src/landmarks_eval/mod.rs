//! `cargo xtask landmarks-eval`: accuracy of the automatic landmarker on faces sampled from the
//! ICT face model (random identities, expressions and rigid motions), against the model's
//! landmark vertices.

use crate::paths::ModelArgs;
use crate::scans::ScanArgs;
use anyhow::{Context, Result};
use facemodel::{FaceModel, LANDMARK_NAMES};
use indicatif::{ProgressBar, ProgressStyle};
use landmarks::{
    detect_with, DetectOptions, GenericModel, LandmarkName, LandmarkRegressor, RegressorOptions,
    TrainOptions,
};
use meshcore::{DVec3, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

mod beyond;
mod beyond_eval;
mod scans;

/// Options of `cargo xtask landmarks-eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Number of test faces.
    #[arg(long, default_value_t = 100)]
    pub faces: usize,
    /// Number of training faces of the generic model.
    #[arg(long, default_value_t = 60)]
    pub train: usize,
    /// Seed (training and test faces use different streams derived from it).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// ICT model folder (`--model-dir` or `--model`) and output folder (default
    /// `target/landmarks-eval`).
    #[command(flatten)]
    pub io: ModelArgs,
    /// Test neutral faces only (no expressions).
    #[arg(long)]
    pub neutral: bool,
    /// Evaluate this generic model file instead of training one.
    #[arg(long)]
    pub generic_model: Option<PathBuf>,
    /// Evaluate only the test face of this index (debugging; with `--trace` for the detector's trace).
    #[arg(long)]
    pub only: Option<usize>,
    /// Evaluate on the training faces (`--train` of them, training seed stream) instead of the
    /// test faces: how detection thresholds are calibrated without looking at the test faces.
    #[arg(long)]
    pub on_training: bool,
    /// Override `DetectOptions::min_symmetry` (0 disables the symmetry check).
    #[arg(long)]
    pub min_symmetry: Option<f64>,
    /// Override `DetectOptions::min_confidence`.
    #[arg(long)]
    pub min_confidence: Option<f64>,
    /// Also write the trained generic model to this file (how the crate's default model is made).
    #[arg(long)]
    pub write_model: Option<PathBuf>,
    /// Train the model's landmark regression on this many faces of the training stream of
    /// `--regressor-seed` (poses fitted by the detector), replacing any it has.
    #[arg(long)]
    pub fit_regressor: Option<usize>,
    /// Seed of the training stream of `--fit-regressor`.
    #[arg(long, default_value_t = 1)]
    pub regressor_seed: u64,
    /// `RegressorOptions::radius` (fraction of the inner-eye distance).
    #[arg(long)]
    pub regressor_radius: Option<f64>,
    /// `RegressorOptions::spacing` (fraction of the inner-eye distance).
    #[arg(long)]
    pub regressor_spacing: Option<f64>,
    /// `RegressorOptions::ridge`: the ridge penalty of the landmark regression.
    #[arg(long)]
    pub regressor_ridge: Option<f64>,
    /// `RegressorOptions::perturbations` (extra perturbed poses per training face).
    #[arg(long)]
    pub regressor_perturbations: Option<usize>,
    /// Detect without the model's landmark regression (template search alone).
    #[arg(long)]
    pub no_regressor: bool,
    /// Evaluate on range scans of the test faces (`rangescan`, cleaned by `scanprep` with a
    /// crop around the nose tip) instead of the meshes; the scanner settings are the `--scan-*`
    /// options. Writes into the `scans` folder of the output folder.
    #[arg(long)]
    pub scans: bool,
    /// With `--scans`: detect without the direction toward the scanner
    /// (`DetectOptions::toward_viewer` unset, every rim counts as mismatch as on a mesh).
    #[arg(long)]
    pub no_viewer: bool,
    /// Scanner settings of `--scans`.
    #[command(flatten)]
    pub scan: ScanArgs,
    /// Override `DetectOptions::refuse_local_agreement` (below `min_local_agreement`: weakly
    /// agreeing landmarks are returned graded instead of refused).
    #[arg(long)]
    pub refuse_local_agreement: Option<f64>,
    /// Print the detector's trace to standard error (`DetectOptions::trace`).
    #[arg(long)]
    pub trace: bool,
    /// Evaluate on faces outside the ICT model's span (expressions beyond full strength, smooth
    /// warps, other topologies, depth-camera scans) and on non-faces, made from the stream of
    /// `--seed`; writes into the `beyond` folder of the output folder.
    #[arg(long)]
    pub beyond: bool,
    /// With `--beyond`: faces per kind.
    #[arg(long, default_value_t = 25)]
    pub beyond_faces: usize,
    /// With `--beyond`: only this kind (strong-expression, warp, remesh, depth-camera).
    #[arg(long)]
    pub beyond_kind: Option<String>,
}

/// Seed of the training stream of `seed`.
fn training_seed(seed: u64) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x7472_6169_6e00
}

/// Seed of the test stream of `seed`.
pub(super) fn test_seed(seed: u64) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x7465_7374_0000
}

/// Trains the landmark regression of `generic` on `n` faces of the training stream of `seed`.
fn fit_regressor(
    ict: &FaceModel,
    generic: &GenericModel,
    n: usize,
    seed: u64,
    opt: &RegressorOptions,
) -> Result<LandmarkRegressor> {
    let t0 = Instant::now();
    let (faces, _) = sample_faces(ict, n, training_seed(seed), true)?;
    let mut plain = generic.clone();
    plain.regressor = None;
    let dopt = DetectOptions::default();
    let poses: Vec<Option<meshcore::DAffine3>> = faces
        .par_iter()
        .map(|(m, _)| detect_with(m, &plain, &dopt).ok().map(|l| l.model_to_mesh))
        .collect();
    let samples: Vec<(&TriMesh, [DVec3; 5], meshcore::DAffine3)> = faces
        .iter()
        .zip(&poses)
        .filter_map(|((m, lm), p)| p.map(|p| (m, *lm, p)))
        .collect();
    let reg = LandmarkRegressor::train(generic, &samples, opt)?;
    eprintln!(
        "trained the landmark regression on {} of {n} faces (training stream of seed {seed}) in {:.1} s",
        reg.n_training,
        t0.elapsed().as_secs_f64()
    );
    Ok(reg)
}

/// Per test face: errors (mm), CPU ms, error message, confidence, symmetry, the weakest local
/// template agreement.
type Outcome = (Vec<f64>, f64, Option<String>, f64, f64, f64);

/// Sampled face with the positions of its landmark vertices.
type Sample = (TriMesh, [DVec3; 5]);

/// Samples `n` faces; also returns, per face, the blendshapes weighted 0.3 or more (a label of
/// its expression for the per-face table).
fn sample_faces(
    model: &FaceModel,
    n: usize,
    seed: u64,
    expressions: bool,
) -> Result<(Vec<Sample>, Vec<String>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let mut labels = Vec::with_capacity(n);
    for _ in 0..n {
        let id = model.random_identity(&mut rng);
        let ex = if expressions {
            model.random_expression(&mut rng)
        } else {
            vec![]
        };
        let pose = facemodel::random_rigid_motion(&mut rng, 10.0);
        let face = model.sample(&id, &ex)?.transformed(&pose);
        let lm = model.landmark_positions(&face)?;
        out.push((face, lm));
        let strong: Vec<String> = model
            .expression_names()
            .iter()
            .zip(&ex)
            .filter(|(_, &w)| w >= 0.3)
            .map(|(name, w)| format!("{name}={w:.2}"))
            .collect();
        labels.push(strong.join(" "));
    }
    Ok((out, labels))
}

/// Statistics of one landmark's errors (mm).
#[derive(Debug, serde::Serialize)]
pub(super) struct Stats {
    landmark: String,
    n: usize,
    failures: usize,
    mean_mm: f64,
    median_mm: f64,
    p95_mm: f64,
    max_mm: f64,
    within_2_5mm: f64,
    within_5mm: f64,
    within_10mm: f64,
}

pub(super) fn stats(name: &str, errs: &[f64]) -> Stats {
    let mut v = errs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let q = |p: f64| {
        if n == 0 {
            f64::NAN
        } else {
            v[((n - 1) as f64 * p).round() as usize]
        }
    };
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let share = |t: f64| v.iter().filter(|&&x| x <= t).count() as f64 / n.max(1) as f64;
    Stats {
        landmark: name.to_owned(),
        n,
        failures: n - finite.len(),
        mean_mm: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
        median_mm: q(0.5),
        p95_mm: q(0.95),
        max_mm: q(1.0),
        within_2_5mm: share(2.5),
        within_5mm: share(5.0),
        within_10mm: share(10.0),
    }
}

/// Runs the evaluation.
pub fn run(args: Args) -> Result<()> {
    let model_dir = args.io.model_dir();
    let ict = FaceModel::load(&model_dir)
        .with_context(|| format!("loading the ICT face model from {}", model_dir.display()))?;
    anyhow::ensure!(args.faces > 0, "--faces must be positive");
    let out = args.io.out.out_dir("landmarks-eval");
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    // Different streams for training and test faces.
    let train_seed = training_seed(args.seed);
    let test_seed = test_seed(args.seed);
    let mut generic = if let Some(p) = &args.generic_model {
        GenericModel::load(p)?
    } else {
        let t0 = Instant::now();
        let (train, _) = sample_faces(&ict, args.train, train_seed, true)?;
        let g = GenericModel::train_with(&train, &TrainOptions::default(), ict.units())?;
        eprintln!(
            "trained the generic model on {} faces in {:.1} s",
            args.train,
            t0.elapsed().as_secs_f64()
        );
        g
    };
    if let Some(n) = args.fit_regressor {
        let mut ro = RegressorOptions::default();
        if let Some(x) = args.regressor_radius {
            ro.radius = x;
        }
        if let Some(x) = args.regressor_spacing {
            ro.spacing = x;
        }
        if let Some(x) = args.regressor_ridge {
            ro.ridge = x;
        }
        if let Some(x) = args.regressor_perturbations {
            ro.perturbations = x;
        }
        generic.regressor = Some(fit_regressor(&ict, &generic, n, args.regressor_seed, &ro)?);
    }
    if let Some(p) = &args.write_model {
        std::fs::write(p, generic.to_json() + "\n")
            .with_context(|| format!("writing {}", p.display()))?;
        eprintln!("wrote the generic model to {}", p.display());
    }
    std::fs::write(out.join("generic-model.json"), generic.to_json() + "\n")?;
    let mut dopt = DetectOptions::default();
    if let Some(x) = args.min_symmetry {
        dopt.min_symmetry = x;
    }
    if let Some(x) = args.min_confidence {
        dopt.min_confidence = x;
    }
    dopt.use_regressor = !args.no_regressor;
    dopt.trace = args.trace;
    if let Some(x) = args.refuse_local_agreement {
        dopt.refuse_local_agreement = x;
    }
    if args.beyond {
        return beyond_eval::run_beyond(&args, &ict, &generic, &dopt, &out.join("beyond"));
    }
    if args.scans {
        if !args.no_viewer {
            dopt.toward_viewer = Some(crate::scans::SCANNER_SIDE);
        }
        return scans::run_scans(&args, &ict, &generic, &dopt, &out.join("scans"));
    }
    let unit_mm = if ict.units() == "cm" { 10.0 } else { 1.0 };
    let (mut test, mut labels) = if args.on_training {
        sample_faces(&ict, args.train, train_seed, true)?
    } else {
        sample_faces(&ict, args.faces, test_seed, !args.neutral)?
    };
    // Index of each evaluated face in its stream.
    let mut face_ids: Vec<usize> = (0..test.len()).collect();
    if let Some(i) = args.only {
        anyhow::ensure!(i < test.len(), "--only {i}: only {} test faces", test.len());
        test = vec![test.swap_remove(i)];
        labels = vec![labels.swap_remove(i)];
        face_ids = vec![i];
    }
    let pb = ProgressBar::new(test.len() as u64);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb.set_message("detecting");
    let (results, rows): (Vec<Outcome>, Vec<String>) = test
        .par_iter()
        .map(|(mesh, gt)| {
            let c0 = thread_cpu_ns();
            let r = detect_with(mesh, &generic, &dopt);
            // CPU time of this thread (wall-clock time is meaningless on a loaded machine);
            // falls back to wall-clock time where /proc is unavailable.
            let ms = match (c0, thread_cpu_ns()) {
                (Some(a), Some(b)) => (b - a) as f64 * 1e-6,
                _ => f64::NAN,
            };
            pb.inc(1);
            match r {
                Ok(lm) => {
                    let e = LandmarkName::ALL
                        .iter()
                        .map(|&n| (lm.get(n).position - gt[n as usize]).length() * unit_mm)
                        .collect();
                    // Per-face row: errors of the landmarks predicted by the fitted pose alone
                    // (before the local refinement), and the error vectors in the canonical
                    // frame of the model (x: right to left eye, y: up, z: out of the face).
                    let pose = lm.model_to_mesh;
                    let inv = pose.inverse();
                    let mut row = Vec::new();
                    for &n in &LandmarkName::ALL {
                        let pred = pose.transform_point3(generic.landmark(n));
                        row.push(format!("{:.2}", (pred - gt[n as usize]).length() * unit_mm));
                    }
                    let od = |p: [DVec3; 5]| (p[3] - p[0]).length() * unit_mm;
                    row.push(format!("{:.2},{:.2}", od(*gt), od(lm.positions())));
                    for &n in &LandmarkName::ALL {
                        let dv = inv.transform_vector3(lm.get(n).position - gt[n as usize]);
                        row.push(format!(
                            "{:.2} {:.2} {:.2}",
                            dv.x * unit_mm,
                            dv.y * unit_mm,
                            dv.z * unit_mm
                        ));
                    }
                    (
                        (
                            e,
                            ms,
                            None,
                            lm.confidence,
                            lm.symmetry,
                            LandmarkName::ALL
                                .iter()
                                .map(|&n| lm.get(n).confidence / lm.confidence.max(1e-12))
                                .fold(1.0, f64::min),
                        ),
                        row.join(","),
                    )
                }
                Err(e) => (
                    (
                        vec![f64::INFINITY; 5],
                        ms,
                        Some(e.to_string()),
                        0.0,
                        0.0,
                        0.0,
                    ),
                    String::new(),
                ),
            }
        })
        .unzip();
    pb.finish_and_clear();
    let mut per: Vec<Vec<f64>> = vec![Vec::new(); 5];
    for (e, ..) in &results {
        for k in 0..5 {
            per[k].push(e[k]);
        }
    }
    let names: Vec<&str> = LandmarkName::ALL.iter().map(|n| n.key()).collect();
    let st: Vec<Stats> = names.iter().zip(&per).map(|(n, e)| stats(n, e)).collect();
    let mut times: Vec<f64> = results.iter().map(|r| r.1).collect();
    times.sort_by(f64::total_cmp);
    let failures: Vec<(usize, String)> = results
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.2.clone().map(|e| (i, e)))
        .collect();
    println!(
        "{} test faces ({}), generic model from {} training faces; errors in mm",
        test.len(),
        if args.neutral {
            "neutral"
        } else {
            "random expressions"
        },
        generic.n_training
    );
    println!(
        "{:<16} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}",
        "landmark", "mean", "median", "p95", "max", "<2.5", "<5", "<10"
    );
    for s in &st {
        println!(
            "{:<16} {:>7.2} {:>7.2} {:>7.2} {:>7.2} {:>6.1}% {:>6.1}% {:>6.1}%",
            s.landmark,
            s.mean_mm,
            s.median_mm,
            s.p95_mm,
            s.max_mm,
            100.0 * s.within_2_5mm,
            100.0 * s.within_5mm,
            100.0 * s.within_10mm
        );
    }
    let tmed = times[times.len() / 2];
    let tp95 = times[((times.len() - 1) as f64 * 0.95) as usize];
    println!("CPU time per face (thread CPU time, release): median {tmed:.1} ms, p95 {tp95:.1} ms");
    for (i, e) in failures.iter().take(20) {
        println!("face {i}: {e}");
    }
    println!("failures: {}", failures.len());
    // Outcome per face: correct (every landmark within 10 mm), rejected (NotFound) or silently
    // wrong (a detection with some landmark beyond 10 mm).
    let n = results.len() as f64;
    let correct = results
        .iter()
        .filter(|r| r.2.is_none() && r.0.iter().all(|&e| e <= 10.0))
        .count();
    let silent_wrong = results
        .iter()
        .filter(|r| r.2.is_none() && r.0.iter().any(|&e| e > 10.0))
        .count();
    let not_found = failures.len();
    println!(
        "outcomes: correct {correct} ({:.1} %), not found {not_found} ({:.1} %), silent wrong (> 10 mm) {silent_wrong} ({:.1} %)",
        100.0 * correct as f64 / n,
        100.0 * not_found as f64 / n,
        100.0 * silent_wrong as f64 / n
    );
    for (what, get) in [
        ("confidence", (|r: &Outcome| r.3) as fn(&Outcome) -> f64),
        ("symmetry", |r| r.4),
        ("local template agreement", |r| r.5),
    ] {
        let mut v: Vec<f64> = results
            .iter()
            .filter(|r| r.2.is_none() && r.0.iter().all(|&e| e <= 10.0))
            .map(get)
            .collect();
        v.sort_by(f64::total_cmp);
        if !v.is_empty() {
            println!(
                "{what} of correct detections: min {:.3}, p1 {:.3}, p5 {:.3}, median {:.3}",
                v[0],
                v[((v.len() - 1) as f64 * 0.01).round() as usize],
                v[((v.len() - 1) as f64 * 0.05).round() as usize],
                v[v.len() / 2]
            );
        }
    }
    let worst: Vec<(usize, f64, f64, f64, f64)> = results
        .iter()
        .enumerate()
        .map(|(i, r)| (i, r.0.iter().copied().fold(0.0, f64::max), r.3, r.4, r.5))
        .filter(|w| w.1 > 10.0 && w.1.is_finite())
        .collect();
    for (i, e, c, sy, lo) in worst.iter().take(20) {
        let each: Vec<String> = results[*i].0.iter().map(|x| format!("{x:.1}")).collect();
        println!(
            "face {i}: largest error {e:.1} mm (per landmark {}), confidence {c:.2}, symmetry {sy:.2}, local {lo:.2}",
            each.join(" ")
        );
    }
    let summary = serde_json::json!({
        "faces": test.len(),
        "training_faces": generic.n_training,
        "seed": args.seed,
        "expressions": !args.neutral,
        "units_of_errors": "mm",
        "landmark_vertices": LANDMARK_NAMES,
        "per_landmark": st,
        "cpu_time_ms_per_face": {"median": tmed, "p95": tp95},
        "outcomes": {"correct": correct, "not_found": not_found, "silent_wrong_over_10mm": silent_wrong},
        "failures": failures.iter().map(|(i, e)| serde_json::json!({"face": i, "error": e})).collect::<Vec<_>>(),
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    // One row per face: errors, pose-only errors, canonical error vectors, expression.
    let mut csv = String::from("face");
    for n in &names {
        csv += &format!(",{n}");
    }
    for n in &names {
        csv += &format!(",{n}_pose_only");
    }
    csv += ",outer_eye_distance_true,outer_eye_distance_detected";
    for n in &names {
        csv += &format!(",{n}_xyz");
    }
    csv += ",cpu_ms,confidence,symmetry,local,error,expression\n";
    for (k, (r, row)) in results.iter().zip(&rows).enumerate() {
        let errs: Vec<String> = r.0.iter().map(|x| format!("{x:.2}")).collect();
        let row = if row.is_empty() {
            vec![String::new(); 12].join(",")
        } else {
            row.clone()
        };
        csv += &format!(
            "{},{},{row},{:.1},{:.3},{:.3},{:.3},{},{}\n",
            face_ids[k],
            errs.join(","),
            r.1,
            r.3,
            r.4,
            r.5,
            r.2.as_deref().unwrap_or("").replace(',', ";"),
            labels[k]
        );
    }
    std::fs::write(out.join("per-face.csv"), csv)?;
    let series: Vec<(String, Vec<f64>)> = names
        .iter()
        .zip(&per)
        .map(|(n, e)| (n.to_string(), e.iter().map(|x| x.min(15.0)).collect()))
        .collect();
    viz::histogram(
        out.join("errors-histogram.svg"),
        "Landmark errors on sampled ICT faces",
        "error (mm, clipped at 15)",
        &series,
        30,
    )?;
    println!("{}", out.display());
    Ok(())
}

/// CPU time consumed by the calling thread so far (ns), from `/proc/thread-self/schedstat`.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}
