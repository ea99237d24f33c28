//! `cargo xtask sphere-validate`: the paper's section 3 experiment.
//!
//! Unit sphere meshes (icospheres and UV spheres at several resolutions), two orthogonal poles
//! `r = +Z`, `q = +X`, geodesic fields from the exact solver (window propagation), and for
//! several level resolutions `N` (step `= d(r, q) / N = pi / (2N)`) the descriptor with each
//! tangent method (strip = paper's method 1, spline = method 2, gradient = exact per-face) is
//! compared with the analytic representation:
//!
//! * grid points: level circles `z = cos(i step)` and `x = cos(j step)` meet at
//!   `y = +-sqrt(1 - z^2 - x^2)`; the opening there is given by the spherical law of cosines
//!   (with `d = pi/2`: `cos = -cot a cot b`);
//! * iso-angle points: on the circle of level `i` (`a = i step`), `cos = +-alpha k / K` is met
//!   where `cot b = -cos / cot a`, one point on each side.
//!
//! The analytic points and the errors against them are `bipolar::synthetic` (`sphere_truth`,
//! `SphereErrors`). Reported: the normalised keyed shape distance `min_R ||A - R B|| / sqrt(|A|^2 + |B|^2)`
//! (common keys, centred, rotation only), mean position error and mean angle (cosine) error.

use anyhow::Context;
use bipolar::synthetic::{sphere_truth, SphereErrors};
use bipolar::{Descriptor, DescriptorOptions, LevelSpec, SelectionRule, Source, TangentMethod};
use glam::DVec3;
use meshcore::{FaceLocator, TriMesh};
use std::time::Instant;

mod output;

/// Opening limit alpha of the iso-angle and filter rules.
const ALPHA: f64 = 0.95;
/// Angle steps K of the iso-angle and filter rules.
const K: u32 = 8;
/// Level resolutions N measured.
const LEVELS: [u32; 5] = [4, 6, 8, 12, 16];
/// The tangent methods compared, in table and plot order, with their names in the tables.
const METHODS: [(TangentMethod, &str); 3] = [
    (TangentMethod::Strip, "strip (M1)"),
    (TangentMethod::Spline, "spline (M2)"),
    (TangentMethod::Gradient, "gradient"),
];

/// The selection rules measured, with their names in the tables.
fn rules() -> [(SelectionRule, &'static str); 3] {
    let tolerance = ALPHA / (4.0 * f64::from(K));
    [
        (SelectionRule::IsoAngle, "isoangle"),
        (SelectionRule::Filter { tolerance }, "filter"),
        (SelectionRule::All, "all"),
    ]
}

/// The analytic representation of `rule` at `n` levels (levels 1..2N-1).
fn truth(rule: SelectionRule, n: u32) -> bipolar::synthetic::SphereTruth {
    sphere_truth(rule, n, 2 * n - 1, K, ALPHA)
}

/// A unit sphere mesh with its two poles.
struct SphereMesh {
    name: String,
    mesh: TriMesh,
    refs: [Source; 2],
}

impl SphereMesh {
    /// The distance fields of the two poles from the exact solver (the Dijkstra one when the
    /// exact solver refuses the mesh), and the name of the solver used.
    fn pole_fields(&self) -> anyhow::Result<(Vec<Vec<f64>>, &'static str)> {
        let (solver, used) = match geodesic::new_solver(&self.mesh, geodesic::Method::Exact) {
            Ok(s) => (s, "exact"),
            Err(_) => (
                geodesic::new_solver(&self.mesh, geodesic::Method::Dijkstra)?,
                "dijkstra",
            ),
        };
        let fields = self
            .refs
            .iter()
            .map(|r| solver.distances(&[*r], &geodesic::SolveOptions::default()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((fields, used))
    }

    /// The descriptor with `n` levels between the poles (levels 1..2N-1 kept), rule and
    /// tangent method, from the pole fields.
    fn describe(
        &self,
        surface: &bipolar::Surface,
        fields: &[Vec<f64>],
        n: u32,
        rule: SelectionRule,
        tangent: TangentMethod,
    ) -> Result<Descriptor, bipolar::BipolarError> {
        let opts = DescriptorOptions {
            levels: LevelSpec::Count(n),
            max_level: Some(2 * n - 1),
            angles: K,
            alpha: ALPHA,
            rule,
            tangent,
            ..DescriptorOptions::default()
        };
        let references = Some(&self.refs[..]);
        bipolar::describe(
            surface,
            bipolar::Fields::Precomputed { fields, references },
            &opts,
        )
    }
}

/// The icospheres (3, 4, 5 subdivisions) and UV spheres measured.
fn meshes() -> anyhow::Result<Vec<SphereMesh>> {
    let mut out = Vec::new();
    for sub in [3u32, 4, 5] {
        let mesh = bipolar::synthetic::icosphere(sub);
        let loc = FaceLocator::new(&mesh);
        let (r, q) = (loc.nearest(DVec3::Z)?.0, loc.nearest(DVec3::X)?.0);
        let name = format!("ico{sub} ({} v)", mesh.n_vertices());
        let refs = [Source::Point(r), Source::Point(q)];
        out.push(SphereMesh { name, refs, mesh });
    }
    for (nlat, nlon) in [(24usize, 48usize), (48, 96)] {
        let mesh = bipolar::synthetic::uv_sphere(nlat, nlon);
        // North pole is vertex 0; +X is ring nlat/2, sector 0.
        let qv = (1 + (nlat / 2 - 1) * nlon) as u32;
        anyhow::ensure!((mesh.position(qv) - DVec3::X).length() < 1e-12);
        let name = format!("uv{nlat}x{nlon} ({} v)", mesh.n_vertices());
        let refs = [Source::Vertex(0), Source::Vertex(qv)];
        out.push(SphereMesh { name, refs, mesh });
    }
    Ok(out)
}

/// One measured configuration (mesh, N, rule, tangent method).
#[derive(Debug, Clone)]
struct Row {
    mesh: String,
    n_vertices: usize,
    mean_edge: f64,
    levels: u32,
    rule: &'static str,
    method: &'static str,
    /// Points of the descriptor, of the analytic representation, and keys in common.
    counts: [usize; 3],
    /// Shape distance, mean position error, mean and largest cos error.
    errors: [f64; 4],
    ms: f64,
}

impl Row {
    fn distance(&self) -> f64 {
        self.errors[0]
    }

    /// The cells of the row: every column at full precision for `results.csv` (`csv`), or the
    /// columns of the report's tables.
    fn cells(&self, csv: bool) -> Vec<String> {
        let digits = if csv { 6 } else { 2 };
        let mut c = vec![self.mesh.clone()];
        if csv {
            c.extend([
                self.n_vertices.to_string(),
                format!("{:.6}", self.mean_edge),
            ]);
        }
        c.push(self.levels.to_string());
        if csv {
            c.push(self.rule.to_string());
        }
        c.push(self.method.to_string());
        c.extend(self.counts.iter().map(usize::to_string));
        c.extend(self.errors.iter().map(|x| format!("{x:.digits$e}")));
        c.push(format!("{:.*}", if csv { 3 } else { 1 }, self.ms));
        c
    }
}

/// Arguments of `cargo xtask sphere-validate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The output folder (`--out`).
    #[command(flatten)]
    pub out: crate::paths::OutArgs,
}

/// Runs the experiment, writing into the output folder.
pub fn run(args: Args) -> anyhow::Result<()> {
    let t_start = Instant::now();
    let out_dir = args.out.out_dir("sphere-validate");
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let meshes = meshes()?;
    let m = measure(&meshes)?;
    let plots = output::write_plots(&out_dir, &m.rows, &meshes)?;
    let renders = output::write_renders(&out_dir, &meshes[1])?;
    let md = output::write_report(&out_dir, &m, &meshes, (&plots, &renders), t_start)?;
    println!("{}", md.lines().take(12).collect::<Vec<_>>().join("\n"));
    println!("wrote {}", out_dir.display());
    Ok(())
}

/// The rows of every configuration, the geodesic solver used and the time of the pole fields
/// per mesh.
struct Measured {
    rows: Vec<Row>,
    solver_name: &'static str,
    /// Time of both pole fields per mesh (name, ms).
    geodesic_ms: Vec<(String, f64)>,
}

/// Describes every mesh at every N with every rule and tangent method and compares each with
/// the analytic representation.
fn measure(meshes: &[SphereMesh]) -> anyhow::Result<Measured> {
    let rules = rules();
    let pb = crate::pipeline::bar(
        meshes.len() * LEVELS.len() * rules.len() * METHODS.len(),
        "",
    );
    let mut m = Measured {
        rows: Vec::new(),
        solver_name: "exact",
        geodesic_ms: Vec::new(),
    };
    for sm in meshes {
        pb.set_message(format!("geodesics on {}", sm.name));
        let tg = Instant::now();
        let (fields, used) = sm.pole_fields()?;
        m.solver_name = used;
        m.geodesic_ms
            .push((sm.name.clone(), tg.elapsed().as_secs_f64() * 1e3));
        let surface = bipolar::Surface::new(sm.mesh.clone());
        for &n in &LEVELS {
            for &(rule, rname) in &rules {
                let truth = truth(rule, n);
                for &(method, mname) in &METHODS {
                    pb.set_message(format!("{} N={n} {rname} {mname}", sm.name));
                    let t0 = Instant::now();
                    let d = sm.describe(&surface, &fields, n, rule, method)?;
                    let ms = t0.elapsed().as_secs_f64() * 1e3;
                    let e = SphereErrors::of(&d, &truth);
                    let n_common = e.mesh_points.len();
                    let distance = if n_common == 0 {
                        f64::NAN
                    } else {
                        let kabsch = shapedist::RotationMethod::Kabsch;
                        shapedist::align_pairs(&e.mesh_points, &e.truth_points, None, kabsch)
                            .map_or(f64::NAN, |al| al.distance)
                    };
                    m.rows.push(Row {
                        mesh: sm.name.clone(),
                        n_vertices: sm.mesh.n_vertices(),
                        mean_edge: sm.mesh.mean_edge_length(),
                        levels: n,
                        rule: rname,
                        method: mname,
                        counts: [d.len(), truth.len(), n_common],
                        errors: [distance, e.pos_err, e.cos_err, e.cos_err_max],
                        ms,
                    });
                    pb.inc(1);
                }
            }
        }
    }
    pb.finish_with_message("done");
    Ok(m)
}
