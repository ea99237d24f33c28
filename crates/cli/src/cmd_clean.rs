//! `bipolar clean`: scan preparation (`scanprep`): spikes, outliers, small components, small
//! holes, crop to a sphere, smoothing, decimation; units detected (or given) and printed.

use anyhow::{bail, Context};
use meshcore::units::Units;
use meshcore::DVec3;
use scanprep::{clean, CleanOptions, Crop, Input, SpikeOptions, DEFAULT_CROP_RADIUS_MM};
use std::path::PathBuf;

/// Arguments of `bipolar clean`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input: a range grid (`.bnt`) or a mesh (obj, ply, stl, off, gltf, glb).
    pub input: PathBuf,
    /// Output mesh (obj, ply, stl, off, glb), in mm.
    pub output: PathBuf,
    /// Units of the input (mm, cm, m); default: detected from the size of the face.
    #[arg(long)]
    pub units: Option<Units>,
    /// Crop to a sphere around this point `x,y,z` (input units and frame; e.g. the nose tip).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub crop_center: Option<String>,
    /// Radius of the crop sphere in mm (needs `--crop-center`).
    #[arg(long, value_name = "MM", default_value_t = DEFAULT_CROP_RADIUS_MM)]
    pub crop_radius: f64,
    /// Decimate to this target edge length in mm.
    #[arg(long, value_name = "MM")]
    pub target_edge: Option<f64>,
    /// Taubin smoothing iterations.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub smooth: usize,
    /// Fill holes up to this diameter in mm (0: fill none).
    #[arg(long, value_name = "MM", default_value_t = 10.0)]
    pub max_hole: f64,
    /// Spike threshold in grid spacings (grid input).
    #[arg(long, value_name = "SPACINGS", default_value_t = SpikeOptions::default().threshold_spacings)]
    pub spike_threshold: f64,
    /// Do not remove spikes and outliers.
    #[arg(long)]
    pub no_spikes: bool,
    /// Least coverage of the scanned silhouette by valid samples (grid input), 0 to 1.
    #[arg(long, default_value_t = 0.5)]
    pub min_coverage: f64,
    /// Print the time of each step.
    #[arg(long)]
    pub timings: bool,
}

/// Parses `x,y,z`.
fn parse_point(s: &str) -> anyhow::Result<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--crop-center {s:?}: expected x,y,z"))?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        bail!("--crop-center {s:?}: expected three finite numbers x,y,z");
    }
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let is_bnt = |p: &std::path::Path| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bnt"));
    if is_bnt(&args.output) {
        bail!(
            "{}: the cleaned scan is a mesh; write it as obj, ply, stl, off or glb",
            args.output.display()
        );
    }
    let spikes = (!args.no_spikes).then_some(SpikeOptions {
        threshold_spacings: args.spike_threshold,
        ..SpikeOptions::default()
    });
    let opts = CleanOptions {
        units: args.units,
        min_coverage: args.min_coverage,
        mesh_spike_factor: if args.no_spikes { None } else { Some(3.0) },
        spikes,
        max_hole_diameter_mm: (args.max_hole > 0.0).then_some(args.max_hole),
        crop: match &args.crop_center {
            Some(c) => Some(Crop {
                centre: parse_point(c)?,
                radius_mm: args.crop_radius,
            }),
            None => None,
        },
        smoothing_iterations: args.smooth,
        target_edge_mm: args.target_edge,
        ..CleanOptions::default()
    };
    let name = args.input.display().to_string();
    let cleaned = if is_bnt(&args.input) {
        let g =
            mesh_io::read_bnt_grid(&args.input).with_context(|| format!("cannot load {name}"))?;
        clean(Input::Grid(&g), &opts)
    } else {
        let m = crate::load::mesh(&args.input)?;
        clean(Input::Mesh(&m.mesh), &opts)
    }
    .with_context(|| format!("cleaning {name}"))?;
    for line in cleaned.report.summary() {
        println!("{line}");
    }
    if args.timings {
        for (step, t) in &cleaned.report.timings {
            println!("time {step:<12} {:.2} ms", t.as_secs_f64() * 1e3);
        }
    }
    mesh_io::write_mesh(&args.output, &mesh_io::LoadedMesh::new(cleaned.mesh))?;
    println!("wrote {} (mm)", args.output.display());
    Ok(())
}
