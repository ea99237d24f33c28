//! The report of a scan run: `report.md` with its tables and figures, the CSVs (results,
//! probes, bipolar pairs, landmarks, sweeps, failures) and `summary.json`.

use super::super::metrics::{
    median, paired_table, results_table, roc_figure, write_summary, Metrics,
};
use super::face::Face;
use super::score::Scored;
use super::{p95, Results, Setup};
use crate::report::Report;
use crate::scans::MAX_SNAP_MM;
use anyhow::Result;

/// Writes the report, its CSVs and figures and `summary.json`; prints the fallbacks' counts, the
/// failures' count and the output folder.
pub(super) fn write(s: &Setup<'_>, r: &Results, secs: f64) -> Result<()> {
    let Setup {
        args,
        identities,
        expressions,
        base,
        scan_opts,
        dopt,
        method,
        sweep_defs,
        sweep_ids,
        out,
    } = *s;
    let (gallery, probes, fails) = (&r.gallery, &r.probes, &r.fails);
    let main = &r.scored.metrics;
    let sweep_results = &r.sweep_results;
    let mut rep = Report::new(
        out,
        "Recognition benchmark on range scans of sampled ICT faces",
    )?;
    rep.para(&intro(s, r));
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
    main_section(&mut rep, &r.scored)?;
    let everyone: Vec<&Face> = gallery.iter().chain(probes).chain(&r.sweep_faces).collect();
    landmark_section(&mut rep, &everyone)?;
    sweeps_section(&mut rep, s, r)?;
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
        "boundary_margin_mm": dopt.matching.boundary_margin_mm,
        "max_incidence_deg": dopt.matching.max_incidence_deg,
        "sweeps": sweep_defs.iter().zip(sweep_results).map(|(sw, pv)| serde_json::json!({
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
    write_summary(out, args, sampled, method, fields, main)?;
    eprintln!("{} failures; {secs:.1} s wall", fails.len());
    println!("{}", out.display());
    Ok(())
}

/// The report's first paragraph: the run's faces, scans and settings.
fn intro(s: &Setup<'_>, r: &Results) -> String {
    let Setup {
        args,
        identities,
        expressions,
        base,
        scan_opts,
        dopt,
        method,
        ..
    } = *s;
    let (gallery, probes) = (&r.gallery, &r.probes);
    let m = &dopt.matching;
    format!(
    "{identities} identities x {expressions} faces (seed {}). Gallery: {} neutral frontal scans ({}). Probes: {} scans of the other expressions, each under a random yaw of 0-45 degrees to either side and a noise of {} mm (other settings as the gallery). Scans by `rangescan` (orthographic), cleaned by `scanprep` (spikes, holes up to 10 mm, small components, crop of {} mm around the nose tip{}): for the ground-truth landmarks around the true nose tip; for the detected landmarks by `facematch::prepare`, as a user's scans are (cleaned, landmarks detected, cleaned again with the crop around the *detected* nose tip, detected again: no ground truth on that path, and ICP's detected rows use these scans too). Geodesics: {}. Bipolar descriptor: static area, N = {} levels between the outer eye corners, {}; single pole: {} sectors around the nose tip; ICP: about {} probe vertices onto the gallery surface from the 3-landmark alignment, 10 % trimmed, score = RMS closest-point distance (mm); facial curves: N level curves of the nose-tip field up to D, elastic distance ({} segments per curve, one start-point candidate, one alternation), root sum of squares; iso-curvature: {} levels per principal field (quantiles of the first gallery scan) in the geodesic disc of radius D around the nose tip, normalised RMS closest-point distance after an ICP started from the 3-landmark alignment. Times, single thread (one-thread pool after the parallel work): per comparison the mean over up to 24 probe x gallery pairs per group and landmark set; per description the median over the first 6 gallery scans (ground truth) of the fields a representation needs plus its build. Ground-truth landmarks: the model's landmark vertices carried through the scanner, at the nearest vertex of the cleaned scan (a landmark the scanner does not see is a failure); detected: `landmarks::detect_visible` on the scan `facematch::prepare` made, seen from the scanner (+z).",
    args.seed,
    gallery.len(),
    base.label(),
    probes.len(),
    rangescan::PROBE_NOISE_MM.map(|x| x.to_string()).join(" / "),
    args.scan.crop_radius,
    scan_opts
        .clean
        .target_edge_mm
        .map(|e| format!(", then decimated to {e} mm edges"))
        .unwrap_or_default(),
    method.name(),
    args.res.levels,
    match (m.boundary_margin_mm, m.max_incidence_deg) {
        (None, None) => "every part of the scan".to_string(),
        (b, i) => format!(
            "leaving out {}",
            b.map(|m| format!("a band of {m} mm along the holes and the border"))
                .into_iter()
                .chain(i.map(|d| format!("what the scanner saw at more than {d} degrees of incidence")))
                .collect::<Vec<_>>()
                .join(" and ")
        ),
    } + &m
        .search
        .map(|r| format!(", each probe also described from its outer eye corners moved by {} mm in {} directions (`bipolar::reference_candidates`), its score the least distance over these descriptors and its own", r.radius_mm, r.directions))
        .unwrap_or_default()
        + &m
            .view
            .as_ref()
            .map(|v| format!("; view matching: where a probe's scanner direction, carried into a gallery scan's frame by the 3-landmark alignment, is more than {} degrees from the gallery's own, the probe is compared with the gallery face's template view nearest that direction (`facematch::views_of`, described once per gallery face: the faces a scanner turned by {:?} degrees to either side would measure, `rangescan::visible_faces`, incidence up to {} degrees; landmarks whose faces are all gone moved to the nearest vertex left, within {MAX_SNAP_MM} mm)", v.min_angle_deg, v.yaws_deg, v.incidence_deg))
            .unwrap_or_default()
        + &m
            .side_pair_deg
            .map(|a| format!("; side pairs: every face is also described by each outer eye corner with the nose tip (their lens above the nose tip's horizontal plane); a probe turned by more than {a} degrees (its eye line against its scanner), or with an outer eye corner off the scan, takes its nearer (or remaining) corner's side pair as its own pair, which the reference-point search moves; {}", if m.least_pair {
                format!("its score is the least distance over the three pairs (outer eye corners, right corner and nose tip, left corner and nose tip){}, each view-matched{}", if m.second_weight > 0.0 {
                    format!(" blended with the second least ({} x least + {} x second least)", 1.0 - m.second_weight, m.second_weight)
                } else {
                    String::new()
                }, if m.search.is_some_and(|s| s.all_pairs) {
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
    )
}

/// The main run: results, the paired comparison, `probes.csv`, `bipolar-pairs.csv` with the
/// fallbacks' counts (also printed) and the ROC.
fn main_section(rep: &mut Report, scored: &Scored) -> Result<()> {
    let Scored {
        metrics: main,
        per_probe,
        by_pair,
        fallbacks,
    } = scored;
    rep.heading(2, "Main run");
    results_table(rep, main, "results.csv")?;
    paired_table(rep, main);
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
        per_probe,
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
        by_pair,
    )?;
    rep.para("The bipolar distance of every probe to every gallery face by each pole pair (`bipolar-pairs.csv`; NaN where a side has no descriptor), with the fallbacks the comparison took (a view's descriptor that failed replaced by the gallery face's own, a probe's own descriptor that failed replaced by its moved ones): the probe's own pair is its score.");
    rep.list(fallbacks);
    for f in fallbacks {
        println!("{f}");
    }
    roc_figure(rep, main, "roc.svg", "ROC on scans (verification)")?;
    Ok(())
}

/// Landmark detection on every scan of the run: its errors, `landmarks.csv` and the scans'
/// times.
fn landmark_section(rep: &mut Report, everyone: &[&Face]) -> Result<()> {
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
    let noted: Vec<String> = everyone
        .iter()
        .filter(|f| !f.prepare_notes.is_empty())
        .map(|f| format!("{}: {}", f.name, f.prepare_notes.join("; ")))
        .collect();
    rep.para(&format!(
        "`facematch::prepare` took a substitution on {} of {} scans (each listed; the detected landmarks of these scans were found after it):",
        noted.len(),
        everyone.len()
    ));
    rep.list(&noted);
    println!(
        "prepare notes on {} of {} scans",
        noted.len(),
        everyone.len()
    );
    let time_row = |k: usize| median(everyone.iter().map(|f| f.secs[k]).collect());
    rep.para(&format!(
        "Per scan (median wall time, {} valid samples, {} vertices after cleaning): scan {:.2} s, clean (ground truth's) {:.2} s, `facematch::prepare` (the detected landmarks' cleanings and detections) {:.2} s, the four representations with both landmark sets {:.2} s (faces in parallel on every core, so these are upper bounds of the single-scan times).",
        median(everyone.iter().map(|f| f.valid_samples as f64).collect()),
        median(everyone.iter().map(|f| f.vertices as f64).collect()),
        time_row(0), time_row(1), time_row(2), time_row(3)
    ));
    Ok(())
}

/// Sweeps: rank-1 against each setting, and where each method breaks (tables, figures,
/// `sweeps.csv`).
fn sweeps_section(rep: &mut Report, s: &Setup<'_>, r: &Results) -> Result<()> {
    let Setup {
        identities,
        base,
        sweep_defs,
        sweep_ids,
        ..
    } = *s;
    let (main, sweep_results) = (&r.scored.metrics, &r.sweep_results);
    if sweep_defs.is_empty() {
        return Ok(());
    }
    rep.heading(2, "Sweeps");
    rep.para(&format!(
        "Probes: expression 1 of the first {sweep_ids} identities, rescanned at each value (the other settings those of the gallery), against the whole gallery of {identities}. 'Breaks at' is the first value at which rank-1 is more than 0.1 below its value at the gallery's setting."
    ));
    let mut csv_rows = Vec::new();
    for (sw, per_value) in sweep_defs.iter().zip(sweep_results) {
        let ref_value = match sw.name {
            "noise" => base.noise_mm,
            "pitch" => base.pitch_mm,
            _ => base.yaw_deg,
        };
        let mut hdr = vec![format!("{} ({})", sw.name, sw.unit)];
        let mut series = Vec::new();
        let mut breaks = Vec::new();
        for (j, m0) in per_value[0].iter().enumerate() {
            let label = m0.label();
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
            series.push(m0.series(pts));
        }
        rep.heading(3, &format!("Rank-1 against {}", sw.name));
        let rows: Vec<Vec<String>> = sw
            .values
            .iter()
            .zip(per_value)
            .map(|(v, ms)| {
                let mut r = vec![v.to_string()];
                r.extend(ms.iter().map(|m| format!("{:.3}", m.rank1)));
                csv_rows.push([vec![sw.name.to_string(), v.to_string()], r[1..].to_vec()].concat());
                r
            })
            .collect();
        rep.table(&hdr, &rows);
        let title = format!("Rank-1 against {}", sw.name);
        rep.plot(
            &format!("sweep-{}.svg", sw.name),
            (&title, &format!("{} ({})", sw.name, sw.unit), "rank-1"),
            &series,
            &format!("{title}; dashed: detected landmarks"),
        )?;
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
    hdr.extend(main.iter().map(Metrics::label));
    rep.csv("sweeps.csv", &hdr, &csv_rows)?;
    Ok(())
}
