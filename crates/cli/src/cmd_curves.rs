//! `bipolar curves` and `bipolar curve-distance`: the section-6 curve representations of a
//! mesh (iso-curvature curves, facial curves) as JSON curve files, and the distance of two
//! such files. Both only call `facecurves`.

use crate::choice::choice;
use crate::refpoint::{RefArgs, Resolver};
use anyhow::{bail, Context};
use facecurves::io::{read_json, write_json, CurveSet};
use facecurves::{
    Aggregate, ElasticOptions, FacialCurvesOptions, IsoCurvatureOptions, IsoLevels, Resampling,
};
use geodesic::{Method, SolveOptions};
use meshcore::Surface;
use std::path::PathBuf;
use std::time::Instant;

meshcore::choice! {
    /// Which representation `bipolar curves` computes.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Kind: "curve kind", meshcore::UnknownChoice {
        /// Level sets of the principal curvature fields.
        IsoCurvature = "iso-curvature" | "isocurvature",
        /// Level curves of the geodesic distance from the nose tip.
        Facial = "facial",
    }
}

/// Arguments of `bipolar curves`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh (OBJ, PLY, STL, OFF, glTF/GLB, BNT).
    pub mesh: PathBuf,
    /// Representation: iso-curvature (level sets of the principal curvatures) or facial
    /// (level curves of the geodesic distance from the nose tip).
    #[arg(long, value_parser = choice::<Kind>())]
    pub kind: Kind,
    /// Centre: the nose tip for facial curves; for iso-curvature curves, the centre of the
    /// region kept with --radius. A vertex index, `X,Y,Z` or a landmark name.
    #[arg(
        long,
        value_name = "REF",
        default_value = "nose_tip",
        allow_hyphen_values = true
    )]
    pub nose: String,
    /// Geodesic radius (mesh units) of the outermost facial curve; for iso-curvature curves,
    /// keep only the vertices within this geodesic distance of --nose (whole mesh without it).
    #[arg(long, value_name = "R")]
    pub radius: Option<f64>,
    /// Facial curves: number of curves (step = radius / levels). Iso-curvature: levels per
    /// principal field, uniform between the 5 % and 95 % quantiles.
    #[arg(long, default_value_t = 8)]
    pub levels: u32,
    /// Iso-curvature: explicit levels of k1 (1 / mesh units), comma-separated; overrides
    /// --levels for k1 (give --k2-levels too, or k2 gets none).
    #[arg(
        long = "k1-levels",
        value_name = "K,...",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub k1_levels: Vec<f64>,
    /// Iso-curvature: explicit levels of k2, comma-separated.
    #[arg(
        long = "k2-levels",
        value_name = "K,...",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub k2_levels: Vec<f64>,
    /// Iso-curvature: radius of the curvature fits, in mean edge lengths.
    #[arg(long = "curvature-radius", value_name = "EDGES", default_value_t = 3.0)]
    pub curvature_radius: f64,
    /// Geodesic method for the distance from --nose.
    #[arg(long, default_value = "exact", value_parser = choice::<Method>())]
    pub method: Method,
    /// How --nose is read (landmark file, snapping tolerance).
    #[command(flatten)]
    pub refs: RefArgs,
    /// Output curve file (JSON).
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `bipolar curves`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let loaded = crate::load::mesh(&args.mesh)?;
    let mesh = loaded.mesh;
    let t0 = Instant::now();
    let needs_field = args.kind == Kind::Facial || args.radius.is_some();
    let field = if needs_field {
        let radius = match args.radius {
            Some(r) if r.is_finite() && r > 0.0 => r,
            Some(r) => bail!("--radius must be positive and finite, got {r}"),
            None => {
                bail!("facial curves need --radius (the geodesic radius of the outermost curve)")
            }
        };
        let resolver = Resolver::new(&mesh, &args.mesh, &args.refs)?;
        let nose = resolver.resolve(&args.nose, "--nose")?;
        let solver = geodesic::new_solver(&mesh, args.method)
            .with_context(|| format!("preparing the {} solver", args.method.name()))?;
        let longest = mesh.longest_edge();
        Some((
            radius,
            solver
                .distances(
                    &[nose.source],
                    &SolveOptions {
                        max_distance: Some(radius + longest),
                    },
                )
                .context("distance from --nose")?,
        ))
    } else {
        None
    };
    let surface = Surface::new(mesh);
    let set = match args.kind {
        Kind::Facial => {
            let Some((radius, u)) = field.as_ref() else {
                bail!("facial curves need --radius");
            };
            if args.levels == 0 {
                bail!("--levels must be at least 1");
            }
            let opts = FacialCurvesOptions {
                step: *radius / f64::from(args.levels),
                levels: args.levels,
            };
            CurveSet::Facial(
                facecurves::describe_facial_curves(&surface, u, &opts).context("facial curves")?,
            )
        }
        Kind::IsoCurvature => {
            let levels = if args.k1_levels.is_empty() && args.k2_levels.is_empty() {
                IsoLevels::Quantiles {
                    count: args.levels as usize,
                    low: 0.05,
                    high: 0.95,
                }
            } else {
                IsoLevels::Explicit {
                    k1: args.k1_levels.clone(),
                    k2: args.k2_levels.clone(),
                }
            };
            let opts = IsoCurvatureOptions {
                radius_edges: args.curvature_radius,
                levels,
                ..Default::default()
            };
            let mask: Option<Vec<bool>> = field
                .as_ref()
                .map(|(r, u)| u.iter().map(|d| d <= r).collect());
            CurveSet::IsoCurvature(
                facecurves::describe_iso_curvature(&surface, mask.as_deref(), &opts)
                    .context("iso-curvature curves")?,
            )
        }
    };
    write_json(&args.out, &set)?;
    let (n, pts) = match &set {
        CurveSet::Facial(d) => (
            d.curves.len(),
            d.curves.iter().map(|c| c.points.len()).sum::<usize>(),
        ),
        CurveSet::IsoCurvature(d) => (
            d.curves.len(),
            d.curves.iter().map(|c| c.points.len()).sum(),
        ),
    };
    eprintln!(
        "{}: {n} curves, {pts} points, {:.3} s -> {}",
        args.kind,
        t0.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

/// Arguments of `bipolar curve-distance`.
#[derive(Debug, clap::Args)]
pub struct DistanceArgs {
    /// First curve file (written by `bipolar curves`).
    pub a: PathBuf,
    /// Second curve file, of the same kind.
    pub b: PathBuf,
    /// Facial curves: how per-curve distances combine (rss: root of the sum of squares; sum).
    #[arg(long, default_value = "rss", value_parser = choice::<Aggregate>())]
    pub aggregate: Aggregate,
    /// Facial curves: segments of the resampled curves.
    #[arg(long, default_value_t = 100)]
    pub samples: usize,
    /// Facial curves: scale every curve to unit length first.
    #[arg(long)]
    pub scale: bool,
    /// Facial curves: resampling (arc-length or parameter).
    #[arg(long, default_value = "arc-length", value_parser = choice::<Resampling>())]
    pub resampling: Resampling,
    /// Print the per-curve distances too.
    #[arg(long)]
    pub verbose: bool,
}

/// Runs `bipolar curve-distance`: prints the distance on stdout.
pub fn run_distance(args: DistanceArgs) -> anyhow::Result<()> {
    let a = read_json(&args.a)?;
    let b = read_json(&args.b)?;
    let t0 = Instant::now();
    match (&a, &b) {
        (CurveSet::Facial(x), CurveSet::Facial(y)) => {
            let opts = ElasticOptions {
                samples: args.samples,
                scale: args.scale,
                resampling: args.resampling,
                ..Default::default()
            };
            let d = facecurves::facial_curves_distance(x, y, args.aggregate, &opts)?;
            if args.verbose {
                for (level, m) in &d.per_curve {
                    eprintln!("level {level}: {}", m.distance);
                }
                eprintln!(
                    "{} curves compared, {} unmatched, {:.3} s",
                    d.per_curve.len(),
                    d.unmatched,
                    t0.elapsed().as_secs_f64()
                );
            }
            println!("{}", d.distance);
        }
        (CurveSet::IsoCurvature(x), CurveSet::IsoCurvature(y)) => {
            let d = facecurves::iso_curvature_distance(x, y, &Default::default())?;
            if args.verbose {
                eprintln!(
                    "hausdorff {} (normalised {}), mean {}, {:.3} s",
                    d.stats.hausdorff,
                    d.stats.hausdorff_normalised,
                    d.stats.mean,
                    t0.elapsed().as_secs_f64()
                );
            }
            println!("{}", d.stats.rms_normalised);
        }
        _ => bail!(
            "{} and {} hold different curve kinds",
            args.a.display(),
            args.b.display()
        ),
    }
    Ok(())
}
