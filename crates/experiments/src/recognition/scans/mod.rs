//! `cargo xtask recognition --scans`: the benchmark on range scans. Faces sampled from the ICT
//! model are scanned by `rangescan` and described twice: with the ground-truth landmarks the
//! scanner projected, on the scan cleaned by `scanprep` with a crop around the true nose tip,
//! and as a user's scan is, on the scan `facematch::prepare` makes (cleaned, cropped around the
//! *detected* nose tip) with the landmarks it detects (seen from the scanner). Gallery: neutral
//! frontal scans at the `--scan-*` settings; probes: the other expressions, each under a random
//! yaw of 0-45 degrees (either side) and a random noise level. Every face is described by three
//! pole pairs (the outer eye corners; each outer corner with the nose tip); a probe turned past
//! `--side-pair`, or with an outer eye corner off the scan or unseen, takes a side pair as its
//! own (the pair its reference-point search moves), and its bipolar score is the least distance
//! over the three pairs (`--own-pair-only`: its own pair's). Sweeps rescan one probe expression of the first
//! `--sweep-identities` identities at several noise levels, pitches and yaws (the other settings
//! those of the gallery) against the same gallery. Every failure (a landmark not found or not on
//! the scan, a descriptor error) is listed with the face's name and counted, never replaced.

mod detect_only;
mod face;
mod report;
mod score;
mod specs;

use super::compare::{time_descriptions, TIMED_FACES};
use super::describe::{elastic_options, iso_levels_of, DescribeOptions};
use super::metrics::{finite_quantile, Metrics};
use super::{Args, Lm};
use crate::scans::{scan_face, FaceSpec, ScanSetOptions, ScanSettings};
use anyhow::{bail, Context, Result};
use detect_only::detect_only;
pub(super) use face::Face;
use face::Pipeline;
use facecurves::{ElasticOptions, IsoLevels};
use facemodel::FaceModel;
use geodesic::Method;
use landmarks::GenericModel;
use meshcore::{DVec3, FaceLocator, TriMesh};
use scanprep::{CleanOptions, Crop};
use score::failures;
pub(super) use score::{score_group, Scored};
use specs::{sweeps, Specs, Sweep};
use std::time::Instant;

/// The two landmark sets.
const SETS: [&str; 2] = ["ground_truth", "detected"];

/// The run's settings, as the report states them.
#[derive(Clone, Copy)]
struct Setup<'a> {
    args: &'a Args,
    identities: usize,
    expressions: usize,
    /// The gallery's scanner settings (the sweeps' reference).
    base: ScanSettings,
    scan_opts: &'a ScanSetOptions,
    dopt: &'a DescribeOptions,
    method: Method,
    sweep_defs: &'a [Sweep],
    sweep_ids: usize,
    out: &'a std::path::Path,
}

/// The described faces of a run and their figures: the main run's, per sweep and value the
/// sweep's, and every failure (group, face, landmark set, what failed).
struct Results {
    gallery: Vec<Face>,
    probes: Vec<Face>,
    sweep_faces: Vec<Face>,
    scored: Scored,
    sweep_results: Vec<Vec<Vec<Metrics>>>,
    fails: Vec<[String; 4]>,
}

/// 95th percentile (nearest rank) of the finite values.
fn p95(v: Vec<f64>) -> f64 {
    finite_quantile(v, 0.95)
}

/// Runs the scan benchmark; prints the output folder on the last line.
pub(super) fn run(args: &Args, model: &FaceModel, t0: Instant) -> Result<()> {
    let (identities, expressions) = args.sizes((16, 3))?;
    let out = args.io.out.out_dir("recognition-scans");
    let base = args.scan.settings();
    let generic =
        GenericModel::default_model().map_err(|e| anyhow::anyhow!("landmark model: {e}"))?;
    let (scan_opts, mut dopt, prep) = settings(args)?;
    let elastic = elastic_options(args.curve_samples);
    // Specs: gallery, main probes, sweeps (each face its own scan seed).
    let sweep_defs = if args.no_sweeps { Vec::new() } else { sweeps() };
    let sweep_ids = args.sweep_identities.min(identities);
    let specs = Specs::new(
        args,
        model,
        identities,
        expressions,
        base,
        &sweep_defs,
        sweep_ids,
    )?;
    if args.detect_only {
        return detect_only(model, &generic, &specs.all(), &prep, &out);
    }
    if let Some(dir) = &args.save_scans {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating --save-scans {}", dir.display()))?;
    }
    // The method as asked: on scans nothing substitutes another (a scan its solver cannot be
    // prepared on fails, and the failure is counted with the others).
    let method: geodesic::Method = args
        .method
        .trim()
        .parse()
        .with_context(|| format!("--method {}", args.method))?;
    dopt.iso_levels = Some(first_iso_levels(
        model,
        &generic,
        &specs.first_gallery,
        &scan_opts,
        method,
        args.iso_levels,
    )?);
    let n_faces = specs.gallery.len()
        + specs.probes.len()
        + specs.sweeps.iter().flatten().map(Vec::len).sum::<usize>();
    eprintln!(
        "{n_faces} scans ({} gallery, {} probes, {} sweep scans); geodesics: {}",
        specs.gallery.len(),
        specs.probes.len(),
        n_faces - specs.gallery.len() - specs.probes.len(),
        method.name()
    );
    let pipeline = Pipeline {
        model,
        generic: &generic,
        method,
        dopt: &dopt,
        scan_opts: &scan_opts,
        prep: &prep,
        icp_n: args.icp_points,
        save: args.save_scans.as_deref(),
    };
    let results = describe_and_score(&pipeline, &specs, &sweep_defs, &elastic)?;
    let secs = t0.elapsed().as_secs_f64();
    let setup = Setup {
        args,
        identities,
        expressions,
        base,
        scan_opts: &scan_opts,
        dopt: &dopt,
        method,
        sweep_defs: &sweep_defs,
        sweep_ids,
        out: &out,
    };
    report::write(&setup, &results, secs)
}

/// The scans' cleaning, the descriptions' settings (iso-curvature levels not yet set) and the
/// detected landmarks' preparation, from the arguments.
fn settings(args: &Args) -> Result<(ScanSetOptions, DescribeOptions, facematch::MatchOptions)> {
    if !(0.0..=1.0).contains(&args.pair_second) {
        bail!(
            "--pair-second {} (the weight of the second least pair distance must be in [0, 1])",
            args.pair_second
        );
    }
    if !(args.scan_edge.is_finite() && args.scan_edge >= 0.0) {
        bail!(
            "--scan-edge {} mm (must be 0, for no decimation, or positive)",
            args.scan_edge
        );
    }
    let scan_opts = ScanSetOptions {
        clean: CleanOptions {
            crop: Some(Crop {
                centre: DVec3::ZERO,
                radius_mm: args.scan.crop_radius,
            }),
            target_edge_mm: (args.scan_edge > 0.0).then_some(args.scan_edge),
            smoothing_iterations: args.scan_smooth,
            ..CleanOptions::default()
        },
        detect_smoothing: args.detect_smooth,
        ..ScanSetOptions::default()
    };
    let dopt = DescribeOptions::of_args(args, true);
    // The detected landmarks' path is a user's: `facematch::prepare` with the same cleaning,
    // its crop around the detected nose tip.
    let prep = facematch::MatchOptions {
        prepare: facematch::PrepareOptions {
            clean: CleanOptions {
                crop: None,
                ..scan_opts.clean.clone()
            },
            crop_radius_mm: Some(args.scan.crop_radius),
            detect_smoothing: args.detect_smooth,
            detect: scan_opts.detect.unwrap_or_default(),
            ..dopt.matching.prepare.clone()
        },
        ..dopt.matching.clone()
    };
    Ok((scan_opts, dopt, prep))
}

/// Iso-curvature levels: from the first gallery scan (ground-truth landmarks), scanned once
/// more here (without detection) before the runs.
fn first_iso_levels(
    model: &FaceModel,
    generic: &GenericModel,
    first_gallery: &FaceSpec,
    scan_opts: &ScanSetOptions,
    method: Method,
    count: usize,
) -> Result<IsoLevels> {
    let first = scan_face(
        model,
        generic,
        first_gallery,
        &ScanSetOptions {
            detect: None,
            ..scan_opts.clone()
        },
    )
    .with_context(|| {
        format!(
            "scanning {} for the iso-curvature levels",
            first_gallery.name
        )
    })?;
    let [r, q, nose] = first
        .truth_vertices()
        .map_err(|e| anyhow::anyhow!("{}: {e}", first_gallery.name))?;
    let solver = geodesic::new_solver(&first.mesh, method)?;
    iso_levels_of(&first.mesh, solver.as_ref(), Lm::new(r, q, nose), count)
}

/// Describes the gallery, the probes and the sweeps' scans and scores each probe group
/// against the gallery.
fn describe_and_score(
    pipeline: &Pipeline<'_>,
    specs: &Specs,
    sweep_defs: &[Sweep],
    elastic: &ElasticOptions,
) -> Result<Results> {
    let gallery = pipeline.process(&specs.gallery, true, "gallery scans");
    let locators: Vec<[Option<FaceLocator<'_>>; 2]> = gallery
        .iter()
        .map(|g| [0, 1].map(|k| g.mesh[k].as_ref().map(FaceLocator::new)))
        .collect();
    let probes = pipeline.process(&specs.probes, false, "probe scans");
    // Description times: the first gallery scans again, one at a time on one thread.
    let first: Vec<(&TriMesh, Lm)> = gallery
        .iter()
        .filter_map(|g| {
            let m = g.mesh[0].as_ref()?;
            g.gt_lm.map(|lm| (m, lm))
        })
        .take(TIMED_FACES)
        .collect();
    let ms_desc = time_descriptions(&first, pipeline.method, pipeline.dopt)?;
    let scored = score_group(&gallery, &locators, &probes, elastic, &ms_desc)?;
    let mut fails = failures(&gallery, "gallery");
    fails.extend(failures(&probes, "probes"));
    // Sweeps.
    let mut sweep_results: Vec<Vec<Vec<Metrics>>> = Vec::new();
    let mut sweep_faces: Vec<Face> = Vec::new();
    for (sw, groups) in sweep_defs.iter().zip(&specs.sweeps) {
        let mut per_value = Vec::new();
        for (v, specs) in sw.values.iter().zip(groups) {
            let faces = pipeline.process(specs, false, &format!("sweep {} {v}", sw.name));
            per_value.push(score_group(&gallery, &locators, &faces, elastic, &ms_desc)?.metrics);
            fails.extend(failures(&faces, &format!("sweep {} {v}", sw.name)));
            sweep_faces.extend(faces);
        }
        sweep_results.push(per_value);
    }
    Ok(Results {
        gallery,
        probes,
        sweep_faces,
        scored,
        sweep_results,
        fails,
    })
}
