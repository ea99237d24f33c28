//! `cargo xtask scan-path`: wall time of each step of the whole path for one range scan: read
//! the `.bnt`, clean it (`scanprep::clean`, defaults), detect the landmarks
//! (`landmarks::detect_seen_from`, seen from +z), describe it (`bipolar::describe` with the
//! exact solver from the two detected outer eye corners, as `bipolar describe scan.bnt --ref-a outer-eye-right --ref-b
//! outer-eye-left` does). Without `--bnt` it scans the ICT neutral face (structured-light
//! artifacts) at `--pitch` and writes the scan into the output folder first.

use crate::paths::{default_model_dir, OutArgs};
use anyhow::{bail, Context, Result};
use facemodel::FaceModel;
use landmarks::GenericModel;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Arguments of `cargo xtask scan-path`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// A range scan to time (default: a scan of the ICT neutral face made here).
    #[arg(long)]
    pub bnt: Option<PathBuf>,
    /// Sample pitch of the scan made without `--bnt`, mm (0.75 mm gives about 36k valid
    /// samples).
    #[arg(long, default_value_t = 0.75)]
    pub pitch: f64,
    /// Runs of the whole path; the median of each step is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Region of the descriptor: levels `1..=max_level` of both fields (default: as far as the
    /// fields go, as `bipolar describe` without `--max-level`).
    #[arg(long)]
    pub max_level: Option<u32>,
    /// Band (mesh units) along the holes and the border that the descriptor leaves out
    /// (`bipolar describe --boundary-margin`; default none). Its cost lands in the step
    /// "descriptor from the fields".
    #[arg(long)]
    pub boundary_margin: Option<f64>,
    /// Output folder.
    #[command(flatten)]
    pub out: OutArgs,
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v.get(v.len() / 2).copied().unwrap_or_default()
}

/// Runs the timing; prints the output folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let out = args.out.out_dir("scan-path");
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let bnt = match args.bnt {
        Some(p) => p,
        None => {
            let model_dir = default_model_dir();
            let model = FaceModel::load(&model_dir)
                .with_context(|| format!("loading the ICT model from {}", model_dir.display()))?;
            let face = model.neutral()?;
            let scan = rangescan::scan(
                &face,
                &rangescan::ScanOptions {
                    input_mm_per_unit: 10.0,
                    pitch_mm: args.pitch,
                    artifacts: rangescan::Artifacts::structured_light(),
                    seed: 1,
                    ..rangescan::ScanOptions::default()
                },
            )?;
            let p = out.join("scan.bnt");
            mesh_io::write_bnt(&p, &scan.grid)?;
            p
        }
    };
    let generic = GenericModel::default_model()?;
    let opts = bipolar::DescriptorOptions {
        max_level: args.max_level,
        boundary_margin: args.boundary_margin,
        ..bipolar::DescriptorOptions::default()
    };
    let steps = [
        "read .bnt",
        "clean",
        "detect landmarks",
        "prepare the exact solver",
        "topology (Surface::new)",
        "two exact fields (parallel)",
        "descriptor from the fields",
    ];
    let mut times: Vec<Vec<Duration>> = vec![Vec::new(); steps.len() + 1];
    let mut info = String::new();
    for run in 0..args.repeats.max(1) {
        let mut t = vec![Instant::now()];
        let grid = mesh_io::read_bnt_grid(&bnt)?;
        t.push(Instant::now());
        let cleaned = scanprep::clean(
            scanprep::Input::Grid(&grid),
            &scanprep::CleanOptions::default(),
        )?;
        t.push(Instant::now());
        // As `bipolar landmarks` reads a `.bnt`: units from the face size, seen from +z.
        let lm =
            landmarks::detect_seen_from(&cleaned.mesh, &generic, Some(crate::scans::SCANNER_SIDE))?
                .complete()?;
        t.push(Instant::now());
        let n_vertices = cleaned.mesh.n_vertices();
        let solver = geodesic::new_solver(&cleaned.mesh, geodesic::Method::Exact)?;
        t.push(Instant::now());
        let surface = bipolar::Surface::new(cleaned.mesh);
        t.push(Instant::now());
        let references = [
            geodesic::Source::Vertex(lm.outer_eye_right.vertex),
            geodesic::Source::Vertex(lm.outer_eye_left.vertex),
        ];
        // The fields as `bipolar::describe` solves them (in parallel, cut off past the region
        // when there is one), timed apart from the rest of the descriptor.
        let fields = bipolar::solve_fields(&surface, solver.as_ref(), &references, &opts)?;
        t.push(Instant::now());
        let d = bipolar::describe(
            &surface,
            bipolar::Fields::Precomputed {
                fields: &fields,
                references: Some(&references),
            },
            &opts,
        )?;
        t.push(Instant::now());
        let n = t.len() - 1;
        for k in 0..n {
            times[k].push(t[k + 1] - t[k]);
        }
        times[n].push(t[n] - t[0]);
        if run == 0 {
            // The split must not change the result: the same descriptor as in one call.
            let whole = bipolar::describe(
                &surface,
                bipolar::Fields::Solve {
                    solver: solver.as_ref(),
                    references: &references,
                },
                &opts,
            )?;
            if whole.points != d.points {
                bail!("the descriptor from the timed fields differs from describe's own");
            }
            let valid = (0..grid.xyz.len()).filter(|&i| grid.is_valid(i)).count();
            info = format!(
                "{}: {} x {} grid, {valid} valid samples; cleaned mesh {} vertices; landmarks at vertices {:?}; descriptor {} points ({} ambiguous), fingerprint {:016x}",
                bnt.display(),
                grid.nrows,
                grid.ncols,
                n_vertices,
                [
                    lm.outer_eye_right.vertex,
                    lm.inner_eye_right.vertex,
                    lm.inner_eye_left.vertex,
                    lm.outer_eye_left.vertex,
                    lm.nose_tip.vertex
                ],
                d.points.len(),
                d.stats.ambiguous,
                d.fingerprint()
            );
        }
        eprintln!("run {}: {:.3} s", run + 1, (t[n] - t[0]).as_secs_f64());
    }
    println!("{info}");
    println!(
        "median of {} runs (wall, release, rayon on every core):",
        args.repeats.max(1)
    );
    let mut md = format!("{info}\n\n| step | median wall time |\n|---|---|\n");
    for (k, name) in steps
        .iter()
        .chain(std::iter::once(&"whole path"))
        .enumerate()
    {
        let m = median(times[k].clone());
        println!("  {name:<30} {:>8.1} ms", m.as_secs_f64() * 1e3);
        md += &format!("| {name} | {:.1} ms |\n", m.as_secs_f64() * 1e3);
    }
    std::fs::write(out.join("report.md"), md)?;
    println!("{}", out.display());
    Ok(())
}
