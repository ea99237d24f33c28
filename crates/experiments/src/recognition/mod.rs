//! `cargo xtask recognition`: identification and verification on faces sampled from the ICT
//! face model, for the bipolar descriptor, the single-pole descriptor, ICP on the raw meshes and
//! the two curve representations of the paper's section 6 (facial curves, iso-curvature curves:
//! `experiments::curves`), each with ground-truth and with detected landmarks, with the time
//! per comparison and per description.
//!
//! N identities x M expressions are sampled (seeded); expression 0 of every identity is the
//! neutral face and forms the gallery, the M - 1 others are the probes. Every face is moved by
//! a random rigid motion, so nothing can rely on a shared frame. Scores are distances (lower =
//! more similar): rank-1 identification rate over the probes, verification EER over all
//! probe x gallery pairs, and the ROC curve. Results: `report.md`, `summary.json`, `roc.svg` (and `roc.png`),
//! CSV tables, in the output folder printed on the last line.
//!
//! The command line is in `options`, the descriptions in `describe`, the scores in `compare`,
//! the figures in `metrics`; `clean` runs the benchmark on clean meshes, `scans` on range
//! scans, `pool` pools runs of several seeds.

mod clean;
mod compare;
mod describe;
mod metrics;
mod options;
mod pool;
mod scans;
#[cfg(test)]
mod tests;

pub use options::Args;

use anyhow::{Context, Result};
use facemodel::FaceModel;
use std::time::Instant;

/// The reference vertices of a face (outer eye corners, nose tip; a lost corner explicit):
/// `facematch`'s, as are the pole pairs.
type Lm = facematch::Poles;

/// Runs the benchmark; prints the output folder on the last line.
pub fn run(args: Args) -> Result<()> {
    if !args.seeds.is_empty() {
        return pool::run(args);
    }
    let t0 = Instant::now();
    let model_dir = args.io.model_dir();
    let model = FaceModel::load(&model_dir)
        .with_context(|| format!("loading the ICT model from {}", model_dir.display()))?;
    if args.scans {
        return scans::run(&args, &model, t0);
    }
    clean::run(&args, &model, t0)
}
