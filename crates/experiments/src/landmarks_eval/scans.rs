//! `landmarks-eval --scans`: detection on range scans of sampled ICT faces against the ground
//! truth the scanner projected.

use super::{stats, test_seed, Args, Stats};
use crate::pipeline::bar;
use crate::scans::{sample_weights, scan_faces, scan_seed, FaceSpec, ScanSetOptions};
use anyhow::{Context, Result};
use facemodel::FaceModel;
use landmarks::{DetectOptions, GenericModel, LandmarkName};
use meshcore::DVec3;
use std::time::Instant;

/// Outcome of one scanned test face: per landmark the error in mm (`inf`: not found, the face
/// or the landmark), or why the truth is not on the cleaned scan; why the detector reported a
/// landmark unseen; the detector's error message.
struct ScanOutcome {
    name: String,
    errors: [Result<f64, String>; 5],
    unseen: [Option<String>; 5],
    not_found: Option<String>,
    valid_samples: usize,
    vertices: usize,
    detect_ms: f64,
}

/// `--scans`: detection on range scans of the test faces against the ground truth the scanner
/// projected.
pub(super) fn run_scans(
    args: &Args,
    ict: &FaceModel,
    generic: &GenericModel,
    dopt: &DetectOptions,
    out: &std::path::Path,
) -> Result<()> {
    let t0 = Instant::now();
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let settings = args.scan.settings();
    let seed = test_seed(args.seed);
    let weights = sample_weights(ict, args.faces, 2, seed);
    let mut specs: Vec<FaceSpec> = weights
        .into_iter()
        .enumerate()
        .map(|(i, (w, ex))| FaceSpec {
            name: format!("face{i:03}"),
            identity: i,
            identity_weights: w,
            expression_weights: if args.neutral {
                Vec::new()
            } else {
                ex[1].clone()
            },
            settings,
            seed: scan_seed(seed, i as u64),
        })
        .collect();
    if let Some(i) = args.only {
        anyhow::ensure!(
            i < specs.len(),
            "--only {i}: only {} test faces",
            specs.len()
        );
        specs = vec![specs.swap_remove(i)];
    }
    let pb = bar(specs.len(), "scanning and detecting");
    let opts = ScanSetOptions {
        clean: scanprep::CleanOptions {
            crop: Some(scanprep::Crop {
                centre: DVec3::ZERO,
                radius_mm: args.scan.crop_radius,
            }),
            ..scanprep::CleanOptions::default()
        },
        detect: Some(*dopt),
        ..ScanSetOptions::default()
    };
    let faces = scan_faces(ict, generic, &specs, &opts, &pb);
    pb.finish_and_clear();
    let mut scan_failures = Vec::new();
    let mut outcomes = Vec::new();
    for (spec, f) in specs.iter().zip(faces) {
        let f = match f {
            Ok(f) => f,
            Err(e) => {
                scan_failures.push(e);
                continue;
            }
        };
        let errors = LandmarkName::ALL.map(|n| {
            let t = &f.truth[n as usize];
            match (&t.vertex, &f.detected) {
                (Err(why), _) => Err(why.clone()),
                (Ok(_), Ok(d)) => Ok(d
                    .get(n)
                    .map_or(f64::INFINITY, |l| (l.position - t.position).length())),
                (Ok(_), Err(_)) => Ok(f64::INFINITY),
            }
        });
        let unseen = LandmarkName::ALL.map(|n| {
            f.detected
                .as_ref()
                .ok()
                .and_then(|d| d.get(n).err())
                .map(|u| u.to_string())
        });
        outcomes.push(ScanOutcome {
            name: spec.name.clone(),
            errors,
            unseen,
            not_found: f.detected.as_ref().err().cloned(),
            valid_samples: f.valid_samples,
            vertices: f.mesh.n_vertices(),
            detect_ms: f.times.detect.as_secs_f64() * 1e3,
        });
    }
    anyhow::ensure!(
        !outcomes.is_empty(),
        "no scan could be made: {}",
        scan_failures.join("; ")
    );
    let names: Vec<&str> = LandmarkName::ALL.iter().map(|n| n.key()).collect();
    // Errors of the landmarks whose truth is on the cleaned scan (inf: not found).
    let st: Vec<Stats> = LandmarkName::ALL
        .iter()
        .map(|&n| {
            let e: Vec<f64> = outcomes
                .iter()
                .filter_map(|o| o.errors[n as usize].as_ref().ok().copied())
                .collect();
            stats(n.key(), &e)
        })
        .collect();
    // Silent wrong landmarks: reported more than 10 mm off, or reported where the truth is not
    // on the cleaned scan (occluded, outside the grid or the crop).
    let silent: Vec<(String, String)> = outcomes
        .iter()
        .filter(|o| o.not_found.is_none())
        .flat_map(|o| {
            LandmarkName::ALL
                .iter()
                .filter(|&&n| o.unseen[n as usize].is_none())
                .filter_map(|&n| match &o.errors[n as usize] {
                    Ok(e) if *e > 10.0 => Some((o.name.clone(), format!("{n} {e:.1} mm off"))),
                    Err(why) => Some((o.name.clone(), format!("{n} reported but {why}"))),
                    _ => None,
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let silent_of = |n: LandmarkName| {
        silent
            .iter()
            .filter(|(_, w)| w.starts_with(n.key()))
            .count()
    };
    let not_found: Vec<(&str, &str)> = outcomes
        .iter()
        .filter_map(|o| o.not_found.as_deref().map(|e| (o.name.as_str(), e)))
        .collect();
    let n = outcomes.len();
    let nf_rate = not_found.len() as f64 / n as f64;
    // Landmarks of found faces reported unseen: where the truth is not on the cleaned scan
    // (right) and where it is (a landmark not found).
    let reported_unseen = |truth_on_scan: bool| -> usize {
        outcomes
            .iter()
            .map(|o| {
                (0..5)
                    .filter(|&k| o.unseen[k].is_some() && o.errors[k].is_ok() == truth_on_scan)
                    .count()
            })
            .sum()
    };
    let (unseen_right, unseen_missed) = (reported_unseen(false), reported_unseen(true));
    let unseen: usize = outcomes
        .iter()
        .map(|o| o.errors.iter().filter(|e| e.is_err()).count())
        .sum();
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let mut vs: Vec<f64> = outcomes.iter().map(|o| o.valid_samples as f64).collect();
    let mut vv: Vec<f64> = outcomes.iter().map(|o| o.vertices as f64).collect();
    let mut dt: Vec<f64> = outcomes.iter().map(|o| o.detect_ms).collect();
    let (med_valid, med_vertices, med_detect) = (med(&mut vs), med(&mut vv), med(&mut dt));
    println!(
        "{n} scanned test faces ({}; {}), generic model from {} training faces; errors in mm",
        if args.neutral {
            "neutral"
        } else {
            "random expressions"
        },
        settings.label(),
        generic.n_training
    );
    println!(
        "median {med_valid:.0} valid samples, {med_vertices:.0} vertices after cleaning; detection wall time median {med_detect:.0} ms"
    );
    println!(
        "{:<16} {:>5} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}",
        "landmark", "n", "mean", "median", "p95", "max", "<2.5", "<5", "<10", ">10 silent"
    );
    for (s, &nm) in st.iter().zip(&LandmarkName::ALL) {
        println!(
            "{:<16} {:>5} {:>7.2} {:>7.2} {:>7.2} {:>7.2} {:>6.1}% {:>6.1}% {:>6.1}% {:>7}",
            s.landmark,
            s.n,
            s.mean_mm,
            s.median_mm,
            s.p95_mm,
            s.max_mm,
            100.0 * s.within_2_5mm,
            100.0 * s.within_5mm,
            100.0 * s.within_10mm,
            silent_of(nm)
        );
    }
    println!(
        "not found: {} of {n} faces ({:.1} %); ground-truth landmarks not on the cleaned scan: {unseen}; scans that failed: {}",
        not_found.len(),
        100.0 * nf_rate,
        scan_failures.len()
    );
    for (name, e) in not_found.iter().take(20) {
        println!("  {name}: {e}");
    }
    println!(
        "landmarks of found faces reported unseen: {unseen_right} whose truth is not on the cleaned scan, {unseen_missed} whose truth is (counted as not found above)"
    );
    println!("silent wrong landmarks: {}", silent.len());
    for (name, w) in silent.iter().take(20) {
        println!("  {name}: {w}");
    }
    for e in scan_failures.iter().take(20) {
        println!("  scan failed: {e}");
    }
    let by = |n: LandmarkName| &st[n as usize];
    let corners = [
        by(LandmarkName::OuterEyeRight),
        by(LandmarkName::OuterEyeLeft),
    ];
    let targets = [
        (
            "outer eye corners median < 2 mm",
            corners.iter().all(|s| s.median_mm < 2.0),
        ),
        (
            "outer eye corners p95 < 4 mm",
            corners.iter().all(|s| s.p95_mm < 4.0),
        ),
        (
            "nose tip median < 2 mm",
            by(LandmarkName::NoseTip).median_mm < 2.0,
        ),
        ("not found < 2 %", nf_rate < 0.02),
        (
            "no outer corner or nose tip > 10 mm off unreported",
            [
                LandmarkName::OuterEyeRight,
                LandmarkName::OuterEyeLeft,
                LandmarkName::NoseTip,
            ]
            .iter()
            .all(|&n| silent_of(n) == 0),
        ),
    ];
    for (what, ok) in &targets {
        println!("target {what}: {}", if *ok { "met" } else { "NOT met" });
    }
    let secs = t0.elapsed().as_secs_f64();
    println!("wall time {secs:.1} s");
    let summary = serde_json::json!({
        "faces": n,
        "seed": args.seed,
        "expressions": !args.neutral,
        "scan": settings.label(),
        "crop_radius_mm": args.scan.crop_radius,
        "units_of_errors": "mm",
        "median_valid_samples": med_valid,
        "median_vertices_after_cleaning": med_vertices,
        "median_detect_ms": med_detect,
        "per_landmark": st,
        "not_found": not_found.iter().map(|(f, e)| serde_json::json!({"face": f, "error": e})).collect::<Vec<_>>(),
        "not_found_rate": nf_rate,
        "silent_wrong": silent.iter().map(|(f, w)| serde_json::json!({"face": f, "what": w})).collect::<Vec<_>>(),
        "truth_not_on_cleaned_scan": unseen,
        "reported_unseen": {"truth_not_on_scan": unseen_right, "truth_on_scan": unseen_missed},
        "scan_failures": scan_failures,
        "targets": targets.iter().map(|(w, ok)| serde_json::json!({"target": w, "met": ok})).collect::<Vec<_>>(),
        "seconds": secs,
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    let mut csv = format!(
        "face,{},valid_samples,vertices,detect_ms,error\n",
        names.join(",")
    );
    for o in &outcomes {
        let e: Vec<String> = o
            .errors
            .iter()
            .zip(&o.unseen)
            .map(|(e, u)| {
                let reported = u
                    .as_deref()
                    .map(|u| format!(" (reported unseen: {u})"))
                    .unwrap_or_default();
                match e {
                    Ok(x) => format!("{x:.2}{reported}"),
                    Err(why) => format!("unseen: {why}{reported}").replace(',', ";"),
                }
            })
            .collect();
        csv += &format!(
            "{},{},{},{},{:.0},{}\n",
            o.name,
            e.join(","),
            o.valid_samples,
            o.vertices,
            o.detect_ms,
            o.not_found.as_deref().unwrap_or("").replace(',', ";")
        );
    }
    std::fs::write(out.join("per-face.csv"), csv)?;
    let series: Vec<(String, Vec<f64>)> = LandmarkName::ALL
        .iter()
        .map(|&n| {
            (
                n.key().to_string(),
                outcomes
                    .iter()
                    .filter_map(|o| o.errors[n as usize].as_ref().ok())
                    .map(|x| x.min(15.0))
                    .collect(),
            )
        })
        .collect();
    viz::histogram(
        out.join("errors-histogram.svg"),
        &format!("Landmark errors on range scans ({})", settings.label()),
        "error (mm, clipped at 15)",
        &series,
        30,
    )?;
    println!("{}", out.display());
    Ok(())
}
