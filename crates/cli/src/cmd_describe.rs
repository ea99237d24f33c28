//! `bipolar describe`: the bipolar descriptor of a mesh, written as CSV, JSON or PLY.

use anyhow::{bail, Context};
use bipolar::{DescriptorOptions, LevelSpec, SelectionRule, Source, TangentMethod};
use geodesic::Method;
use glam::DVec3;
use meshcore::{FaceLocator, TriMesh};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bipolar describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh (any format mesh-io reads: OBJ, PLY, OFF, STL, glTF).
    pub mesh: PathBuf,
    /// First reference point: a vertex index or `X,Y,Z` (snapped to the nearest surface point).
    #[arg(long = "ref-a", allow_hyphen_values = true)]
    pub ref_a: String,
    /// Second reference point: a vertex index or `X,Y,Z`.
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
    #[arg(long, default_value = "isoangle")]
    pub rule: String,
    /// Tolerance of the filter rule (default alpha / (4 K)).
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Tangent method: gradient (exact per-face), strip (paper's method 1), spline (method 2).
    #[arg(long, default_value = "gradient")]
    pub tangent: String,
    /// Geodesic method: exact, fmm, heat or dijkstra.
    #[arg(long, default_value = "exact")]
    pub method: String,
    /// Output file: .csv, .json or .ply.
    #[arg(long)]
    pub out: PathBuf,
}

/// Parses a reference point: a vertex index, or `X,Y,Z` snapped to the nearest surface point.
///
/// A landmark name (`outer-eye-right`, `outer-eye-left`, ...) is detected with
/// `landmarks::detect` and the default generic face model.
pub fn parse_reference(spec: &str, mesh: &TriMesh) -> anyhow::Result<Source> {
    let s = spec.trim();
    if let Ok(v) = s.parse::<u32>() {
        if v as usize >= mesh.n_vertices() {
            bail!(
                "reference vertex {v} does not exist (the mesh has {} vertices)",
                mesh.n_vertices()
            );
        }
        return Ok(Source::Vertex(v));
    }
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() == 3 {
        let c: Result<Vec<f64>, _> = parts.iter().map(|p| p.parse::<f64>()).collect();
        if let Ok(c) = c {
            let p = DVec3::new(c[0], c[1], c[2]);
            if !p.is_finite() {
                bail!("reference point {spec:?} is not finite");
            }
            let (sp, _) = FaceLocator::new(mesh)
                .nearest(p)
                .with_context(|| format!("snapping {spec:?} to the mesh"))?;
            return Ok(Source::Point(sp));
        }
    }
    if let Some(name) = landmarks::LandmarkName::parse(s) {
        let model = landmarks::GenericModel::default_model()
            .context("loading the default generic face model")?;
        let found = landmarks::detect(mesh, &model)
            .with_context(|| format!("detecting the landmark {name} on the mesh"))?;
        let lm = found.get(name);
        eprintln!(
            "{name}: detected at vertex {} (confidence {:.2})",
            lm.vertex, lm.confidence
        );
        return Ok(Source::Vertex(lm.vertex));
    }
    bail!(
        "cannot read reference point {spec:?}: expected a vertex index, X,Y,Z or a landmark name \
         (outer-eye-right, outer-eye-left, inner-eye-right, inner-eye-left, nose-tip)"
    )
}

/// Builds descriptor options from the command line.
pub fn options(args: &Args) -> anyhow::Result<DescriptorOptions> {
    let levels = match (args.levels, args.step) {
        (_, Some(s)) => LevelSpec::Step(s),
        (Some(n), None) => LevelSpec::Count(n),
        (None, None) => LevelSpec::Count(10),
    };
    let rule = match args.rule.as_str() {
        "filter" => SelectionRule::Filter {
            tolerance: args
                .tolerance
                .unwrap_or(args.alpha / (4.0 * args.angles.max(1) as f64)),
        },
        "isoangle" | "iso-angle" => SelectionRule::IsoAngle,
        "all" => SelectionRule::All,
        o => bail!("unknown rule {o:?} (expected filter, isoangle or all)"),
    };
    let tangent: TangentMethod = args.tangent.parse().map_err(anyhow::Error::msg)?;
    Ok(DescriptorOptions {
        levels,
        max_level: args.max_level,
        angles: args.angles,
        alpha: args.alpha,
        rule,
        tangent,
        ..DescriptorOptions::default()
    })
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let opts = options(&args)?;
    let method: Method = args.method.parse()?;
    match args.out.extension().and_then(|e| e.to_str()) {
        Some("csv" | "json" | "ply") => {}
        _ => bail!(
            "output {} must end in .csv, .json or .ply",
            args.out.display()
        ),
    }
    let loaded = mesh_io::read_mesh(&args.mesh)
        .with_context(|| format!("reading {}", args.mesh.display()))?;
    let mesh = loaded.mesh;
    let mut refs = vec![
        parse_reference(&args.ref_a, &mesh).context("--ref-a")?,
        parse_reference(&args.ref_b, &mesh).context("--ref-b")?,
    ];
    for r in &args.more_refs {
        refs.push(parse_reference(r, &mesh).context("--ref")?);
    }
    let t0 = Instant::now();
    let solver = geodesic::new_solver(&mesh, method)
        .with_context(|| format!("preparing the {} geodesic solver", method.name()))?;
    let d = bipolar::describe(&mesh, solver.as_ref(), &refs, &opts)?;
    let elapsed = t0.elapsed();
    bipolar::io::write_auto(&args.out, &d)?;
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
