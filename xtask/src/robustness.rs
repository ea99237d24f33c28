//! `cargo xtask robustness`: the paper's sections 4-6 on the face set, as one report.
//!
//! For every requested geodesic method (default: exact and Dijkstra), on the 12 faces of the
//! paper set: renders of the level curves and descriptor points, the shape distance against
//! resolution and the 12 x 12 matrix, the robustness to reference-point errors (grid of radius
//! x direction, the three cases of figure 11, matrices with random errors on one and on both
//! corners), and the single-pole comparison (figure 17) with the figure-15 argument.
//! See `docs/experiments.md` for every choice made.

use crate::experiments::descriptor::{isoline_segments, paired_distance, KeyedPoints};
use crate::experiments::pipeline::{
    bar, bipolar, crate_failures, dist, field, field_at, matrix, perturb, resolve_methods,
    set_descriptor_impl, DescriptorImpl, MethodUse, Refs, Region,
};
use crate::experiments::polar::{polar_descriptor, polar_key_parts, PolarOptions, Pole};
use crate::experiments::report::{f4, heatmap, line_plot, render, Overlay, Report, Series};
use crate::experiments::walk::Walker;
use crate::paths::{default_out_dir, default_paper_set};
use anyhow::{bail, Result};
use facemodel::{face_frame, load_face_set, static_mask, Face, FaceFrame};
use geodesic::{GeodesicSolver, Method, Source};
use meshcore::{DMat3, DQuat, DVec3, SurfacePoint};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `cargo xtask robustness`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Folder of the face set (OBJ files + landmarks.json); default
    /// `$BIPOLAR_SHARED/faces/ict-facekit/paper-set` (BIPOLAR_SHARED defaults to `../shared`).
    #[arg(long)]
    pub faces: Option<PathBuf>,
    /// Report folder (default `target/robustness`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Geodesic methods to run, comma separated (exact, fmm, heat, dijkstra).
    #[arg(long, default_value = "exact,dijkstra")]
    pub methods: String,
    /// Number of levels between the two reference points (the default resolution).
    #[arg(long, default_value_t = 10)]
    pub levels: u32,
    /// Angular sectors of the single-pole representation.
    #[arg(long, default_value_t = 16)]
    pub sectors: u32,
    /// Seed of the random reference-point errors.
    #[arg(long, default_value_t = 2013)]
    pub seed: u64,
    /// Descriptor implementation.
    #[arg(long, value_enum, default_value = "crate-all")]
    pub descriptor: DescriptorImpl,
}

/// Resolutions of the sweeps (levels between the references).
const RESOLUTIONS: [u32; 9] = [3, 4, 5, 6, 8, 10, 12, 15, 20];
/// Perturbation radii in percent of the corner-to-corner geodesic.
const RADII_PCT: [f64; 5] = [1.0, 2.0, 3.0, 4.0, 5.0];
/// Number of perturbation directions.
const N_DIRS: usize = 8;

/// Separation figures of a distance matrix.
#[derive(Debug, Clone, Copy)]
struct Sep {
    max_same: f64,
    min_diff: f64,
    row_max_same: f64,
    row_min_diff: f64,
}

impl Sep {
    fn of(m: &[Vec<f64>], faces: &[Face], test: usize) -> Self {
        let mut s = Sep {
            max_same: 0.0,
            min_diff: f64::INFINITY,
            row_max_same: 0.0,
            row_min_diff: f64::INFINITY,
        };
        for i in 0..faces.len() {
            for j in i + 1..faces.len() {
                let v = m[i][j];
                if faces[i].person == faces[j].person {
                    s.max_same = s.max_same.max(v);
                    if i == test || j == test {
                        s.row_max_same = s.row_max_same.max(v);
                    }
                } else {
                    s.min_diff = s.min_diff.min(v);
                    if i == test || j == test {
                        s.row_min_diff = s.row_min_diff.min(v);
                    }
                }
            }
        }
        s
    }
    fn ratio(&self) -> f64 {
        self.min_diff / self.max_same
    }
    fn row_ratio(&self) -> f64 {
        self.row_min_diff / self.row_max_same
    }
    fn verdict(&self) -> &'static str {
        if self.ratio() > 1.0 {
            "separated"
        } else {
            "NOT separated"
        }
    }
    fn row_verdict(&self) -> &'static str {
        if self.row_ratio() > 1.0 {
            "separated"
        } else {
            "NOT separated"
        }
    }
}

/// One perturbation cell: moved-corner references, moved-pole polar descriptor, and whether
/// each walk met the boundary.
type GridCell = (Refs, KeyedPoints, bool, bool);

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

/// Runs the task; prints the report folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let t0 = Instant::now();
    let dir = args.faces.clone().unwrap_or_else(default_paper_set);
    let faces = load_face_set(&dir)?;
    let test = faces
        .iter()
        .position(|f| f.name == "id1_neutral")
        .unwrap_or(0);
    if args.levels < 2 || args.sectors < 3 {
        bail!("--levels must be >= 2 and --sectors >= 3");
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir("robustness"));
    set_descriptor_impl(args.descriptor);
    eprintln!(
        "{} faces from {}; test face {}",
        faces.len(),
        dir.display(),
        faces[test].name
    );
    let walkers: Vec<Walker<'_>> = faces.par_iter().map(|f| Walker::new(&f.mesh)).collect();
    let methods = resolve_methods(&args.methods, &faces[test].mesh)?;
    let mut results = Vec::new();
    for mu in &methods {
        if let Some(n) = &mu.note {
            eprintln!(
                "note: {} requested: {n}; using {}",
                mu.requested.name(),
                mu.used.name()
            );
        }
        results.push(run_method(&args, &faces, &walkers, test, mu.used, &out)?);
    }
    write_report(&args, &faces, test, &methods, &results, &out, t0)?;
    println!("{}", out.display());
    Ok(())
}

#[allow(clippy::too_many_lines)]
fn run_method(
    args: &Args,
    faces: &[Face],
    walkers: &[Walker<'_>],
    test: usize,
    method: Method,
    out: &std::path::Path,
) -> Result<MethodResults> {
    let t0 = Instant::now();
    let mname = method.name();
    let n = args.levels;
    let nf = faces.len();
    std::fs::create_dir_all(out)?;
    // Solvers and base fields.
    let pb = bar(nf, &format!("{mname}: base fields"));
    let prepared: Vec<(Box<dyn GeodesicSolver>, Refs, Vec<f64>)> = faces
        .par_iter()
        .map(|f| -> Result<_> {
            let solver = geodesic::new_solver(&f.mesh, method)?;
            let lm = f.landmarks;
            let ur = field(solver.as_ref(), Source::Vertex(lm.right_eye_outer))?;
            let uq = field(solver.as_ref(), Source::Vertex(lm.left_eye_outer))?;
            let un = field(solver.as_ref(), Source::Vertex(lm.nose_tip))?;
            let d = 0.5 * (ur[lm.left_eye_outer as usize] + uq[lm.right_eye_outer as usize]);
            let (r, q, nose) = (
                f.mesh.position(lm.right_eye_outer),
                f.mesh.position(lm.left_eye_outer),
                f.mesh.position(lm.nose_tip),
            );
            let frame = face_frame(&f.mesh, r, q, nose);
            pb.inc(1);
            Ok((
                solver,
                Refs {
                    ur,
                    uq,
                    d,
                    r,
                    q,
                    nose,
                    frame,
                },
                un,
            ))
        })
        .collect::<Result<_>>()?;
    pb.finish();
    let refs: Vec<&Refs> = prepared.iter().map(|p| &p.1).collect();
    let mut res = MethodResults {
        name: mname.to_string(),
        ..Default::default()
    };
    res.d = refs.iter().map(|r| r.d).collect();
    let polar_opts = |r: &Refs| PolarOptions {
        step: r.d / f64::from(n),
        levels: n,
        sectors: args.sectors,
    };
    let eye_mid = |r: &Refs| 0.5 * (r.r + r.q);

    // 1. Renders (test face).
    {
        let f = &faces[test];
        let rf = refs[test];
        for &nl in &[5u32, 10, 30] {
            let step = rf.d / f64::from(nl);
            let maxu = rf
                .ur
                .iter()
                .chain(&rf.uq)
                .copied()
                .filter(|x| x.is_finite())
                .fold(0.0, f64::max);
            let levels: Vec<f64> = (1..)
                .map(|i| f64::from(i) * step)
                .take_while(|l| *l < maxu)
                .collect();
            let cr = isoline_segments(&f.mesh, &rf.ur, &levels).concat();
            let cq = isoline_segments(&f.mesh, &rf.uq, &levels).concat();
            let desc = bipolar(&f.mesh, rf, nl, Region::Whole);
            let ov = Overlay {
                segments: vec![("#c0392b".into(), cr), ("#2471a3".into(), cq)],
                points: vec![
                    (
                        "#f1c40f".into(),
                        if nl >= 30 { 1.3 } else { 2.6 },
                        desc.points.clone(),
                    ),
                    ("#27ae60".into(), 5.0, vec![rf.r, rf.q]),
                ],
                highlight: None,
            };
            render(
                &out.join(format!("render_{mname}_levels{nl}.svg")),
                &format!(
                    "{}: {nl} levels between the corners ({} points, {mname})",
                    f.name,
                    desc.len()
                ),
                &f.mesh,
                rf.frame.up,
                rf.frame.forward,
                &ov,
            )?;
        }
        let mask = static_mask(&f.mesh, &rf.ur, &rf.uq, rf.d, &rf.frame, rf.nose);
        let ds = bipolar(&f.mesh, rf, n, Region::Static);
        let dw = bipolar(&f.mesh, rf, n, Region::Whole);
        render(
            &out.join(format!("render_{mname}_static.svg")),
            &format!(
                "{}: static area (blue) and its {} descriptor points, N = {n}",
                f.name,
                ds.len()
            ),
            &f.mesh,
            rf.frame.up,
            rf.frame.forward,
            &Overlay {
                segments: vec![],
                points: vec![
                    ("#bbbbbb".into(), 1.6, dw.points.clone()),
                    ("#e67e22".into(), 2.8, ds.points.clone()),
                    ("#27ae60".into(), 5.0, vec![rf.r, rf.q, rf.nose]),
                ],
                highlight: Some(mask),
            },
        )?;
    }

    // 2. Distance against resolution, and matrices at the default resolution.
    let pb = bar(RESOLUTIONS.len(), &format!("{mname}: resolution sweep"));
    let sweep_descs: Vec<Vec<KeyedPoints>> = RESOLUTIONS
        .iter()
        .map(|&nl| {
            let v = faces
                .par_iter()
                .zip(&refs)
                .map(|(f, r)| bipolar(&f.mesh, r, nl, Region::Static))
                .collect();
            pb.inc(1);
            v
        })
        .collect();
    pb.finish();
    for (k, &nl) in RESOLUTIONS.iter().enumerate() {
        let ds = &sweep_descs[k];
        let row: Vec<f64> = (0..nf)
            .map(|j| {
                if j == test {
                    0.0
                } else {
                    dist(&ds[test], &ds[j])
                }
            })
            .collect();
        res.sweep.push((nl, row));
    }
    let base_static: Vec<KeyedPoints> = faces
        .par_iter()
        .zip(&refs)
        .map(|(f, r)| bipolar(&f.mesh, r, n, Region::Static))
        .collect();
    let base_whole: Vec<KeyedPoints> = faces
        .par_iter()
        .zip(&refs)
        .map(|(f, r)| bipolar(&f.mesh, r, n, Region::Whole))
        .collect();
    res.n_points = base_static
        .iter()
        .zip(&base_whole)
        .map(|(a, b)| (a.len(), b.len()))
        .collect();
    res.m_static = matrix(&base_static);
    res.m_whole = matrix(&base_whole);
    let base_polar: Vec<KeyedPoints> = (0..nf)
        .into_par_iter()
        .map(|i| {
            polar_descriptor(
                &walkers[i],
                &prepared[i].2,
                Pole::Vertex(faces[i].landmarks.nose_tip),
                eye_mid(refs[i]),
                &polar_opts(refs[i]),
            )
        })
        .collect::<Result<_>>()?;
    res.m_polar = matrix(&base_polar);

    // 3. Perturbation grid on the test face (left outer eye corner and, for the single pole, the
    // nose tip), by radius x direction.
    let tf = &faces[test];
    let tr = refs[test];
    let tsolver = prepared[test].0.as_ref();
    let cells: Vec<(f64, f64)> = RADII_PCT
        .iter()
        .flat_map(|&p| {
            (0..N_DIRS).map(move |k| (p, std::f64::consts::TAU * k as f64 / N_DIRS as f64))
        })
        .collect();
    let pb = bar(cells.len(), &format!("{mname}: perturbation grid"));
    // For each cell: perturbed refs for the bipolar descriptor, and the perturbed polar descriptor.
    let grid: Vec<GridCell> = cells
        .par_iter()
        .map(|&(pct, theta)| -> Result<_> {
            let radius = pct / 100.0 * tr.d;
            let lm = tf.landmarks;
            let w = &walkers[test];
            let (sp, cut_q) = perturb(w, lm.left_eye_outer, tr.r, radius, theta)?;
            let uq = field(tsolver, Source::Point(sp))?;
            let q = tf.mesh.point_position(&sp)?;
            let d = 0.5 * (uq[lm.right_eye_outer as usize] + field_at(&tf.mesh, &tr.ur, &sp));
            let frame = face_frame(&tf.mesh, tr.r, q, tr.nose);
            let pr = Refs {
                ur: tr.ur.clone(),
                uq,
                d,
                r: tr.r,
                q,
                nose: tr.nose,
                frame,
            };
            let (spn, cut_n) = perturb(w, lm.nose_tip, eye_mid(tr), radius, theta)?;
            let un = field(tsolver, Source::Point(spn))?;
            let pol = polar_descriptor(w, &un, Pole::Point(spn), eye_mid(tr), &polar_opts(tr))?;
            pb.inc(1);
            Ok((pr, pol, cut_q, cut_n))
        })
        .collect::<Result<_>>()?;
    pb.finish();
    // Walks stopped by the boundary (the eye opening) did not move the point by the radius:
    // their cells are left out (NaN) and counted.
    for (c, (pr, pol, cut_q, cut_n)) in cells.iter().zip(&grid) {
        let db = if *cut_q {
            f64::NAN
        } else {
            dist(
                &base_static[test],
                &bipolar(&tf.mesh, pr, n, Region::Static),
            )
        };
        res.grid_bip.push((c.0, c.1, db));
        res.grid_pol.push((
            c.0,
            c.1,
            if *cut_n {
                f64::NAN
            } else {
                dist(&base_polar[test], pol)
            },
        ));
    }
    res.truncated = (
        grid.iter().filter(|g| g.2).count(),
        grid.iter().filter(|g| g.3).count(),
    );
    // Figure 11: the three cases against resolution.
    let same: Vec<usize> = (0..nf)
        .filter(|&j| j != test && faces[j].person == faces[test].person)
        .collect();
    let other: Vec<usize> = (0..nf)
        .filter(|&j| faces[j].person != faces[test].person)
        .collect();
    for (k, &nl) in RESOLUTIONS.iter().enumerate() {
        let ds = &sweep_descs[k];
        let pert: Vec<f64> = grid
            .par_iter()
            .filter(|g| !g.2)
            .map(|g| dist(&ds[test], &bipolar(&tf.mesh, &g.0, nl, Region::Static)))
            .collect();
        let e: Vec<f64> = same.iter().map(|&j| dist(&ds[test], &ds[j])).collect();
        let o: Vec<f64> = other.iter().map(|&j| dist(&ds[test], &ds[j])).collect();
        res.fig11.push((
            nl,
            [
                mean(&pert),
                max(&pert),
                mean(&e),
                min(&e),
                mean(&o),
                min(&o),
            ],
        ));
    }

    // 4. Random errors: on the left corner only, on both corners, on the nose tip.
    let pb = bar(nf, &format!("{mname}: random errors"));
    let rand_runs: Vec<(KeyedPoints, KeyedPoints, KeyedPoints, f64)> = (0..nf)
        .into_par_iter()
        .map(|i| -> Result<_> {
            let f = &faces[i];
            let r0 = refs[i];
            let w = &walkers[i];
            let s = prepared[i].0.as_ref();
            let lm = f.landmarks;
            let mut rng = ChaCha8Rng::seed_from_u64(
                args.seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
            );
            // A draw whose walk meets the boundary (eye opening) is redrawn (up to 50 times).
            let draw = |rng: &mut ChaCha8Rng,
                        v: u32,
                        towards: DVec3|
             -> Result<(f64, f64, SurfacePoint)> {
                let mut last = None;
                for _ in 0..50 {
                    let rad = rng.random_range(0.0..0.05) * r0.d;
                    let th = rng.random_range(0.0..std::f64::consts::TAU);
                    let (sp, cut) = perturb(w, v, towards, rad, th)?;
                    last = Some((rad, th, sp));
                    if !cut {
                        break;
                    }
                }
                last.ok_or_else(|| anyhow::anyhow!("no perturbation drawn"))
            };
            // One corner (q).
            let (rad, th, spq) = draw(&mut rng, lm.left_eye_outer, r0.r)?;
            let uq = field(s, Source::Point(spq))?;
            let q = f.mesh.point_position(&spq)?;
            let d1 = 0.5 * (uq[lm.right_eye_outer as usize] + field_at(&f.mesh, &r0.ur, &spq));
            let one = Refs {
                ur: r0.ur.clone(),
                uq: uq.clone(),
                d: d1,
                r: r0.r,
                q,
                nose: r0.nose,
                frame: face_frame(&f.mesh, r0.r, q, r0.nose),
            };
            let d_one = bipolar(&f.mesh, &one, n, Region::Static);
            // Both corners (q as above, r moved independently).
            let (_, _, spr) = draw(&mut rng, lm.right_eye_outer, r0.q)?;
            let ur = field(s, Source::Point(spr))?;
            let r = f.mesh.point_position(&spr)?;
            let d2 = 0.5 * (field_at(&f.mesh, &ur, &spq) + field_at(&f.mesh, &uq, &spr));
            let both = Refs {
                ur,
                uq,
                d: d2,
                r,
                q,
                nose: r0.nose,
                frame: face_frame(&f.mesh, r, q, r0.nose),
            };
            let d_both = bipolar(&f.mesh, &both, n, Region::Static);
            // Nose tip, with the same radius/direction draw as the single corner.
            let (spn, _) = perturb(w, lm.nose_tip, eye_mid(r0), rad, th)?;
            let un = field(s, Source::Point(spn))?;
            let pol = polar_descriptor(w, &un, Pole::Point(spn), eye_mid(r0), &polar_opts(r0))?;
            pb.inc(1);
            Ok((d_one, d_both, pol, 100.0 * rad / r0.d))
        })
        .collect::<Result<_>>()?;
    pb.finish();
    let pick = |k: usize| -> Vec<KeyedPoints> {
        rand_runs
            .iter()
            .map(|r| match k {
                0 => r.0.clone(),
                1 => r.1.clone(),
                _ => r.2.clone(),
            })
            .collect()
    };
    res.m_rand_one = matrix(&pick(0));
    res.m_rand_both = matrix(&pick(1));
    res.m_rand_nose = matrix(&pick(2));
    res.rand_one_pct = rand_runs.iter().map(|r| r.3).collect();
    res.seconds = t0.elapsed().as_secs_f64();
    Ok(res)
}

fn finite(v: &[f64]) -> Vec<f64> {
    v.iter().copied().filter(|x| x.is_finite()).collect()
}
/// Mean of the finite values (NaN if none).
/// One line of figures 9 and 17: over the perturbation grid `(radius %, direction, distance)`,
/// the distances at each radius reduced by `agg` (mean or max over the directions).
fn radius_series(
    label: &str,
    grid: &[(f64, f64, f64)],
    agg: fn(&[f64]) -> f64,
    dashed: bool,
) -> Series {
    Series {
        label: label.into(),
        points: RADII_PCT
            .iter()
            .map(|&p| {
                let at: Vec<f64> = grid.iter().filter(|g| g.0 == p).map(|g| g.2).collect();
                (p, agg(&at))
            })
            .collect(),
        dashed,
    }
}

fn mean(v: &[f64]) -> f64 {
    let f = finite(v);
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}
/// Max of the finite values (NaN if none).
fn max(v: &[f64]) -> f64 {
    finite(v).into_iter().reduce(f64::max).unwrap_or(f64::NAN)
}
/// Min of the finite values (NaN if none).
fn min(v: &[f64]) -> f64 {
    finite(v).into_iter().reduce(f64::min).unwrap_or(f64::NAN)
}

fn matrix_rows(faces: &[Face], m: &[Vec<f64>]) -> Vec<Vec<String>> {
    faces
        .iter()
        .zip(m)
        .map(|(f, row)| {
            std::iter::once(f.name.clone())
                .chain(row.iter().map(|v| format!("{v:.6}")))
                .collect()
        })
        .collect()
}

/// Figure 15: rotating some polar rings individually keeps every per-ring distance ~0 while the
/// global distance becomes large. Returns (per-ring distances, global distance, reference
/// distance to another person) and writes a render.
/// Figure-15 numbers: per-ring distances, global distance, distance to another person.
type Figure15 = (Vec<(u32, f64)>, f64, f64);

#[allow(clippy::too_many_arguments)]
fn figure15(
    faces: &[Face],
    test: usize,
    other: usize,
    method: Method,
    levels: u32,
    sectors: u32,
    seed: u64,
    out: &std::path::Path,
) -> Result<Figure15> {
    let descs: Vec<(KeyedPoints, FaceFrame)> = [test, other]
        .par_iter()
        .map(|&i| -> Result<_> {
            let f = &faces[i];
            let lm = f.landmarks;
            let s = geodesic::new_solver(&f.mesh, method)?;
            let un = field(s.as_ref(), Source::Vertex(lm.nose_tip))?;
            let ur = field(s.as_ref(), Source::Vertex(lm.right_eye_outer))?;
            let d = ur[lm.left_eye_outer as usize];
            let (r, q, nose) = (
                f.mesh.position(lm.right_eye_outer),
                f.mesh.position(lm.left_eye_outer),
                f.mesh.position(lm.nose_tip),
            );
            let w = Walker::new(&f.mesh);
            let opts = PolarOptions {
                step: d / f64::from(levels),
                levels,
                sectors,
            };
            Ok((
                polar_descriptor(&w, &un, Pole::Vertex(lm.nose_tip), 0.5 * (r + q), &opts)?,
                face_frame(&f.mesh, r, q, nose),
            ))
        })
        .collect::<Result<_>>()?;
    let (s, frame) = &descs[0];
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut s1 = s.clone();
    let rotated = [2u32, 4, 6];
    for &lvl in &rotated {
        let idx: Vec<usize> = (0..s.len())
            .filter(|&k| polar_key_parts(s.keys[k]).0 == lvl)
            .collect();
        if idx.is_empty() {
            continue;
        }
        let c = idx.iter().map(|&k| s.points[k]).sum::<DVec3>() / idx.len() as f64;
        let axis = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or_zero();
        let angle = rng.random_range(0.5..1.5);
        let rot = DMat3::from_quat(DQuat::from_axis_angle(
            if axis == DVec3::ZERO { DVec3::Z } else { axis },
            angle,
        ));
        for &k in &idx {
            s1.points[k] = c + rot * (s.points[k] - c);
        }
    }
    let mut per_ring = Vec::new();
    for lvl in 1..=levels {
        let idx: Vec<usize> = (0..s.len())
            .filter(|&k| polar_key_parts(s.keys[k]).0 == lvl && !s.ambiguous[k])
            .collect();
        let a: Vec<DVec3> = idx.iter().map(|&k| s.points[k]).collect();
        let b: Vec<DVec3> = idx.iter().map(|&k| s1.points[k]).collect();
        per_ring.push((lvl, paired_distance(&a, &b).unwrap_or(f64::NAN)));
    }
    let global = dist(s, &s1);
    let reference = dist(s, &descs[1].0);
    let moved: Vec<DVec3> = (0..s.len())
        .filter(|&k| rotated.contains(&polar_key_parts(s.keys[k]).0))
        .map(|k| s1.points[k])
        .collect();
    render(
        &out.join("figure15.svg"),
        "Figure 15: polar rings (blue) and rings 2, 4, 6 rotated individually (red)",
        &faces[test].mesh,
        frame.up,
        frame.forward,
        &Overlay {
            segments: vec![],
            points: vec![
                ("#2471a3".into(), 2.2, s.points.clone()),
                ("#c0392b".into(), 2.6, moved),
            ],
            highlight: None,
        },
    )?;
    Ok((per_ring, global, reference))
}

#[allow(clippy::too_many_lines)]
fn write_report(
    args: &Args,
    faces: &[Face],
    test: usize,
    methods: &[MethodUse],
    results: &[MethodResults],
    out: &std::path::Path,
    t0: Instant,
) -> Result<()> {
    let n = args.levels;
    let mut rep = Report::new(
        out,
        "The bipolar representation on faces: the paper's sections 4-6",
    )?;
    let labels: Vec<String> = faces.iter().map(|f| f.name.clone()).collect();
    let persons: std::collections::BTreeSet<&str> =
        faces.iter().map(|f| f.person.as_str()).collect();
    rep.para(&format!(
        "Face set: {} faces ({} persons) from `{}`; test face `{}`. Reference points: the \
         ground-truth outer eye corners (vertices 1507 right = r, 3721 left = q) and the nose tip \
         (4857) for the single-pole comparison. D = geodesic distance between the corners; N = {n} \
         levels between them (step D/N) unless a figure varies N. Shape distance: keyed L2 after \
         the optimal rotation, normalised to [0, 1] (see `docs/experiments.md`). Random seed {}.",
        faces.len(),
        persons.len(),
        args.faces
            .clone()
            .unwrap_or_else(default_paper_set)
            .display(),
        faces[test].name,
        args.seed
    ));
    let desc_note = match args.descriptor {
        DescriptorImpl::CrateAll => "Descriptor: `bipolar::describe_fields` with selection rule `All` (every intersection of level i of U_r with level j of U_q, keys (i, j, side)): the grid reading of the paper, no angle filter (method notes 4). `--descriptor crate-iso-angle` gives the iso-angle rule B instead.".to_string(),
        DescriptorImpl::CrateIsoAngle => "Descriptor: `bipolar::describe_fields` with the iso-angle rule B (K = 8, alpha = 0.95, gradient tangents), keys (i, k, side, sign).".to_string(),
        DescriptorImpl::Local => "Descriptor: the local grid implementation in `xtask/src/experiments/descriptor.rs` (every intersection, keys (i, j, side)), used as a cross-check of the `bipolar` crate.".to_string(),
    };
    let mut notes = vec![
        desc_note,
        format!("Descriptors the `bipolar` crate refused (e.g. no intersection in range; counted as empty, so their distances are n/a): {}.", crate_failures()),
        "Distance: `shapedist::keyed_distance` (Kabsch closed form, no residual gate) on the unambiguous keys; a key found twice on a face is never paired.".to_string(),
        "Pictures: SVG written by `xtask/src/experiments/report.rs`, each with a PNG twin rasterised by `viz::svg_to_png`.".to_string(),
    ];
    for m in methods {
        if let Some(note) = &m.note {
            notes.push(format!("Geodesic method **{}** was requested but {note}; **{}** was used in its place, and its results are labelled `{}`.", m.requested.name(), m.used.name(), m.used.name()));
        }
    }
    rep.heading(2, "What was available");
    rep.para(
        &notes
            .iter()
            .map(|s| format!("- {s}"))
            .collect::<Vec<_>>()
            .join("\n"),
    );
    let names: Vec<&str> = results.iter().map(|r| r.name.as_str()).collect();

    // D per face.
    rep.heading(2, "Reference distances and point counts");
    let mut rows = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        let mut r = vec![f.name.clone()];
        for res in results {
            r.push(format!("{:.3}", res.d[i]));
            r.push(format!("{} / {}", res.n_points[i].0, res.n_points[i].1));
        }
        rows.push(r);
    }
    let mut header = vec!["face".to_string()];
    for nm in &names {
        header.push(format!("D ({nm}, cm)"));
        header.push(format!("points static / whole ({nm})"));
    }
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    rep.table(&hdr, &rows);
    rep.csv("reference_distances.csv", &hdr, &rows)?;

    // 1. Renders.
    rep.heading(
        2,
        "1. Level curves, descriptor points and the static area (figures 4, 5)",
    );
    rep.para("Red: level curves of U_r (right outer eye corner); blue: of U_q (left); yellow: descriptor points (levels up to 2N); green: reference points. The static area (blue tint) is the set of vertices within D of both corners and above the horizontal plane through the nose tip (`docs/experiments.md`); orange points are the descriptor restricted to it.");
    for res in results {
        for nl in [5, 10, 30] {
            rep.figure(
                &format!("render_{}_levels{nl}.svg", res.name),
                &format!(
                    "{}: {nl} level curves between the corners ({})",
                    faces[test].name, res.name
                ),
            );
        }
        rep.figure(
            &format!("render_{}_static.svg", res.name),
            &format!(
                "static area and restricted descriptor, N = {n} ({})",
                res.name
            ),
        );
    }

    // 2. Resolution sweep and matrix.
    rep.heading(
        2,
        "2. Shape distance against resolution (figure 6) and the 12 x 12 matrix (figure 7)",
    );
    for res in results {
        let mut series = Vec::new();
        for j in 0..faces.len() {
            if j == test {
                continue;
            }
            series.push(Series {
                label: faces[j].name.clone(),
                points: res
                    .sweep
                    .iter()
                    .map(|(nl, row)| (f64::from(*nl), row[j]))
                    .collect(),
                dashed: faces[j].person != faces[test].person,
            });
        }
        let file = format!("fig6_distance_vs_resolution_{}.svg", res.name);
        line_plot(
            &rep.path(&file),
            &format!(
                "{} vs every other face, static area ({})",
                faces[test].name, res.name
            ),
            "levels N between the corners",
            "normalised shape distance",
            &series,
        )?;
        rep.figure(&file, &format!("distance from the test face against resolution; solid: same person, dashed: other persons ({})", res.name));
        let mut hdr = vec!["N".to_string()];
        hdr.extend(faces.iter().map(|f| f.name.clone()));
        let rows: Vec<Vec<String>> = res
            .sweep
            .iter()
            .map(|(nl, row)| {
                std::iter::once(nl.to_string())
                    .chain(row.iter().map(|v| format!("{v:.6}")))
                    .collect()
            })
            .collect();
        let h: Vec<&str> = hdr.iter().map(String::as_str).collect();
        rep.csv(&format!("fig6_{}.csv", res.name), &h, &rows)?;
    }
    let mut sep_rows = Vec::new();
    for res in results {
        for (label, m, file) in [
            ("static area", &res.m_static, "static"),
            ("whole face (levels up to 2N)", &res.m_whole, "whole"),
        ] {
            let fname = format!("fig7_matrix_{file}_{}.svg", res.name);
            heatmap(
                &rep.path(&fname),
                &format!("pairwise distances, {label}, N = {n} ({})", res.name),
                &labels,
                m,
                "distance",
            )?;
            let mut h = vec!["face".to_string()];
            h.extend(labels.iter().cloned());
            let hh: Vec<&str> = h.iter().map(String::as_str).collect();
            rep.csv(
                &format!("fig7_matrix_{file}_{}.csv", res.name),
                &hh,
                &matrix_rows(faces, m),
            )?;
            rep.figure(&fname, &format!("12 x 12 matrix, {label} ({})", res.name));
            let s = Sep::of(m, faces, test);
            sep_rows.push(vec![
                res.name.clone(),
                label.to_string(),
                f4(s.max_same),
                f4(s.min_diff),
                format!("{:.3}", s.ratio()),
                s.verdict().into(),
                f4(s.row_max_same),
                f4(s.row_min_diff),
                format!("{:.3}", s.row_ratio()),
                s.row_verdict().into(),
            ]);
        }
    }
    rep.para("Separation: the largest distance between two faces of the same person, the smallest between faces of different persons, and their ratio (> 1 means every same-person pair is closer than every different-person pair). 'Test row' restricts this to the pairs involving the neutral test face, which is what the paper's figure 6 shows.");
    let sep_hdr = [
        "method",
        "descriptor",
        "max same",
        "min different",
        "ratio",
        "whole matrix",
        "test row: max same",
        "test row: min different",
        "test-row ratio",
        "test row",
    ];
    rep.table(&sep_hdr, &sep_rows);
    rep.csv("separation.csv", &sep_hdr, &sep_rows)?;

    // 3. Robustness.
    rep.heading(2, "3. Robustness to reference-point errors (figures 9-13)");
    rep.para(&format!("The left outer eye corner q of `{}` is moved along a straightest geodesic of length {}% of D, leaving at angle theta from the direction towards r (counter-clockwise about the outward normal); its distance field is recomputed from the moved surface point, D is recomputed, and the static descriptor at N = {n} is compared with the original one.", faces[test].name, RADII_PCT.iter().map(|p| format!("{p}")).collect::<Vec<_>>().join(", ")));
    for res in results {
        rep.para(&format!("{}: {} of {} corner walks and {} nose-tip walks met the mesh boundary (the eye opening) before the full radius; those cells are left out (blank in the plots, NaN in the CSV).", res.name, res.truncated.0, RADII_PCT.len() * N_DIRS, res.truncated.1));
        let series: Vec<Series> = RADII_PCT
            .iter()
            .map(|&p| Series {
                label: format!("radius {p}% of D"),
                points: res
                    .grid_bip
                    .iter()
                    .filter(|g| g.0 == p)
                    .map(|g| (g.1.to_degrees(), g.2))
                    .collect(),
                dashed: false,
            })
            .collect();
        let f10 = format!("fig10_grid_{}.svg", res.name);
        line_plot(
            &rep.path(&f10),
            &format!("perturbed vs original, by direction ({})", res.name),
            "direction theta (degrees from r)",
            "normalised shape distance",
            &series,
        )?;
        let by_r = vec![
            radius_series("mean over directions", &res.grid_bip, mean, false),
            radius_series("max over directions", &res.grid_bip, max, true),
        ];
        let f9 = format!("fig9_radius_{}.svg", res.name);
        line_plot(
            &rep.path(&f9),
            &format!("perturbed vs original, by radius ({})", res.name),
            "radius (% of D)",
            "normalised shape distance",
            &by_r,
        )?;
        rep.figure(
            &f9,
            &format!("distance against the error radius ({})", res.name),
        );
        rep.figure(
            &f10,
            &format!("distance over the radius x direction grid ({})", res.name),
        );
        let rows: Vec<Vec<String>> = res
            .grid_bip
            .iter()
            .zip(&res.grid_pol)
            .map(|(b, p)| {
                vec![
                    format!("{}", b.0),
                    format!("{:.1}", b.1.to_degrees()),
                    format!("{:.6}", b.2),
                    format!("{:.6}", p.2),
                ]
            })
            .collect();
        rep.csv(
            &format!("fig9_10_grid_{}.csv", res.name),
            &[
                "radius_pct",
                "theta_deg",
                "bipolar_distance",
                "single_pole_distance",
            ],
            &rows,
        )?;
    }
    // Figure 11.
    rep.para("Figure 11, the paper's three cases against resolution: (a) perturbed vs original (the 40 grid perturbations), (b) the test face vs the same person's other expressions, (c) vs other persons. The ordering a < b < c is checked on the means and, more strictly, as max(a) < min(b) and min(b)... (strict: max a < min b, and mean b < min c).");
    let mut rows = Vec::new();
    for res in results {
        let s = vec![
            Series {
                label: "(a) perturbed, mean".into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[0]))
                    .collect(),
                dashed: false,
            },
            Series {
                label: "(a) perturbed, max".into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[1]))
                    .collect(),
                dashed: true,
            },
            Series {
                label: "(b) expressions, mean".into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[2]))
                    .collect(),
                dashed: false,
            },
            Series {
                label: "(b) expressions, min".into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[3]))
                    .collect(),
                dashed: true,
            },
            Series {
                label: "(c) other persons, mean".into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[4]))
                    .collect(),
                dashed: false,
            },
            Series {
                label: "(c) other persons, min".into(),
                points: res
                    .fig11
                    .iter()
                    .map(|(nl, v)| (f64::from(*nl), v[5]))
                    .collect(),
                dashed: true,
            },
        ];
        let f11 = format!("fig11_three_cases_{}.svg", res.name);
        line_plot(
            &rep.path(&f11),
            &format!("three cases against resolution ({})", res.name),
            "levels N between the corners",
            "normalised shape distance",
            &s,
        )?;
        rep.figure(
            &f11,
            &format!("the three cases of figure 11 ({})", res.name),
        );
        for (nl, v) in &res.fig11 {
            let mean_order = v[0] < v[2] && v[2] < v[4];
            let strict = v[1] < v[3] && v[2] < v[5];
            rows.push(vec![
                res.name.clone(),
                nl.to_string(),
                f4(v[0]),
                f4(v[1]),
                f4(v[2]),
                f4(v[3]),
                f4(v[4]),
                f4(v[5]),
                if mean_order { "yes" } else { "NO" }.into(),
                if strict { "yes" } else { "NO" }.into(),
            ]);
        }
    }
    let h11 = [
        "method",
        "N",
        "a mean",
        "a max",
        "b mean",
        "b min",
        "c mean",
        "c min",
        "a < b < c (means)",
        "max a < min b and mean b < min c",
    ];
    rep.table(&h11, &rows);
    rep.csv("fig11_three_cases.csv", &h11, &rows)?;
    // Figures 12-13.
    rep.para(&format!("Figures 12 and 13: every face gets its own random error (seeded), radius uniform in [0, 5%] of D and a uniform direction: on q only, then on both r and q (independent draws); the 12 x 12 matrices are computed between the perturbed descriptors (N = {n}, static area)."));
    let mut rows = Vec::new();
    for res in results {
        for (label, m, file) in [
            ("error on q", &res.m_rand_one, "fig12_random_one"),
            ("errors on r and q", &res.m_rand_both, "fig13_random_both"),
        ] {
            let fname = format!("{file}_{}.svg", res.name);
            heatmap(
                &rep.path(&fname),
                &format!("{label}, static area, N = {n} ({})", res.name),
                &labels,
                m,
                "distance",
            )?;
            let mut h = vec!["face".to_string()];
            h.extend(labels.iter().cloned());
            let hh: Vec<&str> = h.iter().map(String::as_str).collect();
            rep.csv(
                &format!("{file}_{}.csv", res.name),
                &hh,
                &matrix_rows(faces, m),
            )?;
            rep.figure(&fname, &format!("{label} ({})", res.name));
            let s = Sep::of(m, faces, test);
            rows.push(vec![
                res.name.clone(),
                label.into(),
                f4(s.max_same),
                f4(s.min_diff),
                format!("{:.3}", s.ratio()),
                s.verdict().into(),
                format!("{:.3}", s.row_ratio()),
                s.row_verdict().into(),
            ]);
        }
    }
    let h12 = [
        "method",
        "errors",
        "max same",
        "min different",
        "ratio",
        "whole matrix",
        "test-row ratio",
        "test row",
    ];
    rep.table(&h12, &rows);
    rep.csv("fig12_13_separation.csv", &h12, &rows)?;

    // 4. Single pole.
    rep.heading(
        2,
        "4. Single-pole representation around the nose tip (figures 15-17)",
    );
    rep.para(&format!("Geodesic polar coordinates around the nose tip: {} rays (straightest geodesics at equal angles from the direction towards the eye-corner midpoint) and N = {n} radius levels of step D/N (radius from the same solver's distance field); keys (level, sector). Under the same perturbation grid the nose tip is moved by the same geodesic distances (directions measured from the eye-midpoint direction).", args.sectors));
    let mut rows = Vec::new();
    for res in results {
        let series = vec![
            radius_series("bipolar (q moved), mean", &res.grid_bip, mean, false),
            radius_series("single pole (nose moved), mean", &res.grid_pol, mean, false),
            radius_series("bipolar, max", &res.grid_bip, max, true),
            radius_series("single pole, max", &res.grid_pol, max, true),
        ];
        let f = format!("fig17_pole_vs_bipolar_{}.svg", res.name);
        line_plot(
            &rep.path(&f),
            &format!(
                "reference-point error: bipolar vs single pole ({})",
                res.name
            ),
            "error radius (% of D)",
            "distance to the unperturbed descriptor",
            &series,
        )?;
        rep.figure(
            &f,
            &format!(
                "bipolar vs single pole under the same errors ({})",
                res.name
            ),
        );
        for (label, m, file) in [
            ("single pole, no error", &res.m_polar, "matrix_pole"),
            (
                "single pole, random error on the nose tip (fig. 17a)",
                &res.m_rand_nose,
                "fig17a_random_nose",
            ),
            ("bipolar, random error on q (fig. 17b)", &res.m_rand_one, ""),
        ] {
            if !file.is_empty() {
                let fname = format!("{file}_{}.svg", res.name);
                heatmap(
                    &rep.path(&fname),
                    &format!("{label} ({})", res.name),
                    &labels,
                    m,
                    "distance",
                )?;
                let mut h = vec!["face".to_string()];
                h.extend(labels.iter().cloned());
                let hh: Vec<&str> = h.iter().map(String::as_str).collect();
                rep.csv(
                    &format!("{file}_{}.csv", res.name),
                    &hh,
                    &matrix_rows(faces, m),
                )?;
                rep.figure(&fname, &format!("{label} ({})", res.name));
            }
            let s = Sep::of(m, faces, test);
            rows.push(vec![
                res.name.clone(),
                label.into(),
                f4(s.max_same),
                f4(s.min_diff),
                format!("{:.3}", s.ratio()),
                format!("{:.3}", s.row_ratio()),
            ]);
        }
        let gb: Vec<f64> = res.grid_bip.iter().map(|g| g.2).collect();
        let gp: Vec<f64> = res.grid_pol.iter().map(|g| g.2).collect();
        rep.para(&format!("{}: over the 40 grid perturbations, bipolar mean {} (max {}), single pole mean {} (max {}); the bipolar representation is {} robust here.", res.name, f4(mean(&gb)), f4(max(&gb)), f4(mean(&gp)), f4(max(&gp)), if mean(&gb) < mean(&gp) { "more" } else { "NOT more" }));
    }
    let h17 = [
        "method",
        "matrix",
        "max same",
        "min different",
        "ratio",
        "test-row ratio",
    ];
    rep.table(&h17, &rows);
    rep.csv("fig17_separation.csv", &h17, &rows)?;
    // Figure 15 argument.
    let other = faces
        .iter()
        .position(|f| f.person != faces[test].person)
        .unwrap_or(test);
    let (per_ring, global, reference) = figure15(
        faces,
        test,
        other,
        methods[0].used,
        n,
        args.sectors,
        args.seed,
        out,
    )?;
    rep.para(&format!("Figure 15, on `{}` ({}): the polar rings 2, 4 and 6 are each rotated about their own centroid by a random rotation (0.5-1.5 rad). Aligning ring by ring (each ring with its own best rotation, as curve-by-curve methods do) gives distances ~0 for every ring, yet the global keyed distance between the two point sets is {}, {} the distance to another person (`{}`: {}).", faces[test].name, methods[0].used.name(), f4(global), if global > reference { "larger than" } else { "compared with" }, faces[other].name, f4(reference)));
    rep.table(
        &["ring", "per-ring distance"],
        &per_ring
            .iter()
            .map(|(l, d)| vec![l.to_string(), format!("{d:.2e}")])
            .collect::<Vec<_>>(),
    );
    rep.figure("figure15.svg", "figure 15: rings rotated individually");

    // 5. Exact vs Dijkstra.
    rep.heading(2, "5. What exactness changes");
    let mut rows = Vec::new();
    for res in results {
        let s = Sep::of(&res.m_static, faces, test);
        let gb: Vec<f64> = res.grid_bip.iter().map(|g| g.2).collect();
        rows.push(vec![
            res.name.clone(),
            format!("{:.3}", mean(&res.d)),
            format!("{:.3}", s.ratio()),
            format!("{:.3}", s.row_ratio()),
            f4(mean(&gb)),
            format!("{:.1}", res.seconds),
        ]);
    }
    rep.table(
        &[
            "method",
            "mean D (cm)",
            "static ratio (matrix)",
            "static ratio (test row)",
            "mean perturbation distance",
            "seconds",
        ],
        &rows,
    );
    if results.len() >= 2 {
        let (a, b) = (&results[0], &results[1]);
        let dd: Vec<f64> =
            a.d.iter()
                .zip(&b.d)
                .map(|(x, y)| (y - x) / x * 100.0)
                .collect();
        rep.para(&format!("D from {} exceeds D from {} by {:.2}% to {:.2}% across faces (edge paths overestimate).", b.name, a.name, min(&dd), max(&dd)));
    }
    let n_png = rep.png_twins()?;
    rep.para(&format!(
        "Total run time: {:.1} s ({n_png} figures, each as SVG and PNG).",
        t0.elapsed().as_secs_f64()
    ));
    rep.finish()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separation_figures() {
        let mk = |name: &str| Face {
            name: name.into(),
            person: name.split('_').next().unwrap().into(),
            expression: String::new(),
            mesh: crate::experiments::walk::tests::plane(1, 0.0, 0),
            landmarks: facemodel::FaceLandmarks::ground_truth(),
        };
        let faces = vec![mk("a_n"), mk("a_x"), mk("b_n"), mk("c_n")];
        let m = vec![
            vec![0.0, 0.1, 0.3, 0.2],
            vec![0.1, 0.0, 0.05, 0.4],
            vec![0.3, 0.05, 0.0, 0.5],
            vec![0.2, 0.4, 0.5, 0.0],
        ];
        let s = Sep::of(&m, &faces, 0);
        assert_eq!((s.max_same, s.min_diff), (0.1, 0.05));
        assert_eq!((s.row_max_same, s.row_min_diff), (0.1, 0.2));
        assert!((s.row_ratio() - 2.0).abs() < 1e-12 && s.verdict() == "NOT separated");
    }

    #[test]
    fn perturbation_moves_by_the_radius_on_a_plane() {
        let m = crate::experiments::walk::tests::plane(20, 0.2, 5);
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
        assert!((field_at(&m, &u, &sp) - q.x).abs() < 1e-12);
    }
}
