//! `cargo xtask landmarks-eval`: accuracy of the automatic landmarker on faces sampled from the
//! ICT face model (random identities, expressions and rigid motions), against the model's
//! landmark vertices.

use crate::paths::ModelArgs;
use crate::scans::ScanArgs;
use anyhow::{Context, Result};
use facemodel::FaceModel;
use landmarks::{
    detect_with, DetectOptions, GenericModel, LandmarkRegressor, RegressorOptions, TrainOptions,
};
use meshcore::{DVec3, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

mod beyond;
mod beyond_eval;
mod meshes;
mod scans;
mod stats;

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
    /// Override `DetectOptions::comparable_fit_cost` (fits costing more than this multiple of
    /// the best fit's are tried after every pass over the better fits).
    #[arg(long)]
    pub comparable_fit_cost: Option<f64>,
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
pub(super) fn training_seed(seed: u64) -> u64 {
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

/// Sampled face with the positions of its landmark vertices.
pub(super) type Sample = (TriMesh, [DVec3; 5]);

/// Samples `n` faces; also returns, per face, the blendshapes weighted 0.3 or more (a label of
/// its expression for the per-face table).
pub(super) fn sample_faces(
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

/// Runs the evaluation.
pub fn run(args: Args) -> Result<()> {
    let model_dir = args.io.model_dir();
    let ict = FaceModel::load(&model_dir)
        .with_context(|| format!("loading the ICT face model from {}", model_dir.display()))?;
    anyhow::ensure!(args.faces > 0, "--faces must be positive");
    let out = args.io.out.out_dir("landmarks-eval");
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let generic = generic_model(&args, &ict)?;
    if let Some(p) = &args.write_model {
        std::fs::write(p, generic.to_json() + "\n")
            .with_context(|| format!("writing {}", p.display()))?;
        eprintln!("wrote the generic model to {}", p.display());
    }
    std::fs::write(out.join("generic-model.json"), generic.to_json() + "\n")?;
    let mut dopt = detect_options(&args);
    if args.beyond {
        return beyond_eval::run_beyond(&args, &ict, &generic, &dopt, &out.join("beyond"));
    }
    if args.scans {
        if !args.no_viewer {
            dopt.toward_viewer = Some(crate::scans::SCANNER_SIDE);
        }
        return scans::run_scans(&args, &ict, &generic, &dopt, &out.join("scans"));
    }
    meshes::run_meshes(&args, &ict, &generic, &dopt, &out)
}

/// The generic model evaluated: `--generic-model`, or trained on `--train` faces of the
/// training stream; with `--fit-regressor`, its landmark regression trained anew.
fn generic_model(args: &Args, ict: &FaceModel) -> Result<GenericModel> {
    let mut generic = if let Some(p) = &args.generic_model {
        GenericModel::load(p)?
    } else {
        let t0 = Instant::now();
        let (train, _) = sample_faces(ict, args.train, training_seed(args.seed), true)?;
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
        ro.radius = args.regressor_radius.unwrap_or(ro.radius);
        ro.spacing = args.regressor_spacing.unwrap_or(ro.spacing);
        ro.ridge = args.regressor_ridge.unwrap_or(ro.ridge);
        ro.perturbations = args.regressor_perturbations.unwrap_or(ro.perturbations);
        generic.regressor = Some(fit_regressor(ict, &generic, n, args.regressor_seed, &ro)?);
    }
    Ok(generic)
}

/// The detection options: the defaults with the overrides of the command line.
fn detect_options(args: &Args) -> DetectOptions {
    let mut dopt = DetectOptions::default();
    dopt.min_symmetry = args.min_symmetry.unwrap_or(dopt.min_symmetry);
    dopt.min_confidence = args.min_confidence.unwrap_or(dopt.min_confidence);
    dopt.use_regressor = !args.no_regressor;
    dopt.trace = args.trace;
    dopt.refuse_local_agreement = args
        .refuse_local_agreement
        .unwrap_or(dopt.refuse_local_agreement);
    dopt.comparable_fit_cost = args.comparable_fit_cost.unwrap_or(dopt.comparable_fit_cost);
    dopt
}
