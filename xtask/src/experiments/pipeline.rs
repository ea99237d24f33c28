//! Pipeline pieces shared by the experiments: reference configurations, descriptors per
//! region, distance matrices, reference-point perturbation, geodesic method resolution and
//! progress bars.

use super::descriptor::{bipolar_grid, keyed_distance, GridOptions, KeyedPoints};
use super::walk::Walker;
use anyhow::{bail, Context, Result};
use facemodel::{static_mask, FaceFrame};
use geodesic::{GeodesicSolver, Method, SolveOptions, Source};
use indicatif::{ProgressBar, ProgressStyle};
use meshcore::{DVec3, SurfacePoint, TriMesh};
use rayon::prelude::*;

/// Which area a bipolar descriptor covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// Points within D of both corners and above the nose-tip plane.
    Static,
    /// Levels up to 2N of both fields (nearly the whole face).
    Whole,
}

/// The reference configuration of one face for one method: the two corner fields, D, the
/// reference and nose positions, and the landmark frame.
#[derive(Debug, Clone)]
pub struct Refs {
    /// See the struct doc.
    pub ur: Vec<f64>,
    /// See the struct doc.
    pub uq: Vec<f64>,
    /// See the struct doc.
    pub d: f64,
    /// See the struct doc.
    pub r: DVec3,
    /// See the struct doc.
    pub q: DVec3,
    /// See the struct doc.
    pub nose: DVec3,
    /// See the struct doc.
    pub frame: FaceFrame,
}

/// Distance field from one source.
pub fn field(solver: &dyn GeodesicSolver, src: Source) -> Result<Vec<f64>> {
    Ok(solver.distances(&[src], &SolveOptions::default())?)
}

/// Linear interpolation of a vertex field at a surface point.
pub fn field_at(mesh: &TriMesh, u: &[f64], sp: &SurfacePoint) -> f64 {
    let t = mesh.triangles()[sp.face as usize];
    sp.bary.x * u[t[0] as usize] + sp.bary.y * u[t[1] as usize] + sp.bary.z * u[t[2] as usize]
}

/// Which implementation builds the bipolar descriptor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DescriptorImpl {
    /// The `bipolar` crate, every intersection of the two level families (rule `All`, keys
    /// `(i, j, side)`): the grid reading of the paper.
    CrateAll,
    /// The `bipolar` crate, exact iso-angle points (rule B, keys `(i, k, side, sign)`), K = 8,
    /// alpha = 0.95, gradient tangents.
    CrateIsoAngle,
    /// The local grid implementation of `experiments::descriptor` (cross-check).
    Local,
}

static DESCRIPTOR_IMPL: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);
static CRATE_FAILURES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Selects the descriptor implementation for the whole process.
pub fn set_descriptor_impl(d: DescriptorImpl) {
    DESCRIPTOR_IMPL.store(d as u8, std::sync::atomic::Ordering::Relaxed);
}

/// The selected descriptor implementation.
pub fn descriptor_impl() -> DescriptorImpl {
    match DESCRIPTOR_IMPL.load(std::sync::atomic::Ordering::Relaxed) {
        0 => DescriptorImpl::CrateAll,
        1 => DescriptorImpl::CrateIsoAngle,
        _ => DescriptorImpl::Local,
    }
}

/// Number of descriptors the crate could not build (they count as empty descriptors).
pub fn crate_failures() -> usize {
    CRATE_FAILURES.load(std::sync::atomic::Ordering::Relaxed)
}

/// Converts a crate descriptor to a keyed set (sorted by packed key; a key found twice is
/// ambiguous).
pub fn from_crate(d: &bipolar::Descriptor) -> KeyedPoints {
    let mut v: Vec<(u64, DVec3, bool)> = d
        .points
        .iter()
        .map(|p| (p.key.pack(), p.position, p.ambiguous))
        .collect();
    v.sort_by(|a, b| {
        a.0.cmp(&b.0)
            .then(a.1.x.total_cmp(&b.1.x))
            .then(a.1.y.total_cmp(&b.1.y))
    });
    let mut out = KeyedPoints::default();
    for (k, p, amb) in v {
        if out.keys.last() == Some(&k) {
            if let Some(last) = out.ambiguous.last_mut() {
                *last = true;
            }
            continue;
        }
        out.keys.push(k);
        out.points.push(p);
        out.ambiguous.push(amb);
    }
    out
}

/// The bipolar descriptor of a configuration at `n` levels between the references (step
/// `D / n`; static region: levels up to n with the static mask; whole: levels up to 2n).
pub fn bipolar(mesh: &TriMesh, refs: &Refs, n: u32, region: Region) -> KeyedPoints {
    let step = refs.d / f64::from(n);
    let (max_level, mask) = match region {
        Region::Static => (
            n,
            Some(static_mask(
                mesh,
                &refs.ur,
                &refs.uq,
                refs.d,
                &refs.frame,
                refs.nose,
            )),
        ),
        Region::Whole => (2 * n, None),
    };
    let imp = descriptor_impl();
    if imp == DescriptorImpl::Local {
        return bipolar_grid(
            mesh,
            &refs.ur,
            &refs.uq,
            &GridOptions { step, max_level },
            mask.as_deref(),
        );
    }
    let opts = bipolar::DescriptorOptions {
        levels: bipolar::LevelSpec::Step(step),
        max_level: Some(max_level),
        vertex_mask: mask,
        rule: if imp == DescriptorImpl::CrateAll {
            bipolar::SelectionRule::All
        } else {
            bipolar::SelectionRule::IsoAngle
        },
        ..Default::default()
    };
    let surface = bipolar::Surface::new(mesh.clone());
    match bipolar::describe(
        &surface,
        bipolar::Fields::Precomputed {
            fields: &[refs.ur.clone(), refs.uq.clone()],
            references: None,
        },
        &opts,
    ) {
        Ok(d) => from_crate(&d),
        Err(_) => {
            CRATE_FAILURES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            KeyedPoints::default()
        }
    }
}

/// Keyed distance (NaN when fewer than 3 keys are shared): `shapedist::keyed_distance`
/// (Kabsch closed form, no gate) on the unambiguous points.
pub fn dist(a: &KeyedPoints, b: &KeyedPoints) -> f64 {
    let (ka, pa) = a.unambiguous();
    let (kb, pb) = b.unambiguous();
    match shapedist::keyed_distance(&ka, &pa, &kb, &pb, &shapedist::KeyedOptions::default()) {
        Ok(k) => k.distance,
        Err(_) => keyed_distance(a, b).map_or(f64::NAN, |k| k.distance),
    }
}

/// Symmetric pairwise distance matrix (rayon over pairs).
pub fn matrix(descs: &[KeyedPoints]) -> Vec<Vec<f64>> {
    let n = descs.len();
    let pairs: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .collect();
    let vals: Vec<f64> = pairs
        .par_iter()
        .map(|&(i, j)| dist(&descs[i], &descs[j]))
        .collect();
    let mut m = vec![vec![0.0; n]; n];
    for (&(i, j), v) in pairs.iter().zip(vals) {
        m[i][j] = v;
        m[j][i] = v;
    }
    m
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

/// Resolves a comma-separated method list; an unavailable exact solver falls back to fmm, then heat.
pub fn resolve_methods(list: &str, mesh: &TriMesh) -> Result<Vec<MethodUse>> {
    let mut out: Vec<MethodUse> = Vec::new();
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let m: Method = name.parse().with_context(|| format!("--methods: {name}"))?;
        let mut note = None;
        let mut used = None;
        let chain: Vec<Method> = match m {
            Method::Exact => vec![Method::Exact, Method::Fmm, Method::Heat],
            other => vec![other],
        };
        for c in chain {
            match geodesic::new_solver(mesh, c) {
                Ok(_) => {
                    used = Some(c);
                    break;
                }
                Err(e) => {
                    let s = format!("{} unavailable ({e})", c.name());
                    note = Some(match note {
                        None => s,
                        Some(prev) => format!("{prev}; {s}"),
                    });
                }
            }
        }
        match used {
            Some(u) => {
                if out.iter().all(|x| x.used != u) {
                    out.push(MethodUse {
                        requested: m,
                        used: u,
                        note,
                    });
                }
            }
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
