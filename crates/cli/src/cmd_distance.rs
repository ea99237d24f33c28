//! `bipolar distance`: normalised shape distance between two descriptor files.

use std::path::{Path, PathBuf};

use crate::choice::choice;
use anyhow::Context;
use shapedist::{
    CompareOptions, ComparedSet, Comparison, IcpVariant, Mode, RobustWeights, RotationMethod, Which,
};

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
    #[arg(long, value_parser = choice::<RobustWeights>())]
    pub robust: Option<RobustWeights>,
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
    /// Reference-point search: also read the moved descriptors `STEM.search-NN.EXT` that
    /// `bipolar describe --search-radius` wrote beside each file, and print the least of the two
    /// files' distance and each side's moved descriptors against the other's own
    /// (`bipolar::least_searched_distance`).
    #[arg(long)]
    pub searched: bool,
}

/// A descriptor file reduced to what the distances need.
#[derive(Debug)]
pub struct Loaded {
    /// Display label (file stem).
    pub label: String,
    /// The points compared.
    pub set: ComparedSet,
}

/// Reads a descriptor file with `bipolar::io::read_auto` and prepares it for the ICP modes of
/// `c` (`which` names it in errors).
pub fn load(path: &Path, c: &CompareArgs, which: Which) -> anyhow::Result<Loaded> {
    let d = bipolar::io::read_auto(path)
        .with_context(|| format!("reading descriptor {}", path.display()))?;
    if d.is_empty() {
        anyhow::bail!("descriptor {} has no points", path.display());
    }
    let label = path.file_stem().map_or_else(
        || path.display().to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    let (keys, key_points) = d.keyed_points(c.keep_ambiguous);
    let mut set = ComparedSet::new(keys, key_points, d.positions());
    set.prepare(c.mode, which)
        .with_context(|| format!("descriptor {label}"))?;
    Ok(Loaded { label, set })
}

impl CompareArgs {
    /// The comparison settings of the flags.
    pub fn options(&self) -> CompareOptions {
        CompareOptions {
            mode: self.mode,
            solver: self.solver,
            robust: self.robust,
            gate: self.gate,
            variant: self.variant,
            trim: self.trim,
            iterations: self.iterations,
            global_search: !self.no_global,
        }
    }
}

/// Distance between two loaded descriptors and its JSON details.
pub fn compare(
    a: &Loaded,
    b: &Loaded,
    c: &CompareArgs,
) -> anyhow::Result<(Comparison, serde_json::Value)> {
    let r = shapedist::compare(&a.set, &b.set, &c.options()).with_context(|| {
        let what = if c.mode == Mode::Keys { "keyed" } else { "ICP" };
        format!("{what} distance of {} and {}", a.label, b.label)
    })?;
    let mut v = r.details(&a.set, &b.set);
    v["a"] = a.label.clone().into();
    v["b"] = b.label.clone().into();
    v["normalisation"] = c.mode.normalisation().into();
    if c.mode != Mode::Keys {
        // The ICP modes align rotations only: no translation is printed.
        if let Some(o) = v.as_object_mut() {
            o.remove("translation");
        }
    }
    Ok((r, v))
}

/// The moved descriptors of a reference-point search beside `own` (`--searched`), loaded.
pub fn load_moved(own: &Path, c: &CompareArgs, which: Which) -> anyhow::Result<Vec<Loaded>> {
    crate::searchfiles::search_files(own)?
        .iter()
        .map(|p| load(p, c, which))
        .collect()
}

/// The distance of `a` and `b` with their moved descriptors (`bipolar::least_searched_distance`)
/// and the JSON details of the comparison that gave it.
pub fn compare_searched(
    (a, a_moved): (&Loaded, &[Loaded]),
    (b, b_moved): (&Loaded, &[Loaded]),
    c: &CompareArgs,
) -> anyhow::Result<(f64, serde_json::Value)> {
    let mut best: Option<(f64, serde_json::Value)> = None;
    let d = bipolar::least_searched_distance(a, a_moved, b, b_moved, |x, y| {
        let (r, v) = compare(x, y, c)?;
        let d = r.distance();
        if best.as_ref().is_none_or(|(b, _)| d < *b) {
            best = Some((d, v));
        }
        Ok::<f64, anyhow::Error>(d)
    })?;
    let details = best.map(|(_, v)| v).unwrap_or_default();
    Ok((d, details))
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let a = load(&args.a, &args.compare, Which::A)?;
    let b = load(&args.b, &args.compare, Which::B)?;
    if args.searched {
        let am = load_moved(&args.a, &args.compare, Which::A)?;
        let bm = load_moved(&args.b, &args.compare, Which::B)?;
        if am.is_empty() && bm.is_empty() {
            anyhow::bail!(
                "--searched: no moved descriptors beside {} or {} (STEM.search-NN.EXT, written by `bipolar describe --search-radius`)",
                args.a.display(),
                args.b.display()
            );
        }
        let (d, mut details) = compare_searched((&a, &am), (&b, &bm), &args.compare)?;
        if args.json {
            details["searched"] = serde_json::json!({
                "distance": d,
                "a_moved": am.len(),
                "b_moved": bm.len(),
            });
            println!("{}", serde_json::to_string_pretty(&details)?);
        } else {
            println!("{d}");
        }
        return Ok(());
    }
    let (r, details) = compare(&a, &b, &args.compare)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&details)?);
    } else {
        println!("{}", r.distance());
    }
    Ok(())
}
