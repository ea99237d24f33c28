//! `cargo xtask recognition`: identification and verification on faces sampled from the ICT
//! face model, for the bipolar descriptor, the single-pole descriptor and ICP on the raw meshes,
//! each with ground-truth and with detected landmarks.
//!
//! N identities x M expressions are sampled (seeded); expression 0 of every identity is the
//! neutral face and forms the gallery, the M - 1 others are the probes. Every face is moved by
//! a random rigid motion, so nothing can rely on a shared frame. Scores are distances (lower =
//! more similar): rank-1 identification rate over the probes, verification EER over all
//! probe x gallery pairs, and the ROC curve. Results: `report.md`, `summary.json`, `roc.svg` (and `roc.png`),
//! CSV tables, in the output folder printed on the last line.

mod scans;

use crate::experiments::pipeline::{
    bar, bipolar, dist, resolve_methods, DescriptorRule, Refs, Region,
};
use crate::experiments::polar::{self, polar_descriptor, PolarOptions, Pole};
use crate::experiments::report::{f4, line_plot, Report, Series};
use crate::experiments::scans::ScanArgs;
use crate::experiments::walk::Walker;
use crate::paths::{default_model_dir, default_out_dir};
use anyhow::{bail, Context, Result};
use bipolar::PolarDescriptor;
use facemodel::{face_frame, random_rigid_motion, FaceModel};
use geodesic::{SolveOptions, Source};
use meshcore::linalg::fit_rigid;
use meshcore::{DVec3, FaceLocator, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use shapedist::{icp_to_target, Convergence, IcpLoopOptions, IcpVariant, TrimRounding};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `cargo xtask recognition`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Number of sampled identities (default 50; with `--scans` 12).
    #[arg(long)]
    pub identities: Option<usize>,
    /// Faces per identity, the first neutral for the gallery (default 6; with `--scans` 3).
    #[arg(long)]
    pub expressions: Option<usize>,
    /// Seed of the sampling.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Geodesic method (exact falls back to fmm, then heat, if unavailable).
    #[arg(long, default_value = "exact")]
    pub method: String,
    /// Levels between the reference points.
    #[arg(long, default_value_t = 10)]
    pub levels: u32,
    /// Sectors of the single-pole descriptor.
    #[arg(long, default_value_t = 16)]
    pub sectors: u32,
    /// Probe vertices used by ICP (evenly strided).
    #[arg(long, default_value_t = 100)]
    pub icp_points: usize,
    /// ICT model folder (default `$BIPOLAR_SHARED/faces/ict-facekit/model`).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Output folder (default `target/recognition`; with `--scans` `target/recognition-scans`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Recognition on range scans (`rangescan`, cleaned by `scanprep`): neutral frontal scans
    /// (the `--scan-*` settings) as the gallery, expressions under yaw and noise as probes, and
    /// sweeps of noise, pitch and yaw.
    #[arg(long)]
    pub scans: bool,
    /// Scanner settings of the gallery (and the reference of the sweeps) with `--scans`.
    #[command(flatten)]
    pub scan: ScanArgs,
    /// Identities whose probes are rescanned at every sweep setting (`--scans`).
    #[arg(long, default_value_t = 6)]
    pub sweep_identities: usize,
    /// Skip the sweeps (`--scans`).
    #[arg(long)]
    pub no_sweeps: bool,
}

/// One sampled face.
#[derive(Debug)]
struct Sample {
    identity: usize,
    index: usize,
    mesh: TriMesh,
}

/// Three reference vertices of a face.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lm {
    r: u32,
    q: u32,
    nose: u32,
}

/// Per face and landmark set: descriptors and landmark positions.
#[derive(Debug, Clone)]
struct Described {
    bip: Result<bipolar::Descriptor, String>,
    pol: PolarDescriptor,
    lm_pos: [DVec3; 3],
}

/// Descriptor settings of the benchmark.
#[derive(Debug, Clone, Copy)]
struct DescribeOptions {
    /// Levels N between the outer eye corners.
    levels: u32,
    /// Sectors of the single-pole descriptor.
    sectors: u32,
}

/// The bipolar (static area, grid reading) and single-pole descriptors of one face for one
/// landmark set. Only the static lens (within D of both corners, D ~ 1.1 |q - r|) and polar
/// radii up to D are used: the fields are cut off at 1.4 |q - r|. Errors name what failed
/// (a bipolar descriptor the crate refuses is kept as its error; an empty single-pole one is
/// the empty set).
fn describe_face(
    mesh: &TriMesh,
    solver: &dyn geodesic::GeodesicSolver,
    walker: &Walker<'_>,
    lm: Lm,
    o: &DescribeOptions,
) -> Result<Described, String> {
    if lm.r == lm.q {
        return Err(format!(
            "the two outer eye corners are the same vertex {}",
            lm.r
        ));
    }
    let (r, q, nose) = (
        mesh.position(lm.r),
        mesh.position(lm.q),
        mesh.position(lm.nose),
    );
    let cut = SolveOptions {
        max_distance: Some(1.4 * (q - r).length()),
    };
    let field = |v: u32| {
        solver
            .distances(&[Source::Vertex(v)], &cut)
            .map_err(|e| format!("geodesic field: {e}"))
    };
    let (ur, uq, un) = (field(lm.r)?, field(lm.q)?, field(lm.nose)?);
    let d = 0.5 * (ur[lm.q as usize] + uq[lm.r as usize]);
    if !d.is_finite() || d <= 0.0 {
        return Err(format!(
            "the geodesic distance between the outer eye corners is {d} (not reachable within 1.4 times their distance)"
        ));
    }
    let frame = face_frame(mesh, r, q, nose);
    let refs = Refs {
        ur,
        uq,
        d,
        r,
        q,
        nose,
        frame,
    };
    let bip = bipolar(
        mesh,
        &refs,
        o.levels,
        Region::Static,
        DescriptorRule::CrateAll,
    )
    .map_err(|e| format!("bipolar descriptor: {e}"));
    let opts = PolarOptions {
        step: d / f64::from(o.levels),
        levels: o.levels,
        sectors: o.sectors,
    };
    let pol = polar_descriptor(walker, &un, Pole::Vertex(lm.nose), 0.5 * (r + q), &opts)
        .unwrap_or_else(|_| polar::empty(&opts));
    Ok(Described {
        bip,
        pol,
        lm_pos: [r, q, nose],
    })
}

/// Identification/verification figures of one score matrix.
#[derive(Debug, Clone, serde::Serialize)]
struct Metrics {
    descriptor: String,
    landmarks: String,
    rank1: f64,
    eer: f64,
    genuine_mean: f64,
    impostor_mean: f64,
    failures: usize,
    #[serde(skip)]
    roc: Vec<(f64, f64)>,
}

/// (rank-1 rate, EER, ROC points, mean genuine score, mean impostor score, failed pairs).
type Figures = (f64, f64, Vec<(f64, f64)>, f64, f64, usize);

/// Rank-1 rate, EER and ROC from a probes x gallery score matrix (NaN = failure = worst).
fn metrics(scores: &[Vec<f64>], probe_id: &[usize], gallery_id: &[usize]) -> Figures {
    let mut correct = 0usize;
    let mut gen = Vec::new();
    let mut imp = Vec::new();
    let mut failures = 0;
    for (p, row) in scores.iter().enumerate() {
        let clean: Vec<f64> = row
            .iter()
            .map(|v| if v.is_finite() { *v } else { f64::INFINITY })
            .collect();
        failures += row.iter().filter(|v| !v.is_finite()).count();
        let best = (0..clean.len()).min_by(|&a, &b| clean[a].total_cmp(&clean[b]).then(a.cmp(&b)));
        if best.is_some_and(|b| gallery_id[b] == probe_id[p] && clean[b].is_finite()) {
            correct += 1;
        }
        for (g, v) in clean.iter().enumerate() {
            if gallery_id[g] == probe_id[p] {
                gen.push(*v);
            } else {
                imp.push(*v);
            }
        }
    }
    let rank1 = correct as f64 / scores.len().max(1) as f64;
    let (eer, roc) = eer_roc(&gen, &imp);
    let fmean = |v: &[f64]| {
        let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        f.iter().sum::<f64>() / f.len().max(1) as f64
    };
    (rank1, eer, roc, fmean(&gen), fmean(&imp), failures)
}

/// Equal error rate and ROC points (false accept rate, true accept rate) for distance scores:
/// a pair is accepted when its score is <= the threshold.
fn eer_roc(gen: &[f64], imp: &[f64]) -> (f64, Vec<(f64, f64)>) {
    let mut thr: Vec<f64> = gen
        .iter()
        .chain(imp)
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    thr.sort_by(f64::total_cmp);
    thr.dedup();
    let mut g = gen.to_vec();
    let mut i = imp.to_vec();
    g.sort_by(f64::total_cmp);
    i.sort_by(f64::total_cmp);
    let frac_le = |v: &[f64], t: f64| v.partition_point(|x| *x <= t) as f64 / v.len().max(1) as f64;
    let mut roc = vec![(0.0, 0.0)];
    let mut eer = 1.0;
    let mut best_gap = f64::INFINITY;
    for &t in &thr {
        let far = frac_le(&i, t);
        let tar = frac_le(&g, t);
        roc.push((far, tar));
        let frr = 1.0 - tar;
        let gap = (far - frr).abs();
        if gap < best_gap {
            best_gap = gap;
            eer = 0.5 * (far + frr);
        }
    }
    roc.push((1.0, 1.0));
    (eer, roc)
}

/// The recognition ICP: point-to-point with translation onto the closest surface points,
/// the worst 10 % of pairs trimmed (kept count rounded down), at most 6 iterations, stop
/// after a step when the trimmed RMS changed by at most `1e-6` relative.
fn icp_options() -> IcpLoopOptions {
    IcpLoopOptions {
        variant: IcpVariant::PointToPoint,
        max_iterations: 6,
        translation: true,
        trim: 0.1,
        trim_rounding: TrimRounding::Down,
        convergence: Convergence::RelativeRmseAfterStep { tolerance: 1e-6 },
        evaluate_final: false,
        ..IcpLoopOptions::default()
    }
}

/// ICP of the probe points onto the gallery surface ([`shapedist::icp_to_target`] on the
/// [`FaceLocator`], options [`icp_options`]), started from the landmark alignment; returns
/// the RMS closest-point distance of all probe points at the final pose (cm), NaN when a
/// step fails.
fn icp_score(
    probe: &[DVec3],
    probe_lm: &[DVec3; 3],
    gallery: &FaceLocator<'_>,
    gallery_lm: &[DVec3; 3],
) -> f64 {
    let Some(init) = fit_rigid(probe_lm, gallery_lm, None) else {
        return f64::NAN;
    };
    let Ok(res) = icp_to_target(gallery, probe, None, init, &icp_options()) else {
        return f64::NAN;
    };
    let ss: f64 = probe
        .iter()
        .map(|p| {
            gallery
                .nearest(res.motion.transform_point3(*p))
                .map_or(f64::NAN, |(_, d)| d * d)
        })
        .sum();
    (ss / probe.len().max(1) as f64).sqrt()
}

/// About `n` vertices of a probe for ICP, evenly strided.
fn icp_points(mesh: &TriMesh, n: usize) -> Vec<DVec3> {
    let stride = (mesh.n_vertices() / n.max(3)).max(1);
    mesh.positions().iter().step_by(stride).copied().collect()
}

/// Scores of one probe (its description and ICP points) against every gallery face:
/// bipolar, single pole and ICP; NaN where either side has no description or the score fails.
fn score_row(
    probe: Option<&Described>,
    pts: &[DVec3],
    gallery: &[Option<(&Described, &FaceLocator<'_>)>],
) -> [Vec<f64>; 3] {
    let mut out = [Vec::new(), Vec::new(), Vec::new()];
    for g in gallery {
        let [b, s, c] = match (probe, g) {
            (Some(x), Some((y, loc))) => [
                dist(&x.bip, &y.bip).unwrap_or(f64::NAN),
                dist(&x.pol, &y.pol).unwrap_or(f64::NAN),
                icp_score(pts, &x.lm_pos, loc, &y.lm_pos),
            ],
            _ => [f64::NAN; 3],
        };
        out[0].push(b);
        out[1].push(s);
        out[2].push(c);
    }
    out
}

/// Names of the three scores of [`score_row`].
const SCORES: [&str; 3] = ["bipolar", "single_pole", "icp_raw_mesh"];

/// The figures of the three score matrices of one landmark set (rows from [`score_row`]).
fn summarize(
    rows: &[[Vec<f64>; 3]],
    probe_id: &[usize],
    gallery_id: &[usize],
    landmarks: &str,
) -> Vec<Metrics> {
    SCORES
        .iter()
        .enumerate()
        .map(|(j, dname)| {
            let m: Vec<Vec<f64>> = rows.iter().map(|r| r[j].clone()).collect();
            let (rank1, eer, roc, gm, im, failures) = metrics(&m, probe_id, gallery_id);
            Metrics {
                descriptor: dname.to_string(),
                landmarks: landmarks.to_string(),
                rank1,
                eer,
                genuine_mean: gm,
                impostor_mean: im,
                failures,
                roc,
            }
        })
        .collect()
}

/// Appends the table of `all` (rank-1, EER, mean scores, failed pairs) to the report and
/// writes it as the CSV file `csv`.
fn results_table(rep: &mut Report, all: &[Metrics], csv: &str) -> Result<()> {
    let rows: Vec<Vec<String>> = all
        .iter()
        .map(|m| {
            vec![
                m.descriptor.clone(),
                m.landmarks.clone(),
                format!("{:.3}", m.rank1),
                format!("{:.3}", m.eer),
                f4(m.genuine_mean),
                f4(m.impostor_mean),
                m.failures.to_string(),
            ]
        })
        .collect();
    let hdr = [
        "descriptor",
        "landmarks",
        "rank-1",
        "EER",
        "mean genuine score",
        "mean impostor score",
        "failed pairs",
    ];
    rep.table(&hdr, &rows);
    rep.csv(csv, &hdr, &rows)
}

/// Draws the ROC curves of `all` into `file` and appends the figure to the report.
fn roc_figure(rep: &mut Report, all: &[Metrics], file: &str, title: &str) -> Result<()> {
    let series: Vec<Series> = all
        .iter()
        .map(|m| Series {
            name: format!("{} ({})", m.descriptor, m.landmarks),
            points: m.roc.clone(),
            dashed: m.landmarks == "detected",
        })
        .collect();
    line_plot(
        &rep.path(file),
        title,
        "false accept rate",
        "true accept rate",
        &series,
    )?;
    rep.figure(file, &format!("{title}; dashed: detected landmarks"));
    Ok(())
}

/// Runs the benchmark; prints the output folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let t0 = Instant::now();
    let model_dir = args.model.clone().unwrap_or_else(default_model_dir);
    let model = FaceModel::load(&model_dir)
        .with_context(|| format!("loading the ICT model from {}", model_dir.display()))?;
    if args.scans {
        return scans::run(&args, &model, t0);
    }
    let identities = args.identities.unwrap_or(50);
    let expressions = args.expressions.unwrap_or(6);
    if identities < 2 || expressions < 2 {
        bail!("need at least 2 identities and 2 expressions (one neutral gallery face + probes)");
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir("recognition"));
    let gt = Lm {
        r: model.landmark_id("right_eye_outer")?,
        q: model.landmark_id("left_eye_outer")?,
        nose: model.landmark_id("nose_tip")?,
    };
    // Sampling (sequential: deterministic).
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut samples = Vec::new();
    for id in 0..identities {
        let w = model.random_identity(&mut rng);
        for e in 0..expressions {
            let ew = if e == 0 {
                vec![0.0; model.n_expressions()]
            } else {
                model.random_expression(&mut rng)
            };
            let mesh = model.sample(&w, &ew)?;
            let motion = random_rigid_motion(&mut rng, 5.0);
            let (pos, tri) = mesh.into_parts();
            let pos = pos
                .into_iter()
                .map(|p| motion.transform_point3(p))
                .collect();
            samples.push(Sample {
                identity: id,
                index: e,
                mesh: TriMesh::new(pos, tri)?,
            });
        }
    }
    let methods = resolve_methods(&args.method, &samples[0].mesh)?;
    let method = methods[0].used;
    let method_note = methods[0].note.clone();
    eprintln!(
        "{} faces sampled ({} identities x {}); geodesics: {}",
        samples.len(),
        identities,
        expressions,
        method.name()
    );
    let desc_opts = DescribeOptions {
        levels: args.levels,
        sectors: args.sectors,
    };
    // Landmark detection.
    let generic = landmarks::GenericModel::default_model()
        .map_err(|e| anyhow::anyhow!("landmark model: {e}"))?;
    let pb = bar(samples.len(), "detecting landmarks");
    let detected: Vec<Option<Lm>> = samples
        .par_iter()
        .map(|s| {
            let r = landmarks::detect(&s.mesh, &generic).ok().map(|l| Lm {
                r: l.outer_eye_right.vertex,
                q: l.outer_eye_left.vertex,
                nose: l.nose_tip.vertex,
            });
            pb.inc(1);
            r
        })
        .collect();
    pb.finish();
    let det_err: Vec<[f64; 3]> = samples
        .iter()
        .zip(&detected)
        .filter_map(|(s, d)| {
            d.map(|d| {
                [(gt.r, d.r), (gt.q, d.q), (gt.nose, d.nose)]
                    .map(|(a, b)| (s.mesh.position(a) - s.mesh.position(b)).length())
            })
        })
        .collect();
    // Descriptors for both landmark sets.
    let pb = bar(samples.len(), &format!("descriptors ({})", method.name()));
    let described: Vec<[Option<Described>; 2]> = samples
        .par_iter()
        .zip(&detected)
        .map(|(s, det)| -> Result<_> {
            let solver = geodesic::new_solver(&s.mesh, method)?;
            let walker = Walker::new(&s.mesh);
            let out = [Some(gt), *det].map(|lm| {
                lm.and_then(|lm| {
                    describe_face(&s.mesh, solver.as_ref(), &walker, lm, &desc_opts).ok()
                })
            });
            pb.inc(1);
            Ok(out)
        })
        .collect::<Result<_>>()?;
    pb.finish();
    let gallery: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].index == 0)
        .collect();
    let probes: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].index != 0)
        .collect();
    let gid: Vec<usize> = gallery.iter().map(|&g| samples[g].identity).collect();
    let pid: Vec<usize> = probes.iter().map(|&p| samples[p].identity).collect();
    let locators: Vec<FaceLocator<'_>> = gallery
        .iter()
        .map(|&g| FaceLocator::new(&samples[g].mesh))
        .collect();
    let mut all = Vec::new();
    let pb = bar(2 * probes.len(), "scoring (ICP dominates)");
    for (k, lname) in ["ground_truth", "detected"].iter().enumerate() {
        let gal: Vec<Option<(&Described, &FaceLocator<'_>)>> = gallery
            .iter()
            .zip(&locators)
            .map(|(&g, l)| described[g][k].as_ref().map(|d| (d, l)))
            .collect();
        let rows: Vec<[Vec<f64>; 3]> = probes
            .par_iter()
            .map(|&p| {
                let pts = icp_points(&samples[p].mesh, args.icp_points);
                let r = score_row(described[p][k].as_ref(), &pts, &gal);
                pb.inc(1);
                r
            })
            .collect();
        all.extend(summarize(&rows, &pid, &gid, lname));
    }
    pb.finish();

    // Output.
    let mut rep = Report::new(&out, "Recognition benchmark on sampled ICT faces")?;
    rep.para(&format!(
        "{} identities x {} faces (seed {}): {} gallery faces (neutral), {} probes (random expressions: with probability 1/2 a recipe at strength 0.3-1, plus random blendshapes), every face under a random rigid motion. Geodesics: {}{}. Bipolar descriptor: static area, N = {} levels between the outer eye corners (grid reading, keyed distance); single pole: {} sectors x {} radius levels around the nose tip; ICP: {} probe vertices onto the gallery surface, started from the 3-landmark alignment, 10 % trimmed, score = RMS closest-point distance (cm).",
        identities, expressions, args.seed, gallery.len(), probes.len(), method.name(),
        method_note.as_ref().map(|n| format!(" (exact requested: {n})")).unwrap_or_default(),
        args.levels, args.sectors, args.levels, icp_points(&samples[0].mesh, args.icp_points).len()
    ));
    let n_det = detected.iter().filter(|d| d.is_some()).count();
    let mean_err =
        |k: usize| det_err.iter().map(|e| e[k]).sum::<f64>() / det_err.len().max(1) as f64;
    rep.para(&format!("Landmark detection: {n_det} of {} faces detected; mean error right corner {:.3} cm, left corner {:.3} cm, nose tip {:.3} cm.", samples.len(), mean_err(0), mean_err(1), mean_err(2)));
    results_table(&mut rep, &all, "results.csv")?;
    roc_figure(&mut rep, &all, "roc.svg", "ROC (verification)")?;
    rep.png_twins()?;
    let secs = t0.elapsed().as_secs_f64();
    rep.para(&format!("Run time: {secs:.1} s."));
    rep.finish()?;
    let summary = serde_json::json!({
        "identities": identities,
        "faces_per_identity": expressions,
        "seed": args.seed,
        "gallery": gallery.len(),
        "probes": probes.len(),
        "geodesic_method": method.name(),
        "geodesic_note": method_note,
        "levels": args.levels,
        "sectors": args.sectors,
        "landmark_detection": { "detected": n_det, "faces": samples.len(), "mean_error_cm": { "right_eye_outer": mean_err(0), "left_eye_outer": mean_err(1), "nose_tip": mean_err(2) } },
        "results": all,
        "roc_plot": "roc.svg",
        "seconds": secs,
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    println!("{}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eer_and_rank1_on_known_scores() {
        // 2 gallery ids, 2 probes each; probe 3 is misidentified.
        let gid = vec![0, 1];
        let pid = vec![0, 0, 1, 1];
        let s = vec![
            vec![0.1, 0.5],
            vec![0.2, 0.6],
            vec![0.7, 0.3],
            vec![0.4, 0.45],
        ];
        let (rank1, eer, roc, gm, im, f) = metrics(&s, &pid, &gid);
        assert!((rank1 - 0.75).abs() < 1e-12);
        assert!((gm - (0.1 + 0.2 + 0.3 + 0.45) / 4.0).abs() < 1e-12);
        assert!((im - (0.5 + 0.6 + 0.7 + 0.4) / 4.0).abs() < 1e-12);
        assert_eq!(f, 0);
        // Threshold 0.4: FAR 1/4, FRR 1/4 -> EER 0.25.
        assert!((eer - 0.25).abs() < 1e-12, "{eer}");
        assert_eq!(roc.first(), Some(&(0.0, 0.0)));
        assert_eq!(roc.last(), Some(&(1.0, 1.0)));
        // Perfect separation gives EER 0; NaN counts as a failure.
        let (r, e, ..) = metrics(&[vec![0.1, f64::NAN], vec![0.9, 0.2]], &[0, 1], &gid);
        assert_eq!((r, e), (1.0, 0.0));
    }

    #[test]
    fn icp_recovers_a_rigid_copy() {
        let m = meshcore::shapes::icosphere(2);
        let rot = meshcore::DMat3::from_quat(meshcore::DQuat::from_axis_angle(
            DVec3::new(1.0, 0.3, 0.2).normalize(),
            1.1,
        ));
        let t = DVec3::new(3.0, -2.0, 1.0);
        let probe: Vec<DVec3> = m.positions().iter().map(|p| rot * *p + t).collect();
        let lm_g = [m.position(0), m.position(5), m.position(9)];
        let lm_p = lm_g.map(|p| rot * p + t);
        let loc = FaceLocator::new(&m);
        assert!(icp_score(&probe, &lm_p, &loc, &lm_g) < 1e-9);
        // A scaled copy is not at distance 0.
        let big: Vec<DVec3> = probe.iter().map(|p| (*p - t) * 1.1 + t).collect();
        assert!(icp_score(&big, &lm_p, &loc, &lm_g) > 0.01);
    }
}
