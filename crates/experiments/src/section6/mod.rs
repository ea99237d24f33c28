//! `cargo xtask section6`: the paper's section 6 in numbers. The four representations side by
//! side on the paper set: bipolar (`bipolar::describe`, static area), single pole
//! (`bipolar::polar`), facial curves and iso-curvature curves (`facecurves`).
//!
//! * **Between persons**: the 12 x 12 matrix of each representation (and the time per
//!   comparison).
//! * **Reference-point errors** (the grid of figures 9-11): the left outer eye corner (bipolar)
//!   or the nose tip (single pole, facial curves, and the centre of the iso-curvature region)
//!   of the test face moved by 1-5 % of D in 8 directions (`crate::pipeline::perturb`).
//! * **Depth noise**: Gaussian noise along the vertex normals of the test face.
//! * **Figure 15**: polar rings 2, 4, 6 rotated about their centroids
//!   (`robustness::pole::rotate_rings`), scored by each distance.
//!
//! Each movement is reported against the distance between persons (the test face's nearest
//! other person), so the four distances, on different scales, can be compared. The report
//! states for each claim of section 6 whether the numbers support it.

use crate::paths::FaceSetArgs;
use crate::polar::Pole;
use crate::report::Failures;
use crate::report::{par_map, Report};
use crate::robustness::FacePrep;
use crate::walk::Walker;
use anyhow::{bail, Context, Result};
use describe::{Ctx, Descs};
use facecurves::nose::reference_iso_levels;
use measure::Set;
use meshcore::Surface;
use rayon::prelude::*;
use std::time::Instant;

mod describe;
mod figure15;
mod measure;
mod write;

/// Table columns of the four representations' movements (relative to the distance between
/// persons in brackets).
const REL_COLUMNS: [&str; 4] = [
    "bipolar mean (rel.)",
    "single pole (rel.)",
    "facial curves (rel.)",
    "iso-curvature (rel.)",
];

/// CSV columns of the four representations.
const CSV_COLUMNS: [&str; 4] = ["bipolar", "single_pole", "facial", "iso_curvature"];

/// Arguments of `cargo xtask section6`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Face set, report folder (default `target/section6`) and resolution: bipolar levels N
    /// between the corners; polar radii and facial curves at D / N; single-pole sectors.
    #[command(flatten)]
    pub set: FaceSetArgs,
    /// Levels per principal field of the iso-curvature network (between the 5 % and 95 %
    /// quantiles of the test face, the same levels for every face).
    #[arg(long = "iso-levels", default_value_t = 6)]
    pub iso_levels: usize,
    /// Standard deviations of the depth noise, mm (comma separated).
    #[arg(
        long = "noise-mm",
        value_delimiter = ',',
        default_value = "0.05,0.1,0.2"
    )]
    pub noise_mm: Vec<f64>,
    /// Noisy copies per standard deviation.
    #[arg(long = "noise-draws", default_value_t = 3)]
    pub noise_draws: usize,
    /// Seed of the noise and of the figure-15 rotations.
    #[arg(long, default_value_t = 2013)]
    pub seed: u64,
}

/// The four representations, in report order.
const REPS: [&str; 4] = ["bipolar", "single pole", "facial curves", "iso-curvature"];

/// Runs the task; prints the report folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let t_start = Instant::now();
    if args.set.res.levels < 2 || args.set.res.sectors < 3 || args.iso_levels == 0 {
        bail!("--levels must be >= 2, --sectors >= 3 and --iso-levels >= 1");
    }
    let (faces, test) = args.set.load()?;
    let out = args.set.out.out_dir("section6");
    let mut rep = Report::new(&out, "Section 6: the four representations side by side")?;
    let walkers: Vec<Walker<'_>> = faces.par_iter().map(|f| Walker::new(&f.mesh)).collect();
    let preps = par_map(&faces, "geodesic fields", |f| {
        FacePrep::new(f, geodesic::Method::Exact)
    });
    let preps = preps.into_iter().collect::<Result<Vec<_>>>()?;
    let failures = Failures::default();
    // Iso-curvature levels: quantiles of the test face's nose disc, the same for all faces.
    let tf = &faces[test];
    let tp = &preps[test];
    let iso_levels = reference_iso_levels(
        &Surface::new(tf.mesh.clone()),
        &tp.un,
        tp.refs.d,
        args.iso_levels,
    )
    .context("iso-curvature levels of the test face")?;
    let ctx = Ctx {
        args: &args,
        iso_levels,
        failures: &failures,
    };
    let base = describe_all(&ctx, &faces, &preps, &walkers);
    // Renders of the two curve representations on the test face.
    write::renders(&out, tf, &tp.refs.frame, &base[test])?;
    let set = Set {
        faces: &faces,
        preps: &preps,
        walkers: &walkers,
        base: &base,
        test,
        ctx: &ctx,
    };
    let between = measure::between_persons(&set)?;
    let (grid_cells, grid) = measure::reference_grid(&set)?;
    let mm = meshcore::units::detect_units(&tf.mesh)
        .map(|u| u.units.mm_per_unit())
        .unwrap_or(1.0);
    let (noise_cells, noise) = measure::depth_noise(&set, mm)?;
    let (fig15, fig15_rings) = measure::rotated_rings(&set, &between.mats[1])?;
    let results = write::Results {
        args: &args,
        faces: &faces,
        test,
        between: &between,
        grid_cells,
        grid,
        noise_cells,
        noise,
        fig15,
        fig15_rings,
        mm,
        failures: failures.summary().0,
        t_start,
    };
    write::write_report(&mut rep, &results)?;
    let n_png = rep.png_twins()?;
    let path = rep.finish()?;
    eprintln!("{n_png} PNG twins; report {}", path.display());
    println!("{}", out.display());
    Ok(())
}

/// The four descriptors of every face (nose-tip vertex as the single pole).
fn describe_all(
    ctx: &Ctx<'_>,
    faces: &[facemodel::Face],
    preps: &[FacePrep],
    walkers: &[Walker<'_>],
) -> Vec<Descs> {
    let ids: Vec<usize> = (0..faces.len()).collect();
    par_map(&ids, "descriptors", |&i| {
        let (f, p) = (&faces[i], &preps[i]);
        let nose = Pole::Vertex(f.landmarks.nose_tip);
        ctx.describe((&f.mesh, &walkers[i]), &p.refs, &p.un, nose, &f.name)
    })
}
