//! `bipolar describe`: the bipolar descriptor of a mesh, written as CSV, JSON or PLY.

use crate::choice::{choice, from_extension};
use crate::refpoint::{RefArgs, Resolver};
use crate::searchfiles::search_path;
use anyhow::Context;
use bipolar::{DescriptorOptions, LevelSpec, SelectionKind, TangentMethod};
use geodesic::Method;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bipolar describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh (any format mesh-io reads: OBJ, PLY, OFF, STL, glTF).
    pub mesh: PathBuf,
    /// First reference point: a vertex index, `X,Y,Z` (snapped to the nearest surface point,
    /// within --snap-tolerance) or a landmark name (from --landmarks, or detected).
    #[arg(long = "ref-a", allow_hyphen_values = true)]
    pub ref_a: String,
    /// Second reference point: a vertex index, `X,Y,Z` or a landmark name.
    #[arg(long = "ref-b", allow_hyphen_values = true)]
    pub ref_b: String,
    /// Further reference points (every pair contributes; keys carry the pair).
    #[arg(long = "ref", allow_hyphen_values = true)]
    pub more_refs: Vec<String>,
    /// Number of levels between the first two reference points (step = d(a, b) / N).
    #[arg(long, conflicts_with = "step")]
    pub levels: Option<u32>,
    /// Geodesic step in mesh units (instead of --levels).
    #[arg(long)]
    pub step: Option<f64>,
    /// Highest level kept for both fields (region); default: as far as the fields go.
    #[arg(long = "max-level")]
    pub max_level: Option<u32>,
    /// Number of angle levels K (targets alpha k / K).
    #[arg(long = "angles", default_value_t = 8)]
    pub angles: u32,
    /// Maximum angular opening alpha in (0, 1].
    #[arg(long, default_value_t = 0.95)]
    pub alpha: f64,
    /// Selection rule: filter (grid intersections within a tolerance of an angle level),
    /// isoangle (exact iso-angle points along the first field's curves) or all.
    #[arg(long, default_value = "isoangle", value_parser = choice::<SelectionKind>())]
    pub rule: SelectionKind,
    /// Tolerance of the filter rule (default alpha / (4 K)).
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Tangent method: gradient (exact per-face), strip (paper's method 1), spline (method 2).
    #[arg(long, default_value = "gradient", value_parser = choice::<TangentMethod>())]
    pub tangent: TangentMethod,
    /// Geodesic method: exact, fmm, heat or dijkstra.
    #[arg(long, default_value = "exact", value_parser = choice::<Method>())]
    pub method: Method,
    /// Leave out the band within this geodesic distance (mesh units) of the mesh boundary:
    /// holes, eye openings, a scan's border (on scans in mm, 6 is the benchmark's choice).
    #[arg(long = "boundary-margin")]
    pub boundary_margin: Option<f64>,
    /// Leave out what a range scanner saw at more than this incidence (degrees), for a scan in
    /// the scanner's frame looking along -z (`.bnt` files, `bipolar scan`): grazing parts, where
    /// depth noise runs along the surface (60 is the scan benchmark's choice).
    #[arg(long = "max-incidence", value_name = "DEG")]
    pub max_incidence: Option<f64>,
    /// Reference-point search (mesh units): also describe the mesh from the two references
    /// moved by this distance in --search-directions directions of their tangent planes (the
    /// first toward the other reference; up to 48 more descriptors, `bipolar::describe_searched`),
    /// written beside --out as `STEM.search-NN.EXT` (earlier such files past the last one
    /// written are removed). `bipolar distance --searched` and `bipolar matrix --searched`
    /// compare faces by the least distance over them.
    #[arg(long = "search-radius")]
    pub search_radius: Option<f64>,
    /// Directions of the reference-point search around each reference.
    #[arg(
        long = "search-directions",
        default_value_t = 6,
        requires = "search_radius"
    )]
    pub search_directions: usize,
    /// Output file: .csv, .json or .ply.
    #[arg(long)]
    pub out: PathBuf,
    /// How reference points are read (landmark file, snapping tolerance).
    #[command(flatten)]
    pub refs: RefArgs,
}

/// Builds descriptor options from the command line.
pub fn options(args: &Args) -> anyhow::Result<DescriptorOptions> {
    let levels = match (args.levels, args.step) {
        (_, Some(s)) => LevelSpec::Step(s),
        (Some(n), None) => LevelSpec::Count(n),
        (None, None) => LevelSpec::Count(10),
    };
    let rule = args.rule.rule(
        args.tolerance
            .unwrap_or(args.alpha / (4.0 * args.angles.max(1) as f64)),
    );
    Ok(DescriptorOptions {
        levels,
        max_level: args.max_level,
        angles: args.angles,
        alpha: args.alpha,
        rule,
        tangent: args.tangent,
        boundary_margin: args.boundary_margin,
        ..DescriptorOptions::default()
    })
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut opts = options(&args)?;
    let method = args.method;
    let _: bipolar::io::Format = from_extension(&args.out)?;
    let loaded = crate::load::mesh(&args.mesh)?;
    let mesh = loaded.mesh;
    let resolver = Resolver::new(&mesh, &args.mesh, &args.refs)?;
    let mut refs = vec![
        resolver.resolve(&args.ref_a, "--ref-a")?.source,
        resolver.resolve(&args.ref_b, "--ref-b")?.source,
    ];
    for r in &args.more_refs {
        refs.push(resolver.resolve(r, "--ref")?.source);
    }
    let t0 = Instant::now();
    if let Some(deg) = args.max_incidence {
        opts.vertex_mask = Some(
            scanprep::incidence_mask(&mesh, meshcore::DVec3::Z, deg).context("--max-incidence")?,
        );
    }
    let solver = geodesic::new_solver(&mesh, method)
        .with_context(|| format!("preparing the {} geodesic solver", method.name()))?;
    let surface = bipolar::Surface::new(mesh);
    let all = match args.search_radius {
        Some(r) => bipolar::describe_searched(
            &surface,
            solver.as_ref(),
            &refs,
            r,
            args.search_directions,
            &opts,
        )
        .context("--search-radius")?,
        None => vec![bipolar::describe(
            &surface,
            bipolar::Fields::Solve {
                solver: solver.as_ref(),
                references: &refs,
            },
            &opts,
        )?],
    };
    let elapsed = t0.elapsed();
    let mut all = all.into_iter();
    let d = all
        .next()
        .context("the descriptor of the references was not built")?;
    let moved: Vec<bipolar::Descriptor> = all.collect();
    bipolar::io::write_auto(&args.out, &d)?;
    for (k, m) in moved.iter().enumerate() {
        bipolar::io::write_auto(&search_path(&args.out, k + 1), m)?;
    }
    let stale = crate::searchfiles::remove_stale(&args.out, moved.len())?;
    if stale > 0 {
        eprintln!(
            "removed {stale} search files of an earlier describe to {} (STEM.search-NN.EXT numbered past this one's {})",
            args.out.display(),
            moved.len()
        );
    }
    if !moved.is_empty() {
        eprintln!(
            "{} descriptors of the reference-point search: {} ...",
            moved.len(),
            search_path(&args.out, 1).display()
        );
    }
    let n_amb = d.points.iter().filter(|p| p.ambiguous).count();
    eprintln!(
        "{} points ({} ambiguous) from {} intersections; step {:.6}, levels 1..={}, d(a,b) = {:.6}; {} geodesics; {:.1} ms; wrote {}",
        d.len(),
        n_amb,
        d.stats.intersections,
        d.step,
        d.max_level,
        d.reference_distance,
        method.name(),
        elapsed.as_secs_f64() * 1e3,
        args.out.display()
    );
    if d.stats.tangent_fallbacks > 0 {
        eprintln!(
            "note: {} tangents fell back to the gradient method (strip too small or spline piece too short)",
            d.stats.tangent_fallbacks
        );
    }
    Ok(())
}
