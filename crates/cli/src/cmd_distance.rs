//! `bipolar distance`: normalised shape distance between two descriptor files.

use std::path::{Path, PathBuf};

use crate::choice::choice;
use anyhow::Context;
use glam::{DMat3, DVec3};
use serde_json::json;
use shapedist::{
    GlobalOptions, IcpOptions, IcpVariant, KeyedOptions, PrepareOptions, PreparedSet, RobustLoss,
    RotationMethod, Which,
};

/// How the two descriptors are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Pair the points by key, closed-form rotation (Kabsch): normalised L2 distance.
    Keys,
    /// Global ICP without keys: normalised mean closest-point distance after alignment.
    Icp,
    /// Global ICP without keys: normalised symmetric Hausdorff distance after alignment.
    Hausdorff,
}
meshcore::choice!(Mode, "comparison mode", meshcore::UnknownChoice {
    Keys = "keys",
    Icp = "icp",
    Hausdorff = "hausdorff",
});

/// Robust weights for the keyed fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Robust {
    /// Huber weights (k = 1.345 robust sigmas).
    Huber,
    /// Tukey biweight (c = 4.685 robust sigmas).
    Tukey,
}
meshcore::choice!(Robust, "robust loss", meshcore::UnknownChoice {
    Huber = "huber",
    Tukey = "tukey",
});

/// Options shared by `bipolar distance` and `bipolar matrix`.
#[derive(Debug, Clone, clap::Args)]
pub struct CompareArgs {
    /// Comparison mode.
    #[arg(long, default_value = "keys", value_parser = choice::<Mode>())]
    pub mode: Mode,
    /// Keys mode: closed-form solver.
    #[arg(long, default_value = "kabsch", value_parser = choice::<RotationMethod>())]
    pub solver: RotationMethod,
    /// Keys mode: robust IRLS weights.
    #[arg(long, value_parser = choice::<Robust>())]
    pub robust: Option<Robust>,
    /// Keys mode: drop pairs whose residual after alignment exceeds this length (same unit as
    /// the points; the method notes use about 0.3 x the reference distance).
    #[arg(long)]
    pub gate: Option<f64>,
    /// Keys mode: also use points flagged ambiguous in the files (they are dropped by default;
    /// keys repeated within a file are dropped in any case).
    #[arg(long)]
    pub keep_ambiguous: bool,
    /// ICP modes: error variant of the refinement.
    #[arg(long, default_value = "point", value_parser = choice::<IcpVariant>())]
    pub variant: IcpVariant,
    /// ICP modes: fraction of the worst pairs rejected at each iteration.
    #[arg(long, default_value_t = 0.0)]
    pub trim: f64,
    /// ICP modes: maximum refinement iterations on all points.
    #[arg(long, default_value_t = 100)]
    pub iterations: usize,
    /// ICP modes: skip the multi-start global search (plain ICP from the identity).
    #[arg(long)]
    pub no_global: bool,
}

/// Arguments of `bipolar distance`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// First descriptor file (CSV, JSON or PLY from `bipolar describe`).
    pub a: PathBuf,
    /// Second descriptor file.
    pub b: PathBuf,
    #[command(flatten)]
    pub compare: CompareArgs,
    /// Print details as JSON (rotation, shared keys and shares, iterations, rmse).
    #[arg(long)]
    pub json: bool,
}

/// A descriptor file reduced to what the distances need.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// Display label (file stem).
    pub label: String,
    /// Packed keys of the points kept for keyed comparison.
    pub keys: Vec<u64>,
    /// Positions of those points.
    pub key_points: Vec<DVec3>,
    /// All positions (ICP modes).
    pub points: Vec<DVec3>,
}

/// Reads a descriptor file with `bipolar::io::read_auto`.
pub fn load(path: &Path, keep_ambiguous: bool) -> anyhow::Result<Loaded> {
    let d = bipolar::io::read_auto(path)
        .with_context(|| format!("reading descriptor {}", path.display()))?;
    if d.is_empty() {
        anyhow::bail!("descriptor {} has no points", path.display());
    }
    let kept: Vec<_> = d
        .points
        .iter()
        .filter(|p| keep_ambiguous || !p.ambiguous)
        .collect();
    Ok(Loaded {
        label: path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into_owned(),
        ),
        keys: kept.iter().map(|p| p.key.pack()).collect(),
        key_points: kept.iter().map(|p| p.position).collect(),
        points: d.positions(),
    })
}

impl CompareArgs {
    /// Keyed options from the flags.
    pub fn keyed_options(&self) -> anyhow::Result<KeyedOptions> {
        Ok(KeyedOptions {
            method: self.solver,
            robust: self.robust.map(|r| match r {
                Robust::Huber => RobustLoss::Huber(1.345),
                Robust::Tukey => RobustLoss::Tukey(4.685),
            }),
            irls_iterations: 5,
            gate: self.gate,
        })
    }

    /// Global ICP options from the flags.
    pub fn global_options(&self) -> GlobalOptions {
        GlobalOptions {
            grid: !self.no_global,
            refine: IcpOptions {
                variant: self.variant,
                max_iterations: self.iterations.max(1),
                trim: self.trim,
                ..IcpOptions::default()
            },
            ..GlobalOptions::default()
        }
    }
}

/// Prepares a loaded descriptor for the ICP modes.
pub fn prepare(l: &Loaded, which: Which) -> anyhow::Result<PreparedSet> {
    PreparedSet::new(&l.points, &PrepareOptions::default(), which)
        .with_context(|| format!("descriptor {}", l.label))
}

fn rows(r: DMat3) -> [[f64; 3]; 3] {
    let t = r.transpose();
    [
        t.x_axis.to_array(),
        t.y_axis.to_array(),
        t.z_axis.to_array(),
    ]
}

/// Distance between two loaded descriptors and its JSON details.
pub fn compare(
    a: &Loaded,
    b: &Loaded,
    pa: Option<&PreparedSet>,
    pb: Option<&PreparedSet>,
    c: &CompareArgs,
) -> anyhow::Result<(f64, serde_json::Value)> {
    match c.mode {
        Mode::Keys => {
            let r = shapedist::keyed_distance(
                &a.keys,
                &a.key_points,
                &b.keys,
                &b.key_points,
                &c.keyed_options()?,
            )
            .with_context(|| format!("keyed distance of {} and {}", a.label, b.label))?;
            let v = json!({
                "mode": "keys",
                "a": a.label, "b": b.label,
                "distance": r.distance,
                "normalisation": "min_R ||A - R B||_F / sqrt(||A||_F^2 + ||B||_F^2), centred, paired by key",
                "rotation": rows(r.motion.matrix3),
                "translation": r.motion.translation.to_array(),
                "shared_keys": r.shared_keys,
                "pairs_used": r.pairs_used,
                "share_a": r.share_a,
                "share_b": r.share_b,
                "points_a": a.points.len(),
                "points_b": b.points.len(),
                "keyed_points_a": a.keys.len(),
                "keyed_points_b": b.keys.len(),
                "repeated_keys_a": r.ambiguous_a,
                "repeated_keys_b": r.ambiguous_b,
                "gated": r.gated,
                "rmse": r.rmse,
                "max_residual": r.max_residual,
            });
            Ok((r.distance, v))
        }
        Mode::Icp | Mode::Hausdorff => {
            let owned;
            let (pa, pb) = match (pa, pb) {
                (Some(x), Some(y)) => (x, y),
                _ => {
                    owned = (prepare(a, Which::A)?, prepare(b, Which::B)?);
                    (&owned.0, &owned.1)
                }
            };
            let r = shapedist::icp_distance(pa, pb, &c.global_options())
                .with_context(|| format!("ICP distance of {} and {}", a.label, b.label))?;
            let d = if c.mode == Mode::Icp {
                r.stats.mean_normalised
            } else {
                r.stats.hausdorff_normalised
            };
            let v = json!({
                "mode": c.mode.to_string(),
                "a": a.label, "b": b.label,
                "distance": d,
                "normalisation": if c.mode == Mode::Icp {
                    "symmetric mean closest-point distance / (rho_A + rho_B), after global ICP"
                } else {
                    "symmetric Hausdorff distance / (rho_A + rho_B), after global ICP"
                },
                "mean_normalised": r.stats.mean_normalised,
                "hausdorff_normalised": r.stats.hausdorff_normalised,
                "rms_normalised": r.stats.rms_normalised,
                "mean": r.stats.mean,
                "hausdorff": r.stats.hausdorff,
                "rms": r.stats.rms,
                "rotation": rows(r.motion.matrix3),
                "iterations": r.iterations,
                "converged": r.converged,
                "starts": r.starts,
                "rmse": r.rmse,
                "points_a": a.points.len(),
                "points_b": b.points.len(),
            });
            Ok((d, v))
        }
    }
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let keep = args.compare.keep_ambiguous;
    let a = load(&args.a, keep)?;
    let b = load(&args.b, keep)?;
    let (d, details) = compare(&a, &b, None, None, &args.compare)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&details)?);
    } else {
        println!("{d}");
    }
    Ok(())
}
