//! `bipolar matrix`: pairwise normalised distances of descriptor files.

use std::path::PathBuf;

use anyhow::Context;
use shapedist::Which;

use crate::cmd_distance::{compare, compare_searched, load, load_moved, CompareArgs};
use crate::searchfiles::own_of;
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
    /// Reference-point search: read each file's moved descriptors `STEM.search-NN.EXT` (written
    /// beside it by `bipolar describe --search-radius`; listed search files of a listed file
    /// are folded into it, not rows of their own) and take per pair the least of the files'
    /// distance and each side's moved descriptors against the other's own
    /// (`bipolar::least_searched_distance`; symmetric).
    #[arg(long)]
    pub searched: bool,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let c = &args.compare;
    let files: Vec<&PathBuf> = if args.searched {
        // A listed search file of a listed file is read with it, not as a row.
        args.files
            .iter()
            .filter(|f| own_of(f).is_none_or(|o| !args.files.contains(&o)))
            .collect()
    } else {
        args.files.iter().collect()
    };
    if files.len() < 2 {
        anyhow::bail!(
            "--searched: {} descriptor file(s) besides search files; need at least two",
            files.len()
        );
    }
    let sets = files
        .iter()
        .map(|p| load(p, c, Which::A))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let moved = if args.searched {
        let moved = files
            .iter()
            .map(|p| load_moved(p, c, Which::A))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let n: usize = moved.iter().map(Vec::len).sum();
        if n == 0 {
            anyhow::bail!(
                "--searched: no moved descriptors beside any of the {} files (STEM.search-NN.EXT, written by `bipolar describe --search-radius`)",
                files.len()
            );
        }
        eprintln!(
            "reference-point search: {n} moved descriptors beside {} of the {} files",
            moved.iter().filter(|m| !m.is_empty()).count(),
            files.len()
        );
        moved
    } else {
        files.iter().map(|_| Vec::new()).collect()
    };
    let idx: Vec<usize> = (0..sets.len()).collect();
    let m = shapedist::pairwise_matrix(&idx, |&i, &j| {
        if args.searched {
            compare_searched((&sets[i], &moved[i]), (&sets[j], &moved[j]), c).map(|(d, _)| d)
        } else {
            compare(&sets[i], &sets[j], c).map(|(r, _)| r.distance())
        }
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
