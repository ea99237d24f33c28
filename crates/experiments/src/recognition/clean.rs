//! The benchmark on clean meshes: faces sampled from the ICT model under random rigid motions,
//! described with the model's landmarks and with detected ones.

use super::compare::{icp_points, time_descriptions, TIMED_FACES, TIMED_PAIRS};
use super::describe::{describe_face, elastic_options, iso_levels_of, DescribeOptions, ISO_POINTS};
use super::metrics::{paired_table, results_table, roc_figure, write_summary};
use super::scans::{score_group, Face, Scored};
use super::{Args, Lm};
use crate::pipeline::resolve_methods;
use crate::report::{par_map, Report};
use crate::walk::Walker;
use anyhow::Result;
use facemodel::{random_rigid_motion, FaceModel};
use meshcore::{FaceLocator, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// One sampled face.
#[derive(Debug)]
struct Sample {
    identity: usize,
    index: usize,
    mesh: TriMesh,
}

/// The run's samples and settings, as the report states them.
struct Setup<'a> {
    identities: usize,
    expressions: usize,
    samples: &'a [Sample],
    /// Indices of the gallery faces (expression 0) and of the probes in `samples`.
    gallery: Vec<usize>,
    probes: Vec<usize>,
    method: geodesic::Method,
    method_note: Option<String>,
    probe_opts: &'a DescribeOptions,
    detected: &'a [Option<Lm>],
}

/// Runs the benchmark on clean meshes; prints the output folder on the last line.
pub(super) fn run(args: &Args, model: &FaceModel, t0: Instant) -> Result<()> {
    let (identities, expressions) = args.sizes((50, 6))?;
    let out = args.io.out.out_dir("recognition");
    let gt = Lm {
        lost: None,
        r: model.landmark_id("right_eye_outer")?,
        q: model.landmark_id("left_eye_outer")?,
        nose: model.landmark_id("nose_tip")?,
    };
    let samples = sample_faces(model, identities, expressions, args.seed)?;
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
    // Iso-curvature levels: from the first gallery face (ground-truth landmarks).
    let iso_levels = {
        let s = &samples[0];
        let solver = geodesic::new_solver(&s.mesh, method)?;
        iso_levels_of(&s.mesh, solver.as_ref(), gt, args.iso_levels)?
    };
    // The reference-point search is the probes' (the gallery keeps its one description).
    let probe_opts = DescribeOptions {
        iso_levels: Some(iso_levels),
        ..DescribeOptions::of_args(args, false)
    };
    let desc_opts = probe_opts.without_search();
    // Landmark detection.
    let generic = landmarks::GenericModel::default_model()
        .map_err(|e| anyhow::anyhow!("landmark model: {e}"))?;
    let detected = detect_all(&samples, &generic);
    // Descriptors for both landmark sets.
    let faces = describe_all(
        args,
        &samples,
        &detected,
        gt,
        method,
        &desc_opts,
        &probe_opts,
    )?;
    let setup = Setup {
        identities,
        expressions,
        samples: &samples,
        gallery: (0..samples.len())
            .filter(|&i| samples[i].index == 0)
            .collect(),
        probes: (0..samples.len())
            .filter(|&i| samples[i].index != 0)
            .collect(),
        method,
        method_note,
        probe_opts: &probe_opts,
        detected: &detected,
    };
    let scored = score_all(args, &setup, faces, gt)?;
    write_report(args, &setup, gt, &scored, &out, t0)
}

/// Samples `identities` x `expressions` faces (expression 0 neutral), each under a random rigid
/// motion (sequential: deterministic).
fn sample_faces(
    model: &FaceModel,
    identities: usize,
    expressions: usize,
    seed: u64,
) -> Result<Vec<Sample>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
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
    Ok(samples)
}

/// The detected landmarks of every face (`None` where detection failed).
fn detect_all(samples: &[Sample], generic: &landmarks::GenericModel) -> Vec<Option<Lm>> {
    par_map(samples, "detecting landmarks", |s| {
        let l = landmarks::detect(&s.mesh, generic).ok()?;
        let v = |p: landmarks::Landmark| p.vertex;
        Some(Lm::new(
            v(l.outer_eye_right),
            v(l.outer_eye_left),
            v(l.nose_tip),
        ))
    })
}

/// Every face described with the ground-truth landmarks `gt` and with its detected ones (the
/// gallery faces with `desc_opts`, the probes with `probe_opts`), with its ICP points.
fn describe_all(
    args: &Args,
    samples: &[Sample],
    detected: &[Option<Lm>],
    gt: Lm,
    method: geodesic::Method,
    desc_opts: &DescribeOptions,
    probe_opts: &DescribeOptions,
) -> Result<Vec<Face>> {
    let faces: Vec<(&Sample, &Option<Lm>)> = samples.iter().zip(detected).collect();
    let msg = format!("descriptors ({})", method.name());
    par_map(&faces, &msg, |&(s, det)| -> Result<_> {
        let solver = geodesic::new_solver(&s.mesh, method)?;
        let walker = Walker::new(&s.mesh);
        let o = if s.index == 0 { desc_opts } else { probe_opts };
        let mut face = Face::new(&format!("id{:02}-e{}", s.identity, s.index), s.identity);
        face.desc = [Some(gt), *det].map(|lm| {
            let lm = lm.ok_or("no landmarks")?;
            describe_face(&s.mesh, solver.as_ref(), &walker, lm, o)
        });
        if s.index != 0 {
            let pts = icp_points(&s.mesh, args.icp_points);
            face.pts = [pts.clone(), pts];
        }
        Ok(face)
    })
    .into_iter()
    .collect()
}

/// The figures of every score with both landmark sets and the bipolar comparisons' fallbacks
/// ([`score_group`]: the probes scored against the gallery in parallel, the comparisons timed
/// on one thread), with the descriptions timed on one thread.
fn score_all(args: &Args, s: &Setup<'_>, faces: Vec<Face>, gt: Lm) -> Result<Scored> {
    let samples = s.samples;
    // Description times: the first gallery faces again, one at a time on one thread.
    let first: Vec<(&TriMesh, Lm)> = s
        .gallery
        .iter()
        .take(TIMED_FACES)
        .map(|&g| (&samples[g].mesh, gt))
        .collect();
    let ms_desc = time_descriptions(&first, s.method, s.probe_opts)?;
    let (mut gallery, mut probes) = (Vec::new(), Vec::new());
    for (f, x) in faces.into_iter().zip(samples) {
        if x.index == 0 {
            gallery.push(f)
        } else {
            probes.push(f)
        }
    }
    let locators: Vec<[Option<FaceLocator<'_>>; 2]> = s
        .gallery
        .iter()
        .map(|&g| [0, 1].map(|_| Some(FaceLocator::new(&samples[g].mesh))))
        .collect();
    let elastic = elastic_options(args.curve_samples);
    score_group(&gallery, &locators, &probes, &elastic, &ms_desc)
}

/// Writes `report.md` (settings, landmark detection, results, the paired comparison, the bipolar
/// fallbacks, ROC) and `summary.json`; prints the fallbacks' counts and the output folder.
fn write_report(
    args: &Args,
    s: &Setup<'_>,
    gt: Lm,
    scored: &Scored,
    out: &std::path::Path,
    t0: Instant,
) -> Result<()> {
    let (samples, detected) = (s.samples, s.detected);
    let det_err: Vec<[f64; 3]> = samples
        .iter()
        .zip(detected)
        .filter_map(|(s, d)| {
            d.map(|d| {
                [(gt.r, d.r), (gt.q, d.q), (gt.nose, d.nose)]
                    .map(|(a, b)| (s.mesh.position(a) - s.mesh.position(b)).length())
            })
        })
        .collect();
    let mut rep = Report::new(out, "Recognition benchmark on sampled ICT faces")?;
    rep.para(&format!(
        "{} identities x {} faces (seed {}): {} gallery faces (neutral), {} probes (random expressions: with probability 1/2 a recipe at strength 0.3-1, plus random blendshapes), every face under a random rigid motion. Geodesics: {}{}. Bipolar descriptor: static area, N = {} levels between the outer eye corners (grid reading, keyed distance){}; single pole: {} sectors x {} radius levels around the nose tip; ICP: {} probe vertices onto the gallery surface, started from the 3-landmark alignment, 10 % trimmed, score = RMS closest-point distance (cm); facial curves: N = {} level curves of the nose-tip field up to D, elastic distance ({} segments per curve, one start-point candidate, one rotation / reparametrisation alternation), root sum of squares; iso-curvature: {} levels per principal field (quantiles of the first gallery face) in the geodesic disc of radius D around the nose tip, ICP of the networks' points (thinned to at most {ISO_POINTS}, every k-th point) started from the 3-landmark alignment (10 iterations on a 500-point subsample, at most 10 on all points), score = normalised RMS closest-point distance. Times, single thread (a one-thread pool, after the parallel scoring; the machine is shared, so compare them as ratios): ms per comparison is the mean over {TIMED_PAIRS} probe x gallery pairs per landmark set; ms per description the median over the first {TIMED_FACES} gallery faces (ground-truth landmarks), described as probes, of the fields a representation needs (both corners; the nose tip; the search's moved corners) plus its build.",
        s.identities, s.expressions, args.seed, s.gallery.len(), s.probes.len(), s.method.name(),
        s.method_note.as_ref().map(|n| format!(" (exact requested: {n})")).unwrap_or_default(),
        args.res.levels,
        s.probe_opts.matching.search.map(|r| format!(", each probe also described from its outer eye corners moved by {} cm in {} directions of their tangent planes (`bipolar::SearchedPole`), its score the least distance over these 49 descriptors", r.radius_mm, r.directions)).unwrap_or_default(),
        args.res.sectors, args.res.levels, icp_points(&s.samples[0].mesh, args.icp_points).len(),
        args.res.levels, args.curve_samples, args.iso_levels
    ));
    let n_det = detected.iter().filter(|d| d.is_some()).count();
    let mean_err =
        |k: usize| det_err.iter().map(|e| e[k]).sum::<f64>() / det_err.len().max(1) as f64;
    rep.para(&format!("Landmark detection: {n_det} of {} faces detected; mean error right corner {:.3} cm, left corner {:.3} cm, nose tip {:.3} cm.", samples.len(), mean_err(0), mean_err(1), mean_err(2)));
    let all = &scored.metrics;
    results_table(&mut rep, all, "results.csv")?;
    paired_table(&mut rep, all);
    rep.para("The bipolar comparisons' fallbacks (a probe's own descriptor that failed replaced by the least of its moved ones, moved descriptors that failed left out), counted per landmark set:");
    rep.list(&scored.fallbacks);
    for f in &scored.fallbacks {
        println!("{f}");
    }
    roc_figure(&mut rep, all, "roc.svg", "ROC (verification)")?;
    rep.png_twins()?;
    let secs = t0.elapsed().as_secs_f64();
    rep.para(&format!("Run time: {secs:.1} s."));
    rep.finish()?;
    let fields = serde_json::json!({
        "geodesic_note": s.method_note,
        "landmark_detection": { "detected": n_det, "faces": samples.len(), "mean_error_cm": { "right_eye_outer": mean_err(0), "left_eye_outer": mean_err(1), "nose_tip": mean_err(2) } },
        "roc_plot": "roc.svg",
        "seconds": secs,
    });
    let sampled = [s.identities, s.expressions, s.gallery.len(), s.probes.len()];
    write_summary(out, args, sampled, s.method, fields, all)?;
    eprintln!("{secs:.1} s wall");
    println!("{}", out.display());
    Ok(())
}
