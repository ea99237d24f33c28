//! Pipeline pieces shared by the experiments: reference configurations (`facematch::PoleRefs`,
//! whose descriptor per area `bipolar` builds), keyed distances (`facematch::KeyedSet`),
//! reference-point perturbation, geodesic method resolution and progress bars.

use crate::walk::Walker;
use anyhow::{bail, Context, Result};
use facematch::KeyedSet;
use facemodel::Face;
use geodesic::{GeodesicSolver, Method, SolveOptions, Source};
use indicatif::{ProgressBar, ProgressStyle};
use meshcore::{DVec3, SurfacePoint, TriMesh};
use shapedist::ShapeDistError;

pub use facematch::{Area, PoleRefs};

/// The reference configuration of a face from its landmark vertices (the outer eye corners as
/// the poles r and q, D the mean of each field's value at the other corner), with `solver` (of
/// `face.mesh`), and the nose tip's distance field (the single pole's and the facial curves'
/// field).
pub fn face_refs(face: &Face, solver: &dyn GeodesicSolver) -> Result<(PoleRefs, Vec<f64>)> {
    let (m, lm) = (&face.mesh, face.landmarks);
    let ur = field(solver, Source::Vertex(lm.right_eye_outer))?;
    let uq = field(solver, Source::Vertex(lm.left_eye_outer))?;
    let un = field(solver, Source::Vertex(lm.nose_tip))?;
    let d = 0.5 * (ur[lm.left_eye_outer as usize] + uq[lm.right_eye_outer as usize]);
    let (r, q, nose) = (
        m.position(lm.right_eye_outer),
        m.position(lm.left_eye_outer),
        m.position(lm.nose_tip),
    );
    Ok((PoleRefs::new(m, [ur, uq], d, [r, q, nose]), un))
}

pub use shapedist::landmark_icp_rms;

/// Distance field from one source.
pub fn field(solver: &dyn GeodesicSolver, src: Source) -> Result<Vec<f64>> {
    Ok(solver.distances(&[src], &SolveOptions::default())?)
}

/// Which `bipolar` selection rule builds the face descriptors (`--descriptor`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DescriptorRule {
    /// Every intersection of the two level families (rule `All`, keys `(i, j, side)`): the grid
    /// reading of the paper.
    CrateAll,
    /// Exact iso-angle points (rule B, keys `(i, k, side, sign)`), K = 8, alpha = 0.95,
    /// gradient tangents.
    CrateIsoAngle,
}

impl DescriptorRule {
    /// `bipolar`'s options of the rule (the rest at their defaults).
    pub fn options(self) -> bipolar::DescriptorOptions {
        match self {
            DescriptorRule::CrateAll => facematch::grid_rule(),
            DescriptorRule::CrateIsoAngle => bipolar::DescriptorOptions {
                rule: bipolar::SelectionRule::IsoAngle,
                ..Default::default()
            },
        }
    }
}

pub use facematch::kept_vertices;

/// A descriptor as the keyed point set a comparison reads (`facematch::KeyedSet`).
pub trait Keyed {
    /// Packed keys and positions of the points that may be paired (ambiguous points left out).
    fn keyed_set(&self) -> KeyedSet;
}

impl Keyed for bipolar::Descriptor {
    fn keyed_set(&self) -> KeyedSet {
        KeyedSet::of(self)
    }
}

/// The single-pole descriptor has one point per key: none is ambiguous.
impl Keyed for bipolar::PolarDescriptor {
    fn keyed_set(&self) -> KeyedSet {
        KeyedSet {
            keys: self.keys(),
            points: self.positions(),
        }
    }
}

/// A descriptor that could not be built counts as a set without points.
impl<T: Keyed> Keyed for Option<T> {
    fn keyed_set(&self) -> KeyedSet {
        self.as_ref()
            .map_or_else(KeyedSet::default, Keyed::keyed_set)
    }
}

/// A descriptor that could not be built (its error kept for the report) counts as a set without
/// points.
impl<T: Keyed, E> Keyed for Result<T, E> {
    fn keyed_set(&self) -> KeyedSet {
        self.as_ref()
            .map_or_else(|_| KeyedSet::default(), Keyed::keyed_set)
    }
}

/// Keyed distance of the unambiguous points: `facematch::KeyedSet::distance` without a gate
/// (`shapedist::keyed_distance`, Kabsch closed form). Fewer than 3 shared keys is
/// `ShapeDistError::TooFewPairs`.
pub fn dist<A: Keyed + ?Sized, B: Keyed + ?Sized>(a: &A, b: &B) -> Result<f64, ShapeDistError> {
    a.keyed_set().distance(&b.keyed_set(), None)
}

/// Perturbation radii of the reference-point error grid (figures 9-11), in percent of D.
pub const RADII_PCT: [f64; 5] = [1.0, 2.0, 3.0, 4.0, 5.0];
/// Directions of the reference-point error grid (evenly spaced angles).
pub const N_DIRS: usize = 8;

/// The cells `(radius in % of D, angle in radians)` of the reference-point error grid: every
/// radius of [`RADII_PCT`] with each of the [`N_DIRS`] directions, radius by radius.
pub fn error_grid() -> Vec<(f64, f64)> {
    RADII_PCT
        .iter()
        .flat_map(|&p| {
            (0..N_DIRS).map(move |k| (p, std::f64::consts::TAU * k as f64 / N_DIRS as f64))
        })
        .collect()
}

/// Moves vertex `v` by `radius` along a straightest geodesic leaving at angle `theta` from the
/// tangent direction towards `towards`. The flag is true when the walk met the mesh boundary
/// (e.g. the eye opening) before the full length: the point then lies on the boundary.
pub fn perturb(
    walker: &Walker<'_>,
    v: u32,
    towards: DVec3,
    radius: f64,
    theta: f64,
) -> Result<(SurfacePoint, bool)> {
    let p = walker.mesh().position(v);
    let dir = Walker::tangent_direction(p, walker.vertex_normal(v), towards, theta)?;
    let w = walker.walk_from_vertex(v, dir, radius)?;
    Ok((w.end, w.truncated))
}

/// Geodesic method actually used for a requested one.
#[derive(Debug, Clone)]
pub struct MethodUse {
    /// Method asked for.
    pub requested: Method,
    /// Method used.
    pub used: Method,
    /// Why they differ.
    pub note: Option<String>,
}

/// Resolves a comma-separated method list; an unavailable exact solver falls back to fmm, then
/// heat ([`geodesic::usable_method`]).
pub fn resolve_methods(list: &str, mesh: &TriMesh) -> Result<Vec<MethodUse>> {
    let mut out: Vec<MethodUse> = Vec::new();
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let m: Method = name.parse().with_context(|| format!("--methods: {name}"))?;
        let (used, failed) = geodesic::usable_method(mesh, m);
        let note = (!failed.is_empty()).then(|| {
            let each = failed
                .iter()
                .map(|(c, e)| format!("{} unavailable ({e})", c.name()));
            each.collect::<Vec<_>>().join("; ")
        });
        match used {
            Some(used) if out.iter().all(|x| x.used != used) => out.push(MethodUse {
                requested: m,
                used,
                note,
            }),
            Some(_) => {}
            None => eprintln!("warning: {}: skipped", note.unwrap_or_default()),
        }
    }
    if out.is_empty() {
        bail!("no usable geodesic method in --methods {list}");
    }
    Ok(out)
}

/// A progress bar with the task's style.
pub fn bar(len: usize, msg: &str) -> ProgressBar {
    let pb = ProgressBar::new(len as u64);
    pb.set_style(
        ProgressStyle::with_template("{msg:>28} [{bar:40}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(msg.to_string());
    pb
}

/// Runs `f` on a pool of one thread and returns its result and wall time: the single-thread
/// cost of a step, free of the work other tasks steal into the wait of a nested parallel loop
/// (which inflates times measured inside a parallel loop).
pub fn single_thread<T: Send>(f: impl FnOnce() -> T + Send) -> Result<(T, std::time::Duration)> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .context("a one-thread pool for timing")?;
    Ok(pool.install(|| {
        let t = std::time::Instant::now();
        let out = f();
        (out, t.elapsed())
    }))
}
