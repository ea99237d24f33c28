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

use super::{
    describe_face, elastic_options, icp_points, iso_levels_of, median, order_stat, paired_table,
    results_table, roc_figure, score_row, summarize, time_comparisons, time_descriptions,
    timed_pairs, write_summary, Args, DescribeOptions, Described, Lm, Metrics, PairDistances, Row,
    SCORES, SEARCH_DIRECTIONS, TIMED_FACES,
};
use crate::pipeline::{bar, resolve_methods};
use crate::report::{line_plot, Report, Series};
use crate::scans::{
    clean_scan, sample_weights, scan_face, scan_raw, scan_seed, FaceSpec, ScanSetOptions,
    ScanSettings, ScannedFace, MAX_SNAP_MM, REFERENCE_LANDMARKS, SCANNER_SIDE,
};
use crate::walk::Walker;
use anyhow::{bail, Context, Result};
use facecurves::ElasticOptions;
use facemodel::FaceModel;
use geodesic::Method;
use landmarks::GenericModel;
use meshcore::{DVec3, FaceLocator, TriMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scanprep::{CleanOptions, Crop};
use std::time::Instant;

/// The two landmark sets.
const SETS: [&str; 2] = ["ground_truth", "detected"];

/// Noise levels of the probes of the main run, mm.
const PROBE_NOISE: [f64; 3] = [0.1, 0.2, 0.4];

/// A sweep: a name, the values, and how a value changes the gallery's settings.
struct Sweep {
    name: &'static str,
    unit: &'static str,
    values: Vec<f64>,
    apply: fn(ScanSettings, f64) -> ScanSettings,
}

/// The sweeps (each value rescans `--sweep-identities` faces); the gallery's default setting
/// (noise 0.1 mm, pitch 0.5 mm, yaw 0) is among the values.
fn sweeps() -> Vec<Sweep> {
    vec![
        Sweep {
            name: "noise",
            unit: "mm",
            values: vec![0.0, 0.1, 0.3, 1.0],
            apply: |s, v| ScanSettings { noise_mm: v, ..s },
        },
        Sweep {
            name: "pitch",
            unit: "mm",
            values: vec![0.3, 0.5, 1.0],
            apply: |s, v| ScanSettings { pitch_mm: v, ..s },
        },
        Sweep {
            name: "yaw",
            unit: "degrees",
            values: vec![0.0, 20.0, 40.0, 60.0],
            apply: |s, v| ScanSettings { yaw_deg: v, ..s },
        },
    ]
}

/// One scanned and described face.
struct Face {
    name: String,
    identity: usize,
    /// Per landmark set, the cleaned scan, kept for gallery faces (ICP target): for the ground
    /// truth cropped around the true nose tip, for the detected landmarks the scan
    /// `facematch::prepare` made (cropped around the detected nose tip).
    mesh: [Option<TriMesh>; 2],
    /// Its ground-truth landmark vertices, when on the scan.
    gt_lm: Option<Lm>,
    /// Per landmark set, the ICP probe points (of that set's scan).
    pts: [Vec<DVec3>; 2],
    /// Per landmark set: the description or why there is none.
    desc: [Result<Described, String>; 2],
    /// Detected minus true position of the outer eye corners and the nose tip (mm), when
    /// detected and on the scan.
    det_err: Option<[f64; 3]>,
    valid_samples: usize,
    vertices: usize,
    /// Wall seconds: scan, clean (ground truth's), prepare (the detected path's cleanings and
    /// detections), describe.
    secs: [f64; 4],
}

/// The specs `keep` accepts, in order.
fn kept_specs(specs: Vec<FaceSpec>, keep: impl Fn(&FaceSpec) -> bool) -> Vec<FaceSpec> {
    specs.into_iter().filter(|s| keep(s)).collect()
}

/// Scans, cleans, detects and describes every face (in parallel, in order).
#[allow(clippy::too_many_arguments)]
fn process(
    model: &FaceModel,
    generic: &GenericModel,
    specs: &[FaceSpec],
    keep_mesh: bool,
    method: Method,
    dopt: &DescribeOptions,
    scan_opts: &ScanSetOptions,
    prep: &facematch::MatchOptions,
    icp_n: usize,
    save: Option<&std::path::Path>,
    msg: &str,
) -> Vec<Face> {
    let pb = bar(specs.len(), msg);
    let out = specs
        .par_iter()
        .map(|spec| {
            let f = describe_spec(
                model, generic, spec, keep_mesh, method, dopt, scan_opts, prep, icp_n, save,
            );
            pb.inc(1);
            f
        })
        .collect();
    pb.finish();
    out
}

/// The ground-truth landmarks of a scan ([`Lm::from_parts`]; a corner off the cleaned scan,
/// see [`ScannedFace::truth_vertices`], may be lost).
fn truth_lm(s: &ScannedFace, allow_lost: bool) -> Result<Lm, String> {
    use landmarks::LandmarkName as L;
    let v = |n: L| s.truth_vertex(n);
    let at = |n: L| s.truth[n as usize].position;
    Lm::from_parts(
        [v(L::OuterEyeRight), v(L::OuterEyeLeft), v(L::NoseTip)],
        [at(L::OuterEyeRight), at(L::OuterEyeLeft)],
        allow_lost,
    )
}

/// Distances (mm) of the detected outer eye corners and nose tip from their ground truth (an
/// unseen one counts as infinitely far off), when the ground truth is on the scan.
fn detection_errors(s: &ScannedFace, found: &landmarks::VisibleLandmarks) -> Option<[f64; 3]> {
    s.truth_vertices().ok()?;
    Some(REFERENCE_LANDMARKS.map(|n| {
        found.get(n).map_or(f64::INFINITY, |l| {
            (l.position - s.truth[n as usize].position).length()
        })
    }))
}

/// Scans the face of `spec`; cleans it for the ground-truth landmarks (crop around the true nose
/// tip) and prepares it as a user would for the detected ones ([`facematch::prepare_with`]:
/// crop around the detected nose tip, no ground truth); describes both.
#[allow(clippy::too_many_arguments)]
fn describe_spec(
    model: &FaceModel,
    generic: &GenericModel,
    spec: &FaceSpec,
    keep_mesh: bool,
    method: Method,
    dopt: &DescribeOptions,
    scan_opts: &ScanSetOptions,
    prep: &facematch::MatchOptions,
    icp_n: usize,
    save: Option<&std::path::Path>,
) -> Face {
    let mut face = Face {
        name: spec.name.clone(),
        identity: spec.identity,
        mesh: [None, None],
        gt_lm: None,
        pts: [Vec::new(), Vec::new()],
        desc: [Err(String::new()), Err(String::new())],
        det_err: None,
        valid_samples: 0,
        vertices: 0,
        secs: [0.0; 4],
    };
    let gt_opts = ScanSetOptions {
        detect: None,
        ..scan_opts.clone()
    };
    let scanned = scan_raw(model, spec).and_then(|(raw, t_scan)| {
        let s = clean_scan(&raw, t_scan, generic, &gt_opts)?;
        Ok((raw, s))
    });
    let saved = |raw: &rangescan::Scan| match save {
        Some(dir) => mesh_io::write_bnt(dir.join(format!("{}.bnt", spec.name)), &raw.grid)
            .map_err(anyhow::Error::from),
        None => Ok(()),
    };
    let (raw, s) = match scanned.and_then(|(raw, s)| saved(&raw).map(|()| (raw, s))) {
        Ok(x) => x,
        Err(e) => {
            let e = format!("scan, cleaning or saving: {e:#}");
            face.desc = [Err(e.clone()), Err(e)];
            return face;
        }
    };
    let t = Instant::now();
    let prepared = facematch::prepare_with(facematch::ScanInput::Grid(&raw.grid), generic, prep)
        .map_err(|e| format!("prepare: {e}"));
    drop(raw);
    face.secs[2] = t.elapsed().as_secs_f64();
    face.valid_samples = s.valid_samples;
    face.vertices = s.mesh.n_vertices();
    face.secs[0] = s.times.scan.as_secs_f64();
    face.secs[1] = s.times.clean.as_secs_f64();
    if let Ok(p) = &prepared {
        face.det_err = detection_errors(&s, &p.detected);
    }
    // The reference-point search is the probes' (the gallery keeps its one description).
    let gallery_opts;
    let dopt = if keep_mesh {
        gallery_opts = DescribeOptions {
            ref_search: None,
            ..dopt.clone()
        };
        &gallery_opts
    } else {
        dopt
    };
    let allow_lost = dopt.side_pair_deg.is_some();
    let t = Instant::now();
    let meshes: [Result<TriMesh, String>; 2] =
        [Ok(s.mesh.clone()), prepared.clone().map(|p| p.mesh)];
    let lms = [
        truth_lm(&s, allow_lost),
        prepared.as_ref().map_err(Clone::clone).and_then(|p| {
            Lm::from_detected(
                &p.mesh,
                &p.detected,
                allow_lost,
                dopt.predicted_corners,
                MAX_SNAP_MM,
            )
        }),
    ];
    face.gt_lm = lms[0].as_ref().ok().copied();
    for k in 0..2 {
        let (Ok(mesh), Ok(lm)) = (&meshes[k], &lms[k]) else {
            face.desc[k] = Err(lms[k].clone().err().unwrap_or_default());
            continue;
        };
        face.pts[k] = icp_points(mesh, icp_n);
        face.desc[k] = geodesic::new_solver(mesh, method)
            .map_err(|e| format!("geodesic solver: {e}"))
            .and_then(|solver| describe_face(mesh, solver.as_ref(), &Walker::new(mesh), *lm, dopt));
        if let (true, Some(min_angle_deg), Ok(d)) = (keep_mesh, dopt.view_match, &mut face.desc[k])
        {
            // The gallery face's template views (facematch's, computed once).
            let view = facematch::ViewOptions {
                min_angle_deg,
                ..facematch::ViewOptions::default()
            };
            let matching = facematch::MatchOptions {
                method,
                ..dopt.matching()
            };
            let views = facematch::views_of(mesh, *lm, SCANNER_SIDE, &matching, &view);
            d.views = Some((views, view));
        }
    }
    face.secs[3] = t.elapsed().as_secs_f64();
    if keep_mesh {
        face.mesh = meshes.map(Result::ok);
    }
    face
}

/// Figures of a probe group against the gallery, per landmark set and score, with the times
/// per comparison (timed on pairs of this group) and per description (`ms_desc`).
fn score_group(
    gallery: &[Face],
    locators: &[[Option<FaceLocator<'_>>; 2]],
    probes: &[Face],
    elastic: &ElasticOptions,
    ms_desc: &[f64; 4],
) -> Result<Scored> {
    let gid: Vec<usize> = gallery.iter().map(|g| g.identity).collect();
    let pid: Vec<usize> = probes.iter().map(|p| p.identity).collect();
    let mut all = Vec::new();
    let mut per_probe = Vec::new();
    let mut by_pair = Vec::new();
    let mut fallbacks = Vec::new();
    for (k, set) in SETS.iter().enumerate() {
        let gal: Vec<Option<(&Described, &FaceLocator<'_>)>> = gallery
            .iter()
            .zip(locators)
            .map(|(g, l)| g.desc[k].as_ref().ok().zip(l[k].as_ref()))
            .collect();
        let (rows, pairs): (Vec<Row>, Vec<Vec<PairDistances>>) = probes
            .par_iter()
            .map(|p| score_row(p.desc[k].as_ref().ok(), &p.pts[k], &gal, elastic))
            .unzip();
        let pr: Vec<(Option<&Described>, &[DVec3])> = probes
            .iter()
            .map(|p| (p.desc[k].as_ref().ok(), p.pts[k].as_slice()))
            .collect();
        let ms_cmp = time_comparisons(&timed_pairs(&pr, &gal), elastic)?;
        all.extend(summarize(&rows, &ms_cmp, ms_desc, &pid, &gid, set));
        for (p, row) in probes.iter().zip(&rows) {
            for (j, score) in SCORES.iter().enumerate() {
                per_probe.push(probe_rank(&p.name, p.identity, set, score, &row[j], &gid));
            }
        }
        let mut kinds = std::collections::BTreeMap::<String, usize>::new();
        let (mut with, mut total) = (0, 0);
        for (p, ds) in probes.iter().zip(&pairs) {
            let Ok(x) = &p.desc[k] else { continue };
            for (g, (d, fb)) in gallery.iter().zip(ds) {
                total += 1;
                with += usize::from(!fb.is_empty());
                for f in fb {
                    *kinds.entry(f.clone()).or_default() += 1;
                }
                by_pair.push(
                    [
                        p.name.clone(),
                        p.identity.to_string(),
                        set.to_string(),
                        x.bip
                            .as_ref()
                            .map_or(String::new(), |b| format!("{:?}", b.pair)),
                        g.identity.to_string(),
                    ]
                    .into_iter()
                    .chain(d.iter().map(|v| format!("{v:.6}")))
                    .chain([fb.join("; ")])
                    .collect(),
                );
            }
        }
        let kinds: Vec<String> = kinds.iter().map(|(k, n)| format!("{k}: {n}")).collect();
        fallbacks.push(format!(
            "{set}: {with} of {total} bipolar comparisons took a fallback{}{}",
            if kinds.is_empty() { "" } else { " (" },
            if kinds.is_empty() {
                String::new()
            } else {
                kinds.join("; ") + ")"
            }
        ));
    }
    Ok(Scored {
        metrics: all,
        per_probe,
        by_pair,
        fallbacks,
    })
}

/// What [`score_group`] gives: the figures, the lines of `probes.csv` and those of
/// `bipolar-pairs.csv`, and per landmark set the count of bipolar comparisons that took a
/// fallback ([`facematch::Comparison::fallbacks`]), by kind.
struct Scored {
    metrics: Vec<Metrics>,
    per_probe: Vec<Vec<String>>,
    by_pair: Vec<Vec<String>>,
    fallbacks: Vec<String>,
}

/// One line of `probes.csv`: where the probe's own identity ranks among the gallery for one
/// score (1 = identified; empty when its genuine score failed), its genuine score, and the
/// best impostor with its score.
fn probe_rank(
    name: &str,
    identity: usize,
    set: &str,
    score: &str,
    row: &[f64],
    gallery_id: &[usize],
) -> Vec<String> {
    let genuine = row
        .iter()
        .zip(gallery_id)
        .filter(|(_, &g)| g == identity)
        .map(|(v, _)| *v)
        .fold(f64::NAN, f64::min);
    let impostor = row
        .iter()
        .zip(gallery_id)
        .filter(|(v, &g)| g != identity && v.is_finite())
        .min_by(|a, b| a.0.total_cmp(b.0).then(a.1.cmp(b.1)));
    let rank = genuine.is_finite().then(|| {
        1 + row
            .iter()
            .zip(gallery_id)
            .filter(|(v, &g)| g != identity && v.is_finite() && **v < genuine)
            .count()
    });
    let num = |v: f64| {
        if v.is_finite() {
            format!("{v:.6}")
        } else {
            String::new()
        }
    };
    vec![
        name.to_string(),
        identity.to_string(),
        set.to_string(),
        score.to_string(),
        rank.map(|r| r.to_string()).unwrap_or_default(),
        num(genuine),
        impostor.map(|(_, g)| g.to_string()).unwrap_or_default(),
        impostor.map(|(v, _)| num(*v)).unwrap_or_default(),
    ]
}

/// Every failure of a group: (face, landmark set, what failed).
fn failures(faces: &[Face], group: &str) -> Vec<[String; 4]> {
    let mut out = Vec::new();
    for f in faces {
        for (k, set) in SETS.iter().enumerate() {
            let what: Vec<String> = match &f.desc[k] {
                Err(e) => vec![e.clone()],
                Ok(d) => [
                    match &d.bip {
                        Ok(b) => b.sets[b.pair as usize].as_ref().err().cloned(),
                        Err(e) => Some(e.clone()),
                    }
                    .as_ref(),
                    d.facial.as_ref().err(),
                    d.iso.as_ref().err(),
                ]
                .into_iter()
                .flatten()
                .cloned()
                .collect(),
            };
            for w in what {
                out.push([group.to_string(), f.name.clone(), set.to_string(), w]);
            }
        }
    }
    out
}

/// `--detect-only`: scans, cleans and detects every face, writes `detection.csv` (per scan its
/// yaw, noise, each detected landmark's distance from its ground truth or why it is unseen, and
/// the detector's error when it found nothing) and a report with the errors and the share of
/// landmarks placed against the yaw (table and figures), and prints the count and every
/// failure.
fn detect_only(
    model: &FaceModel,
    generic: &GenericModel,
    specs: &[&FaceSpec],
    prep: &facematch::MatchOptions,
    out: &std::path::Path,
) -> Result<()> {
    /// One scan: its outcome, each landmark's error (`None`: not placed) and the reasons.
    struct Outcome {
        status: &'static str,
        err: [Option<f64>; 3],
        confidence: Option<f64>,
        why: String,
    }
    let pb = bar(specs.len(), "scan, prepare (clean, detect, crop, detect)");
    let outcomes: Vec<Outcome> = specs
        .par_iter()
        .map(|spec| {
            let r = scan_raw(model, spec).map(|(raw, _)| {
                let p = facematch::prepare_with(
                    facematch::ScanInput::Grid(&raw.grid),
                    generic,
                    prep,
                );
                (raw, p)
            });
            pb.inc(1);
            let failed = |status, why| Outcome {
                status,
                err: [None; 3],
                confidence: None,
                why,
            };
            match r {
                Err(e) => failed("scan failed", format!("{e:#}")),
                Ok((_, Err(e))) => failed("not found", e.to_string()),
                Ok((raw, Ok(p))) => {
                    let d = &p.detected;
                    let mut why = Vec::new();
                    let err = REFERENCE_LANDMARKS.map(|n| {
                        let k = n as usize;
                        let truth = raw.landmarks[k].position;
                        match d.get(n) {
                            Ok(l) => Some((l.position - truth).length()),
                            Err(u) => {
                                // Where the fitted face puts it: how far the pole would be
                                // if it were used anyway.
                                let off = (d.predicted[k] - truth).length();
                                why.push(format!(
                                    "{}: {u}; the fitted face predicts it {off:.2} mm from its ground truth",
                                    n.key()
                                ));
                                None
                            }
                        }
                    });
                    Outcome {
                        status: "found",
                        err,
                        confidence: Some(d.confidence),
                        why: why.join("; "),
                    }
                }
            }
        })
        .collect();
    pb.finish();
    let found = outcomes.iter().filter(|o| o.status == "found").count();
    let rows: Vec<Vec<String>> = specs
        .iter()
        .zip(&outcomes)
        .map(|(spec, o)| {
            let mut row = vec![
                spec.name.clone(),
                format!("{}", spec.settings.yaw_deg),
                format!("{}", spec.settings.noise_mm),
                o.status.to_string(),
            ];
            row.extend(o.err.iter().map(|e| match (e, o.status) {
                (Some(e), _) => format!("{e:.2}"),
                (None, "found") => "unseen".into(),
                (None, _) => String::new(),
            }));
            row.push(o.confidence.map_or(String::new(), |c| format!("{c:.3}")));
            row.push(o.why.clone());
            row
        })
        .collect();
    let mut rep = Report::new(out, "Landmark detection on the recognition's scans")?;
    rep.para(&format!(
        "`--detect-only`: landmarks found on {found} of {} scans (gallery, probes and sweeps of the run; `facematch::prepare`: cleaned, `landmarks::detect_visible` seen from the scanner, cropped around the detected nose tip, detected again). Errors are distances from the ground truth carried through the scanner (mm); a landmark not placed (not found, or unseen) has none.",
        outcomes.len()
    ));
    rep.csv(
        "detection.csv",
        &[
            "scan",
            "yaw (degrees)",
            "noise (mm)",
            "detection",
            "outer eye right (mm)",
            "outer eye left (mm)",
            "nose tip (mm)",
            "confidence",
            "why not found or unseen",
        ],
        &rows,
    )?;
    // Against the yaw, in 10-degree bins (centres -40 ... 40; 45 degrees counts as 40).
    let bin = |yaw: f64| ((yaw / 10.0).round() as i64).clamp(-4, 4) * 10;
    let bins: std::collections::BTreeMap<i64, Vec<&Outcome>> =
        specs
            .iter()
            .zip(&outcomes)
            .fold(Default::default(), |mut m, (spec, o)| {
                m.entry(bin(spec.settings.yaw_deg)).or_default().push(o);
                m
            });
    let mut table = Vec::new();
    let mut med_series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 3];
    let mut placed_series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 3];
    for (&b, os) in &bins {
        let mut row = vec![format!("{b}"), os.len().to_string()];
        for k in 0..3 {
            let errs: Vec<f64> = os.iter().filter_map(|o| o.err[k]).collect();
            let placed = errs.len() as f64 / os.len() as f64;
            let med = median(errs.clone());
            row.push(format!("{:.0} %", 100.0 * placed));
            row.push(if errs.is_empty() {
                "-".into()
            } else {
                format!("{med:.2} / {:.2}", p95(errs.clone()))
            });
            placed_series[k].push((b as f64, 100.0 * placed));
            if !errs.is_empty() {
                med_series[k].push((b as f64, med));
            }
        }
        table.push(row);
    }
    rep.table(
        &[
            "yaw bin (degrees)",
            "scans",
            "right outer corner placed",
            "its error median / p95 (mm)",
            "left outer corner placed",
            "its error median / p95 (mm)",
            "nose tip placed",
            "its error median / p95 (mm)",
        ],
        &table,
    );
    let names = ["right outer corner", "left outer corner", "nose tip"];
    let figures = [
        (
            "detection-error-yaw.svg",
            "Detection error against yaw (median over the landmarks placed)",
            "median error (mm)",
            med_series,
            "Median detection error per yaw bin",
        ),
        (
            "detection-placed-yaw.svg",
            "Landmarks placed against yaw",
            "placed (% of the bin's scans)",
            placed_series,
            "Share of scans on which each landmark was placed (not found or unseen: not placed)",
        ),
    ];
    for (file, title, y_label, per_landmark, caption) in figures {
        let series: Vec<Series> = per_landmark
            .into_iter()
            .zip(names)
            .map(|(pts, n)| Series::new(n, pts))
            .collect();
        let x_label = "yaw (degrees, 10-degree bins)";
        crate::report::line_plot(&rep.path(file), title, x_label, y_label, &series)?;
        rep.figure(file, caption);
    }
    let failures: Vec<String> = rows
        .iter()
        .filter(|r| r[3] != "found" || !r[8].is_empty())
        .map(|r| format!("{}: {}: {}", r[0], r[3], r[8]))
        .collect();
    if !failures.is_empty() {
        rep.heading(2, "Not found or not placed");
        rep.list(&failures);
    }
    rep.png_twins()?;
    let path = rep.finish()?;
    eprintln!("landmarks found on {found} of {} scans", rows.len());
    for f in &failures {
        eprintln!("  {f}");
    }
    println!("{}", path.display());
    Ok(())
}

/// 95th percentile (nearest rank) of the finite values.
fn p95(v: Vec<f64>) -> f64 {
    order_stat(v, |n| ((n - 1) as f64 * 0.95).round() as usize)
}

/// Runs the scan benchmark; prints the output folder on the last line.
pub(super) fn run(args: &Args, model: &FaceModel, t0: Instant) -> Result<()> {
    let identities = args.identities.unwrap_or(16);
    let expressions = args.expressions.unwrap_or(3);
    if identities < 2 || expressions < 2 {
        bail!("need at least 2 identities and 2 expressions (one neutral gallery face + probes)");
    }
    let out = args.io.out.out_dir("recognition-scans");
    let base = args.scan.settings();
    let generic =
        GenericModel::default_model().map_err(|e| anyhow::anyhow!("landmark model: {e}"))?;
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
    let mut dopt = DescribeOptions {
        levels: args.res.levels,
        sectors: args.res.sectors,
        iso_levels: None,
        boundary_margin: (args.boundary_margin > 0.0).then_some(args.boundary_margin),
        max_incidence_deg: (args.max_incidence > 0.0).then_some(args.max_incidence),
        ref_search: (args.ref_search > 0.0).then_some(args.ref_search),
        view_match: (!args.no_view_match).then_some(args.view_match),
        side_pair_deg: (!args.no_side_pair).then_some(args.side_pair),
        least_pair: !(args.no_side_pair || args.own_pair_only),
        second_weight: args.pair_second,
        predicted_corners: args.predicted_corners,
        search_all_pairs: !args.own_pair_search,
    };
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
        },
        ..dopt.matching()
    };
    let elastic = elastic_options(args.curve_samples);
    // Specs: gallery, main probes, sweeps (each face its own scan seed).
    let weights = sample_weights(model, identities, expressions, args.seed);
    let mut rng = ChaCha8Rng::seed_from_u64(scan_seed(args.seed, u64::MAX));
    let mut n_spec = 0u64;
    let mut spec = |identity: usize, expression: usize, settings: ScanSettings, tag: &str| {
        n_spec += 1;
        FaceSpec {
            name: format!("id{identity:02}-e{expression}{tag}"),
            identity,
            identity_weights: weights[identity].0.clone(),
            expression_weights: weights[identity].1[expression].clone(),
            settings,
            seed: scan_seed(args.seed, n_spec),
        }
    };
    let gallery_specs: Vec<FaceSpec> = (0..identities).map(|i| spec(i, 0, base, "")).collect();
    let mut probe_specs = Vec::new();
    for i in 0..identities {
        for e in 1..expressions {
            let yaw =
                rng.random_range(0..=45) as f64 * if rng.random::<bool>() { 1.0 } else { -1.0 };
            let noise = PROBE_NOISE[rng.random_range(0..PROBE_NOISE.len())];
            let st = ScanSettings {
                yaw_deg: yaw,
                noise_mm: noise,
                ..base
            };
            probe_specs.push(spec(i, e, st, &format!("-yaw{yaw}-noise{noise}")));
        }
    }
    let sweep_defs = if args.no_sweeps { Vec::new() } else { sweeps() };
    let sweep_ids = args.sweep_identities.min(identities);
    let sweep_specs: Vec<Vec<Vec<FaceSpec>>> = sweep_defs
        .iter()
        .map(|sw| {
            sw.values
                .iter()
                .map(|&v| {
                    (0..sweep_ids)
                        .map(|i| spec(i, 1, (sw.apply)(base, v), &format!("-{}{v}", sw.name)))
                        .collect()
                })
                .collect()
        })
        .collect();
    if let Some(&i) = args.only_identities.iter().find(|&&i| i >= identities) {
        bail!(
            "--only-identities {i}: the run has identities 0 to {}",
            identities - 1
        );
    }
    // The iso-curvature levels come from the whole run's first gallery scan.
    let first_gallery = gallery_specs[0].clone();
    // `--only-identities` and `--only-probes`: the specs keep the whole run's seeds.
    let named = |s: &FaceSpec| {
        args.only_probes.is_empty()
            || args
                .only_probes
                .iter()
                .any(|p| s.name.starts_with(p.as_str()))
    };
    let of_identity = |s: &FaceSpec| {
        args.only_identities.is_empty() || args.only_identities.contains(&s.identity)
    };
    let gallery_specs = kept_specs(gallery_specs, of_identity);
    let probe_specs = kept_specs(probe_specs, |s| of_identity(s) && named(s));
    let sweep_specs: Vec<Vec<Vec<FaceSpec>>> = sweep_specs
        .into_iter()
        .map(|groups| {
            groups
                .into_iter()
                .map(|v| kept_specs(v, |s| of_identity(s) && named(s)))
                .collect()
        })
        .collect();
    if probe_specs.is_empty() && sweep_specs.iter().flatten().all(Vec::is_empty) {
        bail!(
            "no probe left: --only-identities {:?}, --only-probes {:?}",
            args.only_identities,
            args.only_probes
        );
    }
    if args.detect_only {
        let specs: Vec<&FaceSpec> = gallery_specs
            .iter()
            .chain(&probe_specs)
            .chain(sweep_specs.iter().flatten().flatten())
            .collect();
        return detect_only(model, &generic, &specs, &prep, &out);
    }
    if let Some(dir) = &args.save_scans {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating --save-scans {}", dir.display()))?;
    }
    let methods = resolve_methods(&args.method, &meshcore::shapes::icosphere(1))?;
    let method = methods[0].used;
    // Iso-curvature levels: from the first gallery scan (ground-truth landmarks), scanned once
    // more here (without detection) before the runs.
    {
        let first = scan_face(
            model,
            &generic,
            &first_gallery,
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
        dopt.iso_levels = Some(iso_levels_of(
            &first.mesh,
            solver.as_ref(),
            Lm::new(r, q, nose),
            args.iso_levels,
        )?);
    }
    let n_faces = gallery_specs.len()
        + probe_specs.len()
        + sweep_specs.iter().flatten().map(Vec::len).sum::<usize>();
    eprintln!(
        "{n_faces} scans ({} gallery, {} probes, {} sweep scans); geodesics: {}",
        gallery_specs.len(),
        probe_specs.len(),
        n_faces - gallery_specs.len() - probe_specs.len(),
        method.name()
    );
    let run = |specs: &[FaceSpec], keep: bool, msg: &str| {
        process(
            model,
            &generic,
            specs,
            keep,
            method,
            &dopt,
            &scan_opts,
            &prep,
            args.icp_points,
            args.save_scans.as_deref(),
            msg,
        )
    };
    let gallery = run(&gallery_specs, true, "gallery scans");
    let locators: Vec<[Option<FaceLocator<'_>>; 2]> = gallery
        .iter()
        .map(|g| [0, 1].map(|k| g.mesh[k].as_ref().map(FaceLocator::new)))
        .collect();
    let probes = run(&probe_specs, false, "probe scans");
    // Description times: the first gallery scans again, one at a time on one thread.
    let first: Vec<(&TriMesh, Lm)> = gallery
        .iter()
        .filter_map(|g| {
            let m = g.mesh[0].as_ref()?;
            g.gt_lm.map(|lm| (m, lm))
        })
        .take(TIMED_FACES)
        .collect();
    let ms_desc = time_descriptions(&first, method, &dopt)?;
    let Scored {
        metrics: main,
        per_probe,
        by_pair,
        fallbacks,
    } = score_group(&gallery, &locators, &probes, &elastic, &ms_desc)?;
    let mut fails = failures(&gallery, "gallery");
    fails.extend(failures(&probes, "probes"));
    // Sweeps.
    let mut sweep_results: Vec<Vec<Vec<Metrics>>> = Vec::new();
    let mut sweep_faces: Vec<Face> = Vec::new();
    for (sw, groups) in sweep_defs.iter().zip(&sweep_specs) {
        let mut per_value = Vec::new();
        for (v, specs) in sw.values.iter().zip(groups) {
            let faces = run(specs, false, &format!("sweep {} {v}", sw.name));
            per_value.push(score_group(&gallery, &locators, &faces, &elastic, &ms_desc)?.metrics);
            fails.extend(failures(&faces, &format!("sweep {} {v}", sw.name)));
            sweep_faces.extend(faces);
        }
        sweep_results.push(per_value);
    }
    let secs = t0.elapsed().as_secs_f64();

    // Report.
    let mut rep = Report::new(
        &out,
        "Recognition benchmark on range scans of sampled ICT faces",
    )?;
    rep.para(&format!(
        "{identities} identities x {expressions} faces (seed {}). Gallery: {} neutral frontal scans ({}). Probes: {} scans of the other expressions, each under a random yaw of 0-45 degrees to either side and a noise of {} mm (other settings as the gallery). Scans by `rangescan` (orthographic), cleaned by `scanprep` (spikes, holes up to 10 mm, small components, crop of {} mm around the nose tip{}): for the ground-truth landmarks around the true nose tip; for the detected landmarks by `facematch::prepare`, as a user's scans are (cleaned, landmarks detected, cleaned again with the crop around the *detected* nose tip, detected again: no ground truth on that path, and ICP's detected rows use these scans too). Geodesics: {}. Bipolar descriptor: static area, N = {} levels between the outer eye corners, {}; single pole: {} sectors around the nose tip; ICP: about {} probe vertices onto the gallery surface from the 3-landmark alignment, 10 % trimmed, score = RMS closest-point distance (mm); facial curves: N level curves of the nose-tip field up to D, elastic distance ({} segments per curve, one start-point candidate, one alternation), root sum of squares; iso-curvature: {} levels per principal field (quantiles of the first gallery scan) in the geodesic disc of radius D around the nose tip, normalised RMS closest-point distance after an ICP started from the 3-landmark alignment. Times, single thread (one-thread pool after the parallel work): per comparison the mean over up to 24 probe x gallery pairs per group and landmark set; per description the median over the first 6 gallery scans (ground truth) of the fields a representation needs plus its build. Ground-truth landmarks: the model's landmark vertices carried through the scanner, at the nearest vertex of the cleaned scan (a landmark the scanner does not see is a failure); detected: `landmarks::detect_visible` on the scan `facematch::prepare` made, seen from the scanner (+z).",
        args.seed,
        gallery.len(),
        base.label(),
        probes.len(),
        PROBE_NOISE.map(|x| x.to_string()).join(" / "),
        args.scan.crop_radius,
        scan_opts
            .clean
            .target_edge_mm
            .map(|e| format!(", then decimated to {e} mm edges"))
            .unwrap_or_default(),
        method.name(),
        args.res.levels,
        match (dopt.boundary_margin, dopt.max_incidence_deg) {
            (None, None) => "every part of the scan".to_string(),
            (b, i) => format!(
                "leaving out {}",
                b.map(|m| format!("a band of {m} mm along the holes and the border"))
                    .into_iter()
                    .chain(i.map(|d| format!("what the scanner saw at more than {d} degrees of incidence")))
                    .collect::<Vec<_>>()
                    .join(" and ")
            ),
        } + &dopt
            .ref_search
            .map(|r| format!(", each probe also described from its outer eye corners moved by {r} mm in {SEARCH_DIRECTIONS} directions (`bipolar::reference_candidates`), its score the least distance over these descriptors and its own"))
            .unwrap_or_default()
            + &dopt
                .view_match
                .map(|a| format!("; view matching: where a probe's scanner direction, carried into a gallery scan's frame by the 3-landmark alignment, is more than {a} degrees from the gallery's own, the gallery scan is described again on the faces a scanner would measure from that direction (`rangescan::visible_faces`, incidence up to {} degrees; landmarks whose faces are all gone moved to the nearest vertex left, within {MAX_SNAP_MM} mm), so a bipolar comparison includes that description", facematch::ViewOptions::default().incidence_deg))
                .unwrap_or_default()
            + &dopt
                .side_pair_deg
                .map(|a| format!("; side pairs: every face is also described by each outer eye corner with the nose tip (their lens above the nose tip's horizontal plane); a probe turned by more than {a} degrees (its eye line against its scanner), or with an outer eye corner off the scan, takes its nearer (or remaining) corner's side pair as its own pair, which the reference-point search moves; {}", if dopt.least_pair {
                    format!("its score is the least distance over the three pairs (outer eye corners, right corner and nose tip, left corner and nose tip){}, each view-matched{}", if dopt.second_weight > 0.0 {
                        format!(" blended with the second least ({} x least + {} x second least)", 1.0 - dopt.second_weight, dopt.second_weight)
                    } else {
                        String::new()
                    }, if dopt.search_all_pairs && dopt.ref_search.is_some() {
                        ", and the reference-point search moves the poles of all three pairs (a nose tip's first direction toward the corners' midpoint)"
                    } else {
                        ""
                    })
                } else {
                    "its score is its own pair's distance".to_string()
                }))
                .unwrap_or_default(),
        args.res.sectors,
        args.icp_points,
        args.curve_samples,
        args.iso_levels,
    ));
    if !args.only_identities.is_empty() {
        rep.para(&format!(
            "Only identities {:?} of the {identities} (`--only-identities`): their scans as in the whole run, ranks among them alone.",
            args.only_identities
        ));
    }
    if !args.only_probes.is_empty() {
        rep.para(&format!(
            "Only the probes and sweep scans whose names start with {:?} (`--only-probes`), scanned as in the whole run, against the whole gallery.",
            args.only_probes
        ));
    }
    if args.predicted_corners {
        rep.para(&format!("Detected landmarks: an outer eye corner the detector reports unseen is placed at the vertex nearest where the fitted face predicts it, when that is within {MAX_SNAP_MM} mm of the cleaned scan (`--predicted-corners`)."));
    }
    rep.heading(2, "Main run");
    results_table(&mut rep, &main, "results.csv")?;
    paired_table(&mut rep, &main);
    rep.csv(
        "probes.csv",
        &[
            "probe",
            "identity",
            "landmarks",
            "score",
            "rank",
            "genuine",
            "best impostor",
            "best impostor score",
        ],
        &per_probe,
    )?;
    rep.para("Per probe and score: the rank of the probe's own identity in the gallery (1: identified; empty: its genuine comparison failed), its score and the nearest other identity (`probes.csv`).");
    rep.csv(
        "bipolar-pairs.csv",
        &[
            "probe",
            "identity",
            "landmarks",
            "probe pair",
            "gallery identity",
            "corners",
            "right corner and nose",
            "left corner and nose",
            "fallbacks",
        ],
        &by_pair,
    )?;
    rep.para("The bipolar distance of every probe to every gallery face by each pole pair (`bipolar-pairs.csv`; NaN where a side has no descriptor), with the fallbacks the comparison took (a view's descriptor that failed replaced by the gallery face's own, a probe's own descriptor that failed replaced by its moved ones): the probe's own pair is its score.");
    rep.list(&fallbacks);
    for f in &fallbacks {
        println!("{f}");
    }
    roc_figure(&mut rep, &main, "roc.svg", "ROC on scans (verification)")?;
    // Landmark detection on every scan of the run.
    let everyone: Vec<&Face> = gallery.iter().chain(&probes).chain(&sweep_faces).collect();
    let detected = everyone.iter().filter(|f| f.desc[1].is_ok()).count();
    let errs: Vec<[f64; 3]> = everyone.iter().filter_map(|f| f.det_err).collect();
    let col = |k: usize| errs.iter().map(|e| e[k]).collect::<Vec<f64>>();
    rep.para(&format!(
        "Landmarks on all {} scans: described with detected landmarks {detected}; detection errors (mm, median / p95) right outer corner {:.2} / {:.2}, left outer corner {:.2} / {:.2}, nose tip {:.2} / {:.2}.",
        everyone.len(),
        median(col(0)), p95(col(0)), median(col(1)), p95(col(1)), median(col(2)), p95(col(2)),
    ));
    let lm_rows: Vec<Vec<String>> = everyone
        .iter()
        .map(|f| {
            let mut row = vec![f.name.clone()];
            match f.det_err {
                Some(e) => row.extend(e.iter().map(|x| format!("{x:.2}"))),
                None => row.extend(std::iter::repeat_n(String::new(), 3)),
            }
            row
        })
        .collect();
    rep.csv(
        "landmarks.csv",
        &[
            "scan",
            "outer eye right (mm)",
            "outer eye left (mm)",
            "nose tip (mm)",
        ],
        &lm_rows,
    )?;
    rep.para("Per scan: the distance of each detected landmark from its ground truth (`landmarks.csv`; empty where detection failed or the ground truth is not on the scan).");
    let time_row = |k: usize| median(everyone.iter().map(|f| f.secs[k]).collect());
    rep.para(&format!(
        "Per scan (median wall time, {} valid samples, {} vertices after cleaning): scan {:.2} s, clean (ground truth's) {:.2} s, `facematch::prepare` (the detected landmarks' cleanings and detections) {:.2} s, the four representations with both landmark sets {:.2} s (faces in parallel on every core, so these are upper bounds of the single-scan times).",
        median(everyone.iter().map(|f| f.valid_samples as f64).collect()),
        median(everyone.iter().map(|f| f.vertices as f64).collect()),
        time_row(0), time_row(1), time_row(2), time_row(3)
    ));
    // Sweeps: rank-1 against each setting, and where each method breaks.
    if !sweep_defs.is_empty() {
        rep.heading(2, "Sweeps");
        rep.para(&format!(
            "Probes: expression 1 of the first {sweep_ids} identities, rescanned at each value (the other settings those of the gallery), against the whole gallery of {identities}. 'Breaks at' is the first value at which rank-1 is more than 0.1 below its value at the gallery's setting."
        ));
        let mut csv_rows = Vec::new();
        for (sw, per_value) in sweep_defs.iter().zip(&sweep_results) {
            let ref_value = match sw.name {
                "noise" => base.noise_mm,
                "pitch" => base.pitch_mm,
                _ => base.yaw_deg,
            };
            let mut hdr = vec![format!("{} ({})", sw.name, sw.unit)];
            let mut series = Vec::new();
            let mut breaks = Vec::new();
            for (j, m0) in per_value[0].iter().enumerate() {
                let label = format!("{} ({})", m0.descriptor, m0.landmarks);
                hdr.push(label.clone());
                let pts: Vec<(f64, f64)> = sw
                    .values
                    .iter()
                    .zip(per_value)
                    .map(|(&v, ms)| (v, ms[j].rank1))
                    .collect();
                let at_ref = pts
                    .iter()
                    .find(|(v, _)| (*v - ref_value).abs() < 1e-9)
                    .map(|p| p.1);
                let br = at_ref.and_then(|r0| pts.iter().find(|(_, r)| *r < r0 - 0.1));
                breaks.push(vec![
                    label.clone(),
                    at_ref.map_or("n/a".into(), |r| format!("{r:.3}")),
                    br.map_or("does not break in the range".into(), |(v, r)| {
                        format!("{v} {} (rank-1 {r:.3})", sw.unit)
                    }),
                ]);
                series.push(Series {
                    name: label,
                    points: pts,
                    dashed: m0.landmarks == "detected",
                });
            }
            rep.heading(3, &format!("Rank-1 against {}", sw.name));
            let rows: Vec<Vec<String>> = sw
                .values
                .iter()
                .zip(per_value)
                .map(|(v, ms)| {
                    let mut r = vec![v.to_string()];
                    r.extend(ms.iter().map(|m| format!("{:.3}", m.rank1)));
                    csv_rows
                        .push([vec![sw.name.to_string(), v.to_string()], r[1..].to_vec()].concat());
                    r
                })
                .collect();
            let hdr_ref: Vec<&str> = hdr.iter().map(String::as_str).collect();
            rep.table(&hdr_ref, &rows);
            let file = format!("sweep-{}.svg", sw.name);
            line_plot(
                &rep.path(&file),
                &format!("Rank-1 against {}", sw.name),
                &format!("{} ({})", sw.name, sw.unit),
                "rank-1",
                &series,
            )?;
            rep.figure(
                &file,
                &format!("Rank-1 against {}; dashed: detected landmarks", sw.name),
            );
            rep.table(
                &[
                    "method (landmarks)",
                    "rank-1 at the gallery's setting",
                    "breaks at",
                ],
                &breaks,
            );
        }
        let mut hdr = vec!["sweep".to_string(), "value".to_string()];
        hdr.extend(
            main.iter()
                .map(|m| format!("{} ({})", m.descriptor, m.landmarks)),
        );
        let hdr_ref: Vec<&str> = hdr.iter().map(String::as_str).collect();
        rep.csv("sweeps.csv", &hdr_ref, &csv_rows)?;
    }
    // Failures.
    rep.heading(2, "Failures");
    let count = |set: &str| fails.iter().filter(|f| f[2] == set).count();
    rep.para(&format!(
        "{} failures over {} scans x 2 landmark sets (ground truth {}, detected {}): each is listed with the face, never replaced; its scores count as failed pairs (the worst score) in rank-1 and EER. All are in `failures.csv`; the first 40:",
        fails.len(),
        everyone.len(),
        count("ground_truth"),
        count("detected"),
    ));
    let hdr = ["group", "face", "landmarks", "what failed"];
    let rows: Vec<Vec<String>> = fails.iter().map(|f| f.to_vec()).collect();
    rep.table(&hdr, &rows[..rows.len().min(40)]);
    rep.csv("failures.csv", &hdr, &rows)?;
    rep.png_twins()?;
    rep.para(&format!("Run time: {secs:.1} s wall."));
    rep.finish()?;
    let fields = serde_json::json!({
        "gallery_scan": base.label(),
        "sweep_identities": sweep_ids,
        "scan_edge_mm": scan_opts.clean.target_edge_mm,
        "scan_smoothing_iterations": scan_opts.clean.smoothing_iterations,
        "detect_smoothing_iterations": scan_opts.detect_smoothing,
        "boundary_margin_mm": dopt.boundary_margin,
        "max_incidence_deg": dopt.max_incidence_deg,
        "sweeps": sweep_defs.iter().zip(&sweep_results).map(|(sw, pv)| serde_json::json!({
            "name": sw.name,
            "unit": sw.unit,
            "values": sw.values,
            "results": pv,
        })).collect::<Vec<_>>(),
        "failures": fails.len(),
        "scans": everyone.len(),
        "seconds": secs,
    });
    let sampled = [identities, expressions, gallery.len(), probes.len()];
    write_summary(&out, args, sampled, method, fields, &main)?;
    eprintln!("{} failures; {secs:.1} s wall", fails.len());
    println!("{}", out.display());
    Ok(())
}
