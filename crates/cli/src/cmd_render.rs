//! `bipolar render`: a picture of a mesh with level curves and descriptor points.
//!
//! The mesh is drawn shaded from an orthographic view fitted to the scene (`.svg` or `.png`),
//! or written with the same curves and points as a 3D scene (`.glb`). Optional layers:
//!
//! * `--field FILE`: one value per vertex (`.txt` one per line, `.csv` the last column, a
//!   non-numeric first line is a header; `inf`/`nan` allowed) colours the mesh (viridis,
//!   non-finite grey); with `--curves N` and no reference points, N level curves of it at
//!   equally spaced levels strictly between its finite minimum and maximum;
//! * `--ref-a A --ref-b B` (vertex index or `X,Y,Z` snapped to the surface): geodesic fields of
//!   both (solver `--method`), drawn as markers; with `--curves N` the level curves of both
//!   fields at the constant step `d(A, B) / N` (red for A, blue for B), as in the paper's
//!   figures;
//! * `--descriptor FILE` (`.csv` or `.json` from `bipolar describe`): its points as orange discs
//!   (and, for JSON, its reference points).
//!
//! Curves and points hidden by the surface are not drawn.

use crate::choice::choice;
use crate::refpoint::{RefArgs, Resolver};
use anyhow::{bail, Context};
use geodesic::{Method, SolveOptions, Source};
use glam::DVec3;
use meshcore::{Choice, Topology, TriMesh};
use std::path::{Path, PathBuf};
use viz::{Marker, Polyline, Scene, View};

/// Arguments of `bipolar render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh (any format `bipolar convert` reads).
    pub mesh: PathBuf,
    /// Descriptor file (`.csv` or `.json`) whose points are drawn.
    #[arg(long, value_name = "FILE")]
    pub descriptor: Option<PathBuf>,
    /// Per-vertex scalar field (`.txt` or `.csv`) colouring the mesh.
    #[arg(long, value_name = "FILE")]
    pub field: Option<PathBuf>,
    /// Number of level curves: geodesic levels between the reference points (with
    /// `--ref-a/--ref-b`) or equally spaced levels of `--field`.
    #[arg(long, value_name = "N")]
    pub curves: Option<u32>,
    /// First reference point: vertex index, `X,Y,Z` (within --snap-tolerance of the surface)
    /// or a landmark name (from --landmarks, or detected).
    #[arg(long = "ref-a", value_name = "A", allow_hyphen_values = true)]
    pub ref_a: Option<String>,
    /// Second reference point: vertex index, `X,Y,Z` or a landmark name.
    #[arg(long = "ref-b", value_name = "B", allow_hyphen_values = true)]
    pub ref_b: Option<String>,
    /// How reference points are read (landmark file, snapping tolerance).
    #[command(flatten)]
    pub refs: RefArgs,
    /// Geodesic method for the reference fields: exact, fmm, heat or dijkstra.
    #[arg(long, default_value = "exact", value_parser = choice::<Method>())]
    pub method: Method,
    /// View: front, back, left, right, top, or a viewing direction `X,Y,Z` (eye to scene).
    #[arg(long, default_value = "front", value_parser = parse_view, allow_hyphen_values = true)]
    pub view: View,
    /// Picture width in pixels.
    #[arg(long, default_value_t = 800)]
    pub width: u32,
    /// Picture height in pixels.
    #[arg(long, default_value_t = 800)]
    pub height: u32,
    /// Line width of the level curves in pixels.
    #[arg(long = "line-width", default_value_t = 1.5)]
    pub line_width: f64,
    /// Radius of the descriptor points in pixels.
    #[arg(long = "point-radius", default_value_t = 3.0)]
    pub point_radius: f64,
    /// Output picture: `.svg`, `.png` or `.glb`.
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_view(s: &str) -> Result<View, String> {
    View::parse(s).map_err(|e| e.to_string())
}

const COLOR_A: [u8; 3] = [215, 40, 40];
const COLOR_B: [u8; 3] = [30, 90, 220];
const COLOR_POINT: [u8; 3] = [255, 150, 0];
/// Safety cap on the number of levels drawn per field.
const MAX_LEVELS: usize = 1000;

meshcore::choice! {
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum OutKind: "picture", meshcore::UnknownChoice {
        Picture = "svg" | "png",
        Glb = "glb",
    }
}

fn out_kind(path: &Path) -> anyhow::Result<OutKind> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    OutKind::from_name(ext).map_err(|_| {
        anyhow::anyhow!(
            "unknown output extension {ext:?} of {}: expected .svg, .png or .glb",
            path.display()
        )
    })
}

/// Reads one value per vertex from a `.txt` or `.csv` file.
fn read_field(path: &Path, n: usize) -> anyhow::Result<Vec<f64>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut values = Vec::with_capacity(n);
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let last = line.rsplit([',', ' ', '\t']).next().unwrap_or("").trim();
        match last.parse::<f64>() {
            Ok(v) => values.push(v),
            Err(_) if values.is_empty() && i == 0 => {} // header
            Err(_) => bail!(
                "{}: line {}: {last:?} is not a number",
                path.display(),
                i + 1
            ),
        }
    }
    if values.len() != n {
        bail!(
            "{}: {} values for a mesh of {n} vertices",
            path.display(),
            values.len()
        );
    }
    Ok(values)
}

/// Field value at a source: the vertex's value, or [`TriMesh::interpolate`] at a point.
fn value_at(mesh: &TriMesh, field: &[f64], src: &Source) -> anyhow::Result<f64> {
    Ok(match src {
        Source::Vertex(v) => field[*v as usize],
        Source::Point(sp) => mesh.interpolate(field, sp)?,
    })
}

fn curves_of(
    mesh: &TriMesh,
    topo: &Topology,
    field: &[f64],
    levels: &[f64],
    color: [u8; 3],
    width: f64,
) -> anyhow::Result<Vec<Polyline>> {
    let iso =
        levelcurves::isolines(mesh, topo, field, levels).context("extracting level curves")?;
    Ok(iso
        .into_iter()
        .flatten()
        .filter(|c| c.points.len() >= 2)
        .map(|c| Polyline {
            points: c.points,
            closed: c.closed,
            color,
            width,
        })
        .collect())
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let kind = out_kind(&args.out)?;
    if !(args.line_width.is_finite() && args.line_width > 0.0) {
        bail!("--line-width must be positive");
    }
    if !(args.point_radius.is_finite() && args.point_radius > 0.0) {
        bail!("--point-radius must be positive");
    }
    let loaded = crate::load::mesh(&args.mesh)?;
    let mesh = loaded.mesh;
    let mut scene = Scene::new(&mesh);
    let mut topo: Option<Topology> = None;

    let field = match &args.field {
        Some(p) => Some(read_field(p, mesh.n_vertices())?),
        None => None,
    };
    if let Some(f) = &field {
        scene.vertex_colors = Some(viz::colormap::field_colors(f));
    }

    match (&args.ref_a, &args.ref_b) {
        (Some(a), Some(b)) => {
            let resolver = Resolver::new(&mesh, &args.mesh, &args.refs)?;
            let ra = resolver.resolve(a, "--ref-a")?;
            let rb = resolver.resolve(b, "--ref-b")?;
            let (src_a, pos_a, src_b, pos_b) = (ra.source, ra.position, rb.source, rb.position);
            if pos_a.distance(pos_b) <= 1e-12 * mesh.bbox().diagonal() {
                bail!("--ref-a and --ref-b are the same point");
            }
            scene.points.push(Marker {
                position: pos_a,
                color: COLOR_A,
                radius: args.point_radius * 2.0,
            });
            scene.points.push(Marker {
                position: pos_b,
                color: COLOR_B,
                radius: args.point_radius * 2.0,
            });
            if let Some(n) = args.curves {
                if n == 0 {
                    bail!("--curves must be at least 1");
                }
                let solver = geodesic::new_solver(&mesh, args.method)
                    .with_context(|| format!("preparing the {} solver", args.method.name()))?;
                let opts = SolveOptions { max_distance: None };
                let da = solver
                    .distances(&[src_a], &opts)
                    .context("geodesic field of --ref-a")?;
                let db = solver
                    .distances(&[src_b], &opts)
                    .context("geodesic field of --ref-b")?;
                let d_ab = value_at(&mesh, &da, &src_b).context("--ref-b")?;
                if !(d_ab.is_finite() && d_ab > 0.0) {
                    bail!("the reference points are not connected on the surface (geodesic distance {d_ab})");
                }
                let step = d_ab / n as f64;
                let t = topo.get_or_insert_with(|| Topology::new(&mesh));
                for (d, color) in [(&da, COLOR_A), (&db, COLOR_B)] {
                    let max = d
                        .iter()
                        .copied()
                        .filter(|x| x.is_finite())
                        .fold(0.0, f64::max);
                    let k = ((max / step).floor() as usize).min(MAX_LEVELS);
                    let levels: Vec<f64> = (1..=k).map(|i| i as f64 * step).collect();
                    scene.polylines.extend(curves_of(
                        &mesh,
                        t,
                        d,
                        &levels,
                        color,
                        args.line_width,
                    )?);
                }
            }
        }
        (None, None) => {
            if let Some(n) = args.curves {
                let Some(f) = &field else {
                    bail!("--curves needs --field or --ref-a/--ref-b");
                };
                let Some((lo, hi)) = viz::colormap::finite_range(f) else {
                    bail!("the field has no finite value");
                };
                if n == 0 {
                    bail!("--curves must be at least 1");
                }
                let n = (n as usize).min(MAX_LEVELS);
                let levels: Vec<f64> = (1..=n)
                    .map(|k| lo + (hi - lo) * k as f64 / (n + 1) as f64)
                    .collect();
                let t = topo.get_or_insert_with(|| Topology::new(&mesh));
                scene.polylines.extend(curves_of(
                    &mesh,
                    t,
                    f,
                    &levels,
                    [20, 20, 20],
                    args.line_width,
                )?);
            }
        }
        _ => bail!("--ref-a and --ref-b must be given together"),
    }

    if let Some(p) = &args.descriptor {
        let d = bipolar::io::read_auto(p).with_context(|| format!("reading {}", p.display()))?;
        for r in &d.references {
            scene.points.push(Marker {
                position: *r,
                color: [40, 40, 40],
                radius: args.point_radius * 2.0,
            });
        }
        for pt in &d.points {
            scene.points.push(Marker {
                position: pt.position,
                color: COLOR_POINT,
                radius: args.point_radius,
            });
        }
    }

    match kind {
        OutKind::Picture => {
            viz::render_to_file(&args.out, &scene, &args.view, args.width, args.height)
                .with_context(|| format!("writing {}", args.out.display()))?;
        }
        OutKind::Glb => write_glb(&args.out, &scene)?,
    }
    eprintln!(
        "wrote {} ({} curves, {} points)",
        args.out.display(),
        scene.polylines.len(),
        scene.points.len()
    );
    Ok(())
}

fn rgba(c: [u8; 3]) -> [u8; 4] {
    [c[0], c[1], c[2], 255]
}

fn write_glb(path: &Path, scene: &Scene) -> anyhow::Result<()> {
    let mut g = mesh_io::GltfScene::default();
    let colors = scene
        .vertex_colors
        .as_ref()
        .map(|c| c.iter().map(|&x| rgba(x)).collect());
    g.add_mesh("mesh", scene.mesh, colors);
    for (i, pl) in scene.polylines.iter().enumerate() {
        let mode = if pl.closed {
            mesh_io::LineMode::Loop
        } else {
            mesh_io::LineMode::Strip
        };
        g.add_polyline(&format!("curve_{i}"), &pl.points, mode, rgba(pl.color));
    }
    // One point set per colour, in order of first appearance.
    let mut groups: Vec<([u8; 3], Vec<DVec3>)> = Vec::new();
    for m in &scene.points {
        match groups.iter_mut().find(|(c, _)| *c == m.color) {
            Some((_, v)) => v.push(m.position),
            None => groups.push((m.color, vec![m.position])),
        }
    }
    for (i, (c, pts)) in groups.iter().enumerate() {
        g.add_points(&format!("points_{i}"), pts, rgba(*c));
    }
    mesh_io::write_glb(path, &g).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
