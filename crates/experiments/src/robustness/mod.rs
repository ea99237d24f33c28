//! `cargo xtask robustness`: the paper's sections 4-6 on the face set, as one report.
//!
//! For every requested geodesic method (default: exact and Dijkstra), on the 12 faces of the
//! paper set: renders of the level curves and descriptor points, the shape distance against
//! resolution and the 12 x 12 matrix (`base`), the robustness to reference-point errors (grid
//! of radius x direction and the three cases of figure 11, `grid`; matrices with random errors
//! on one and on both corners, `random`), and the single-pole comparison (figure 17) with the
//! figure-15 argument (`pole`); `report` writes it all. Descriptors come from `bipolar`,
//! distances from `shapedist`; a crate error is listed in the report with the face's name and
//! counted, its cells are NaN. See `docs/experiments.md` for every choice made.

mod base;
mod grid;
pub(crate) mod pole;
mod random;
mod report;
pub(crate) mod stats;

use crate::paths::FaceSetArgs;
use crate::pipeline::{
    dist, face_refs, field, perturb, resolve_methods, Area, DescriptorRule, Keyed, PoleRefs,
};
use crate::polar::PolarOptions;
use crate::report::{par_map, Failures};
use crate::walk::Walker;
use anyhow::{bail, Result};
use bipolar::PolarDescriptor;
use facemodel::Face;
use geodesic::Source;
use geodesic::{GeodesicSolver, Method};
use meshcore::{DVec3, SurfacePoint, TriMesh};
use rayon::prelude::*;
use shapedist::ShapeDistError;
use std::path::Path;
use std::time::Instant;

/// Arguments of `cargo xtask robustness`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Face set, report folder (default `target/robustness`) and descriptor resolution (the
    /// default N of the figures that do not vary it).
    #[command(flatten)]
    pub set: FaceSetArgs,
    /// Geodesic methods to run, comma separated (exact, fmm, heat, dijkstra).
    #[arg(long, default_value = "exact,dijkstra")]
    pub methods: String,
    /// Seed of the random reference-point errors.
    #[arg(long, default_value_t = 2013)]
    pub seed: u64,
    /// Selection rule of the `bipolar` descriptor.
    #[arg(long, value_enum, default_value = "crate-all")]
    pub descriptor: DescriptorRule,
}

/// Resolutions of the sweeps (levels between the references).
const RESOLUTIONS: [u32; 9] = [3, 4, 5, 6, 8, 10, 12, 15, 20];

/// A face descriptor, `None` where `bipolar` refused it (the refusal is in [`Failures`]).
type Desc = Option<bipolar::Descriptor>;

/// Everything measured with one geodesic method.
#[derive(Debug, Default)]
struct MethodResults {
    name: String,
    d: Vec<f64>,
    n_points: Vec<(usize, usize)>,
    sweep: Vec<(u32, Vec<f64>)>,
    m_static: Vec<Vec<f64>>,
    m_whole: Vec<Vec<f64>>,
    m_polar: Vec<Vec<f64>>,
    grid_bip: Vec<(f64, f64, f64)>,
    grid_pol: Vec<(f64, f64, f64)>,
    fig11: Vec<(u32, [f64; 6])>,
    m_rand_one: Vec<Vec<f64>>,
    m_rand_both: Vec<Vec<f64>>,
    m_rand_nose: Vec<Vec<f64>>,
    rand_one_pct: Vec<f64>,
    truncated: (usize, usize),
    seconds: f64,
}

/// What every part of one method's run reads.
struct Ctx<'a> {
    args: &'a Args,
    faces: &'a [Face],
    walkers: &'a [Walker<'a>],
    test: usize,
    method: Method,
    failures: &'a Failures,
}

/// One face's geodesic set-up for one method: its solver, reference configuration and
/// nose-tip field (also `section6`'s).
pub(crate) struct FacePrep {
    pub(crate) solver: Box<dyn GeodesicSolver>,
    pub(crate) refs: PoleRefs,
    pub(crate) un: Vec<f64>,
}

/// One cell of the reference-point error grid on a face ([`FacePrep::moved_cell`]): the
/// references with q moved, the moved nose tip with its field, and whether the walk of q and of
/// the nose tip met the boundary before the full radius.
pub(crate) type MovedCell = (PoleRefs, (SurfacePoint, Vec<f64>), (bool, bool));

impl FacePrep {
    /// The solver of `method` on the face and its references from the landmark vertices.
    pub(crate) fn new(face: &Face, method: Method) -> Result<Self> {
        let solver = geodesic::new_solver(&face.mesh, method)?;
        let (refs, un) = face_refs(face, solver.as_ref())?;
        Ok(Self { solver, refs, un })
    }

    /// The references with the left outer eye corner q moved to `sp`: its field from the
    /// face's solver, D the mean of both fields at the other corner, the frame rebuilt.
    pub(crate) fn with_q_moved(&self, face: &Face, sp: SurfacePoint) -> Result<PoleRefs> {
        let (m, r, nose) = (&face.mesh, self.refs.r, self.refs.nose);
        let uq = field(self.solver.as_ref(), Source::Point(sp))?;
        let q = m.point_position(&sp)?;
        let right = face.landmarks.right_eye_outer as usize;
        let d = 0.5 * (uq[right] + m.interpolate(&self.refs.ur, &sp)?);
        Ok(PoleRefs::new(
            m,
            [self.refs.ur.clone(), uq],
            d,
            [r, q, nose],
        ))
    }

    /// The grid cell `(pct, theta)`: q ([`FacePrep::with_q_moved`]) and the nose tip each
    /// moved along a straightest geodesic (`walker`, on `face`) of `pct` % of D, leaving at
    /// `theta` from the direction towards r (q) or towards the corners' midpoint (nose tip).
    pub(crate) fn moved_cell(
        &self,
        face: &Face,
        walker: &Walker<'_>,
        (pct, theta): (f64, f64),
    ) -> Result<MovedCell> {
        let (lm, radius) = (face.landmarks, pct / 100.0 * self.refs.d);
        let (sq, cut_q) = perturb(walker, lm.left_eye_outer, self.refs.r, radius, theta)?;
        let refs = self.with_q_moved(face, sq)?;
        let (sn, cut_n) = perturb(walker, lm.nose_tip, eye_mid(&self.refs), radius, theta)?;
        let un = field(self.solver.as_ref(), Source::Point(sn))?;
        Ok((refs, (sn, un), (cut_q, cut_n)))
    }
}

impl Ctx<'_> {
    fn mname(&self) -> &'static str {
        self.method.name()
    }

    /// The bipolar descriptor of `refs` on `mesh`; a refusal is listed under `what`.
    fn describe(
        &self,
        mesh: &TriMesh,
        refs: &PoleRefs,
        n: u32,
        area: Area,
        what: impl FnOnce() -> String,
    ) -> Desc {
        let surface = bipolar::Surface::new(mesh.clone());
        match refs.descriptor(&surface, n, area, None, self.args.descriptor.options()) {
            Ok(d) => Some(d),
            Err(e) => {
                let msg = format!("{}: descriptor of {}: {e}", self.mname(), what());
                self.failures.list(msg);
                None
            }
        }
    }

    /// Distance of two descriptors (NaN when either was refused or the distance failed; a
    /// failure is listed under `what`, a pair with too few shared keys counted).
    fn dist<T: AsKeyed>(&self, a: &T, b: &T, what: impl FnOnce() -> String) -> f64 {
        let (Some(a), Some(b)) = (a.keyed(), b.keyed()) else {
            return f64::NAN;
        };
        match dist(a, b) {
            Ok(d) => d,
            Err(ShapeDistError::TooFewPairs { .. }) => {
                self.failures.too_few();
                f64::NAN
            }
            Err(e) => {
                self.failures
                    .list(format!("{}: distance {}: {e}", self.mname(), what()));
                f64::NAN
            }
        }
    }

    /// The matrix of [`Ctx::dist`] over the pairs of `descs` (one per face, in face order) by
    /// `shapedist::pairwise_matrix`, failures named by `label` and the pair.
    fn matrix<T: AsKeyed>(&self, descs: &[T], label: &str) -> Vec<Vec<f64>> {
        let items: Vec<(&str, &T)> = self
            .faces
            .iter()
            .map(|f| f.name.as_str())
            .zip(descs)
            .collect();
        let m = shapedist::pairwise_matrix(&items, |a, b| {
            let what = || format!("{label}: {} vs {}", a.0, b.0);
            Ok::<f64, std::convert::Infallible>(self.dist(a.1, b.1, what))
        });
        match m {
            Ok(m) => m,
            Err(e) => match e.error {},
        }
    }

    /// Options of the single-pole descriptor for a configuration.
    fn polar_opts(&self, r: &PoleRefs) -> PolarOptions {
        PolarOptions {
            step: r.d / f64::from(self.args.set.res.levels),
            levels: self.args.set.res.levels,
            sectors: self.args.set.res.sectors,
        }
    }
}

/// A descriptor as the distances take it: absent where `bipolar` refused it.
trait AsKeyed: Sync {
    /// The keyed point set.
    type K: Keyed;
    /// The descriptor, if any.
    fn keyed(&self) -> Option<&Self::K>;
}

impl AsKeyed for Desc {
    type K = bipolar::Descriptor;
    fn keyed(&self) -> Option<&Self::K> {
        self.as_ref()
    }
}

impl AsKeyed for PolarDescriptor {
    type K = PolarDescriptor;
    fn keyed(&self) -> Option<&Self::K> {
        Some(self)
    }
}

/// Midpoint of the two outer eye corners (angular origin of the single pole).
pub(crate) fn eye_mid(r: &PoleRefs) -> DVec3 {
    0.5 * (r.r + r.q)
}

/// Number of distinct keys of a descriptor (a key found twice counts once; 0 if refused).
fn n_keys(d: &Desc) -> usize {
    d.as_ref().map_or(0, |d| {
        let mut k = d.packed_keys();
        k.dedup();
        k.len()
    })
}

/// Runs the task; prints the report folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let t0 = Instant::now();
    let (faces, test) = args.set.load()?;
    if args.set.res.levels < 2 || args.set.res.sectors < 3 {
        bail!("--levels must be >= 2 and --sectors >= 3");
    }
    let out = args.set.out.out_dir("robustness");
    let walkers: Vec<Walker<'_>> = faces.par_iter().map(|f| Walker::new(&f.mesh)).collect();
    let methods = resolve_methods(&args.methods, &faces[test].mesh)?;
    let failures = Failures::default();
    let mut results = Vec::new();
    for mu in &methods {
        if let Some(n) = &mu.note {
            eprintln!(
                "note: {} requested: {n}; using {}",
                mu.requested.name(),
                mu.used.name()
            );
        }
        let ctx = Ctx {
            args: &args,
            faces: &faces,
            walkers: &walkers,
            test,
            method: mu.used,
            failures: &failures,
        };
        results.push(run_method(&ctx, &out)?);
    }
    let fig15 = pole::figure15(&args, &faces, test, methods[0].used, &out)?;
    report::write_report(
        &args, &faces, test, &methods, &results, &fig15, &failures, &out, t0,
    )?;
    println!("{}", out.display());
    Ok(())
}

/// The [`FacePrep`] of every face with the context's method.
fn prepare(ctx: &Ctx<'_>) -> Result<Vec<FacePrep>> {
    let msg = format!("{}: base fields", ctx.mname());
    par_map(ctx.faces, &msg, |f| FacePrep::new(f, ctx.method))
        .into_iter()
        .collect()
}

fn run_method(ctx: &Ctx<'_>, out: &Path) -> Result<MethodResults> {
    let t0 = Instant::now();
    std::fs::create_dir_all(out)?;
    let prep = prepare(ctx)?;
    let mut res = MethodResults {
        name: ctx.mname().to_string(),
        d: prep.iter().map(|p| p.refs.d).collect(),
        ..Default::default()
    };
    base::renders(ctx, &prep, out)?;
    let base = base::run(ctx, &prep, &mut res)?;
    grid::run(ctx, &prep, &base, &mut res)?;
    random::run(ctx, &prep, &mut res)?;
    res.seconds = t0.elapsed().as_secs_f64();
    Ok(res)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::perturb;

    #[test]
    fn perturbation_moves_by_the_radius_on_a_plane() {
        let m = crate::walk::tests::plane(20, 0.2, 5);
        let w = Walker::new(&m);
        let v = 10 * 21 + 10;
        let p = m.position(v);
        let (sp, cut) = perturb(&w, v, p + DVec3::X, 0.2, std::f64::consts::FRAC_PI_2).unwrap();
        assert!(!cut);
        let (_, cut) = perturb(&w, v, p + DVec3::X, 0.7, 0.0).unwrap();
        assert!(
            cut,
            "a 0.7 walk from the centre towards +x leaves the unit square"
        );
        let q = m.point_position(&sp).unwrap();
        assert!((q - (p + 0.2 * DVec3::Y)).length() < 1e-9);
        let u: Vec<f64> = m.positions().iter().map(|x| x.x).collect();
        assert!((m.interpolate(&u, &sp).unwrap() - q.x).abs() < 1e-12);
    }
}
