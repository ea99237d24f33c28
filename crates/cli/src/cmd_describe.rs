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
    /// Landmark file giving the reference points named in --ref-a/--ref-b/--ref (instead of
    /// detecting them): JSON written by `bipolar landmarks`, a flat `{name: [x, y, z]}` object,
    /// the ICT `landmarks.json` layout (the face named like the mesh file), or Bosphorus `.lm3`.
    /// Points are snapped to the nearest surface point, or taken as the file's vertex when it
    /// names one that sits at the given position.
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
}

/// A labelled point read from a landmark file, with the vertex the file names, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct GivenLandmark {
    /// Label as written in the file (`outer_eye_right`, `Outer right eye corner`, ...).
    pub label: String,
    /// Position (mesh units).
    pub position: DVec3,
    /// Vertex index given by the file (`bipolar landmarks` JSON, ICT `vertex_ids`).
    pub vertex: Option<u32>,
}

/// Reads the labelled points of a landmark file for the mesh `mesh_path` (see
/// [`Args::landmarks`]); for the ICT layout the face is the one named like the mesh file's stem.
pub fn read_given_landmarks(
    path: &std::path::Path,
    mesh_path: &std::path::Path,
) -> anyhow::Result<Vec<GivenLandmark>> {
    let shown = path.display();
    let is_lm3 = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("lm3"));
    if is_lm3 {
        let pts = landmarks::io::read_lm3(path)
            .with_context(|| format!("reading the landmark file {shown}"))?;
        return Ok(pts
            .into_iter()
            .map(|(label, position)| GivenLandmark {
                label,
                position,
                vertex: None,
            })
            .collect());
    }
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the landmark file {shown}"))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{shown}: not a JSON landmark file (nor .lm3)"))?;
    let vec3 = |x: &serde_json::Value, what: &str| -> anyhow::Result<DVec3> {
        let c: Vec<f64> = x
            .as_array()
            .map(|a| a.iter().filter_map(|c| c.as_f64()).collect())
            .unwrap_or_default();
        if c.len() != 3 || c.iter().any(|c| !c.is_finite()) {
            bail!("{shown}: {what}: expected [x, y, z] with finite numbers, got {x}");
        }
        Ok(DVec3::new(c[0], c[1], c[2]))
    };
    let mut out = Vec::new();
    if let Some(faces) = v.get("faces").and_then(|f| f.as_object()) {
        // ICT layout: {"vertex_ids": {name: id}, "faces": {face: {name: [x, y, z]}}}.
        let stem = mesh_path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default();
        let Some(face) = faces.get(stem).and_then(|f| f.as_object()) else {
            let names: Vec<&str> = faces.keys().map(String::as_str).collect();
            bail!(
                "{shown} has no face named {stem:?} (the mesh file's name); it has: {}",
                names.join(", ")
            );
        };
        let ids = v.get("vertex_ids").and_then(|i| i.as_object());
        for (label, p) in face {
            out.push(GivenLandmark {
                label: label.clone(),
                position: vec3(p, &format!("{stem}.{label}"))?,
                vertex: ids
                    .and_then(|i| i.get(label))
                    .and_then(|x| x.as_u64())
                    .and_then(|x| u32::try_from(x).ok()),
            });
        }
        return Ok(out);
    }
    // `bipolar landmarks` JSON ({"landmarks": {name: {"vertex", "position"}}}) or a flat object.
    let obj = v
        .get("landmarks")
        .and_then(|l| l.as_object())
        .or_else(|| v.as_object())
        .ok_or_else(|| anyhow::anyhow!("{shown}: expected a JSON object of landmarks"))?;
    for (label, x) in obj {
        let (position, vertex) = if let Some(p) = x.get("position") {
            (
                vec3(p, label)?,
                x.get("vertex")
                    .and_then(|i| i.as_u64())
                    .and_then(|i| u32::try_from(i).ok()),
            )
        } else if x.is_array() {
            (vec3(x, label)?, None)
        } else {
            continue;
        };
        out.push(GivenLandmark {
            label: label.clone(),
            position,
            vertex,
        });
    }
    if out.is_empty() {
        bail!("{shown}: no landmark positions found");
    }
    Ok(out)
}

/// The reference point named `spec` in a landmark file: labels match when they name the same
/// landmark in any spelling ([`landmarks::LandmarkName::parse`]: `outer-eye-right`,
/// `outer_eye_right`, `right_eye_outer`, `Outer right eye corner`) or are equal ignoring case.
/// The file's vertex is used when it exists and sits at the given position (within 1e-5 of the
/// mesh's bounding-box diagonal); otherwise the position is snapped to the nearest surface point.
pub fn given_reference(
    spec: &str,
    given: &[GivenLandmark],
    file: &std::path::Path,
    mesh: &TriMesh,
) -> anyhow::Result<Source> {
    let s = spec.trim();
    let want = landmarks::LandmarkName::parse(s);
    let found = given.iter().find(|g| {
        let l = g.label.trim();
        (want.is_some() && landmarks::LandmarkName::parse(l) == want) || l.eq_ignore_ascii_case(s)
    });
    let Some(g) = found else {
        let labels: Vec<&str> = given.iter().map(|g| g.label.as_str()).collect();
        bail!(
            "landmark {s:?} is not in {} (it has: {})",
            file.display(),
            labels.join(", ")
        );
    };
    let (lo, hi) = mesh.positions().iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let tol = 1e-5 * (hi - lo).length();
    if let Some(v) = g.vertex {
        if (v as usize) < mesh.n_vertices() && (mesh.position(v) - g.position).length() <= tol {
            eprintln!("{s}: vertex {v} from {}", file.display());
            return Ok(Source::Vertex(v));
        }
    }
    let (sp, _) = FaceLocator::new(mesh)
        .nearest(g.position)
        .with_context(|| format!("snapping {s:?} of {} to the mesh", file.display()))?;
    eprintln!(
        "{s}: {:?} from {} snapped to the surface",
        g.position.to_array(),
        file.display()
    );
    Ok(Source::Point(sp))
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
    let given = match &args.landmarks {
        Some(p) => Some(read_given_landmarks(p, &args.mesh)?),
        None => None,
    };
    // With --landmarks, names are looked up in the file; vertex indices and X,Y,Z still work.
    let reference = |spec: &str| -> anyhow::Result<Source> {
        match (&given, &args.landmarks) {
            (Some(g), Some(file))
                if spec.trim().parse::<u32>().is_err()
                    && spec
                        .split(',')
                        .filter(|c| c.trim().parse::<f64>().is_ok())
                        .count()
                        != 3 =>
            {
                given_reference(spec, g, file, &mesh)
            }
            _ => parse_reference(spec, &mesh),
        }
    };
    let mut refs = vec![
        reference(&args.ref_a).context("--ref-a")?,
        reference(&args.ref_b).context("--ref-b")?,
    ];
    for r in &args.more_refs {
        refs.push(reference(r).context("--ref")?);
    }
    let t0 = Instant::now();
    let solver = geodesic::new_solver(&mesh, method)
        .with_context(|| format!("preparing the {} geodesic solver", method.name()))?;
    let surface = bipolar::Surface::new(mesh);
    let d = bipolar::describe(
        &surface,
        bipolar::Fields::Solve {
            solver: solver.as_ref(),
            references: &refs,
        },
        &opts,
    )?;
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
