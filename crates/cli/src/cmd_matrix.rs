//! `bipolar matrix`: pairwise normalised distances of descriptor files.

use std::path::PathBuf;

use anyhow::Context;
use shapedist::Which;

use crate::cmd_distance::{compare, load, CompareArgs};
use shapedist::Mode;

/// Arguments of `bipolar matrix`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Descriptor files (CSV, JSON or PLY from `bipolar describe`), at least two.
    #[arg(required = true, num_args = 2..)]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub compare: CompareArgs,
    /// Output CSV (header `label,<labels>`, one row per file; symmetric, zero diagonal).
    #[arg(long)]
    pub out: PathBuf,
    /// Also draw a labelled heatmap (SVG or PNG by extension).
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Title of the heatmap.
    #[arg(long, default_value = "Pairwise normalised shape distances")]
    pub title: String,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let c = &args.compare;
    let sets = args
        .files
        .iter()
        .map(|p| load(p, c, Which::A))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let idx: Vec<usize> = (0..sets.len()).collect();
    let m = shapedist::pairwise_matrix(&idx, |&i, &j| {
        compare(&sets[i], &sets[j], c).map(|(r, _)| r.distance())
    })
    .map_err(|e| e.error.context(format!("pair ({}, {})", e.i, e.j)))?;
    let labels: Vec<String> = sets.iter().map(|s| s.label.clone()).collect();
    let f = std::fs::File::create(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    shapedist::write_matrix_csv(std::io::BufWriter::new(f), &labels, &m)
        .with_context(|| format!("writing {}", args.out.display()))?;
    if let Some(h) = &args.heatmap {
        let value_label = match c.mode {
            Mode::Keys => "normalised L2 distance (keys)",
            Mode::Icp => "normalised mean closest-point distance",
            Mode::Hausdorff => "normalised Hausdorff distance",
        };
        viz::heatmap(h, &args.title, &labels, &m, value_label)
            .with_context(|| format!("drawing {}", h.display()))?;
    }
    eprintln!(
        "{} x {} matrix written to {}",
        m.len(),
        m.len(),
        args.out.display()
    );
    Ok(())
}
