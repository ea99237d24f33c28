//! `cargo xtask match-eval`: face matching measured on the path a user takes. Scans are made
//! by the virtual scanner and written as `.bnt` files; everything after that goes through the
//! public `facematch` API only ([`facematch::enroll`], [`facematch::prepare`],
//! [`facematch::Gallery::identify`], [`facematch::compare`]), as `bipolar enroll`, `identify`
//! and `verify` do: no ground truth (the crop is around the detected nose tip), every fallback
//! counted.
//!
//! Two sets, sampled from two seed streams:
//!
//! * the **tuning** set: the scan benchmark's protocol (a neutral frontal gallery scan per
//!   identity; probes with other expressions, yaw up to 45 degrees either way, noise 0.1, 0.2
//!   or 0.4 mm). The residual rule of the keyed distance (the gate) is chosen on it: the gate
//!   with the lowest equal error rate (ties: the higher rank-1);
//! * the **held-out** set: another scanner (pitch 0.4-0.8 mm, spikes 3-15 mm, 2-8 holes of 1-6
//!   mm anywhere, yaw up to 20 and pitch up to 10 degrees), two scans of each person (one
//!   enrolled, one probe). Its figures, at the gate chosen on the tuning set, are the reported
//!   ones: rank-1 and `min(other persons) / max(same person)` of the verify score.
//!
//! Also the costs: enrolment of one scan (split by step), one probe against 1,000 templates,
//! template size.

use crate::report::{f4, Report};
use anyhow::{Context, Result};
use facematch::metrics::{eer, error_rates};
use facematch::{prepare, Description, Gallery, MatchOptions, ScanInput, Template};
use facemodel::FaceModel;
use figures::{figures, gate_label, gate_of, Figures, SCORE_COLUMNS};
use mesh_io::BntGrid;
use sets::{held_out_specs, process, scan_all, tuning_specs, Processed, Spec};
use std::path::Path;
use std::time::Instant;

mod figures;
mod sets;

/// `cargo xtask match-eval` options.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// The ICT model (`--model`).
    #[command(flatten)]
    pub io: crate::paths::ModelArgs,
    /// Identities of the tuning set.
    #[arg(long, default_value_t = 16)]
    pub identities: usize,
    /// Expressions per identity of the tuning set (the first, neutral, is the gallery's).
    #[arg(long, default_value_t = 3)]
    pub expressions: usize,
    /// Seed of the tuning set.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Persons of the held-out set.
    #[arg(long, default_value_t = 12)]
    pub held_out: usize,
    /// Seed of the held-out set.
    #[arg(long, default_value_t = 1001)]
    pub held_out_seed: u64,
    /// Residual gates tried (mm; 0: no gate), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0,5,10,15,20")]
    pub gates: Vec<f64>,
    /// Templates of the identification timing (the gallery's, repeated).
    #[arg(long, default_value_t = 1000)]
    pub timing_templates: usize,
}

/// A set's name with its gallery and probe specs.
type Set = (&'static str, (Vec<Spec>, Vec<Spec>));

/// The figures of one set at every gate tried.
type PerSet = (&'static str, Vec<(f64, Figures)>);

/// Runs the evaluation; prints the report's path on the last line.
pub fn run(a: Args) -> Result<()> {
    if a.identities < 2 || a.expressions < 2 || a.held_out < 2 {
        anyhow::bail!("need at least 2 identities, 2 expressions and 2 held-out persons");
    }
    if a.gates.iter().any(|g| !(g.is_finite() && *g >= 0.0)) || a.gates.is_empty() {
        anyhow::bail!("--gates {:?}: non-negative numbers (0: no gate)", a.gates);
    }
    let model_dir = a.io.model_dir();
    let model = FaceModel::load(&model_dir)
        .with_context(|| format!("loading the ICT model from {}", model_dir.display()))?;
    let out = a.io.out.out_dir("match-eval");
    let o = MatchOptions::default();
    let sets: [Set; 2] = [
        ("tuning", tuning_specs(&model, &a)),
        ("held-out", held_out_specs(&model, &a)),
    ];
    let mut processed = Vec::new();
    for (name, (g, p)) in &sets {
        processed.push(scan_and_process(&model, &out, name, g, p, &o)?);
    }
    let mut rep = Report::new(&out, "Face matching through the public API (facematch)")?;
    rep.para("Scans made by the virtual scanner and written as .bnt files (scans/), then only the public facematch API, as `bipolar enroll`, `identify` and `verify` use it: no ground truth anywhere, the crop around the detected nose tip. Gallery templates are in gallery/. The gate (residual rule of the keyed distance) is chosen on the tuning set (lowest EER, then highest rank-1); the held-out set's figures at that gate are the reported ones.");
    let per_set: Vec<PerSet> = sets
        .iter()
        .zip(&processed)
        .map(|((name, (_, p)), (_, pr))| (*name, at_every_gate(&a.gates, pr, p, &o)))
        .collect();
    let chosen = per_set[0]
        .1
        .iter()
        .min_by(|a, b| {
            (a.1.eval.eer)
                .total_cmp(&b.1.eval.eer)
                .then(b.1.eval.identified.cmp(&a.1.eval.identified))
        })
        .map(|x| x.0)
        .unwrap_or(0.0);
    let rows = figures_section(&mut rep, &per_set, chosen)?;
    unusable_section(&mut rep, &sets, &processed);
    threshold_section(&mut rep, &per_set, chosen, &o);
    fallbacks_section(&mut rep, &per_set, chosen)?;
    costs_section(&mut rep, &processed[0], a.timing_templates)?;
    rep.png_twins()?;
    let path = rep.finish()?;
    for r in &rows {
        println!("{}", r.join(" | "));
    }
    println!("{}", path.display());
    Ok(())
}

/// Scans one set into `out/scans/NAME/{gallery,probes}`, passes it through the public API
/// and writes the gallery templates into `out/gallery/NAME`; returns the gallery grids and
/// what the API made of the set.
fn scan_and_process(
    model: &FaceModel,
    out: &Path,
    name: &str,
    g: &[Spec],
    p: &[Spec],
    o: &MatchOptions,
) -> Result<(Vec<BntGrid>, Processed)> {
    let dir = out.join("scans").join(name);
    let gg = scan_all(
        model,
        g,
        &dir.join("gallery"),
        &format!("{name} gallery scans"),
    )?;
    let gp = scan_all(
        model,
        p,
        &dir.join("probes"),
        &format!("{name} probe scans"),
    )?;
    let pr = process(g, &gg, &gp, o);
    let gdir = out.join("gallery").join(name);
    std::fs::create_dir_all(&gdir)?;
    for (t, s) in pr.templates.iter().zip(g) {
        if let Ok(t) = t {
            t.write(&gdir.join(format!("{}.bpt", s.name)))?;
        }
    }
    Ok((gg, pr))
}

/// The figures of one processed set at each of `gates`.
fn at_every_gate(
    gates: &[f64],
    pr: &Processed,
    probes: &[Spec],
    o: &MatchOptions,
) -> Vec<(f64, Figures)> {
    gates
        .iter()
        .map(|&g| {
            let og = MatchOptions {
                gate_mm: gate_of(g),
                ..o.clone()
            };
            (g, figures(pr, probes, &og))
        })
        .collect()
}

/// The figures of every set at every gate (`chosen` marked) as a table and `figures.csv`;
/// returns the rows.
fn figures_section(rep: &mut Report, per_set: &[PerSet], chosen: f64) -> Result<Vec<Vec<String>>> {
    let header = [
        "set",
        "gate",
        "gallery scans not enrolled",
        "probes",
        "rank-1",
        "no score",
        "EER",
        "min other / max same",
        "comparisons with a fallback",
    ];
    let mut rows = Vec::new();
    for (name, fs) in per_set {
        for (g, f) in fs {
            rows.push(vec![
                name.to_string(),
                gate_label(*g) + if *g == chosen { " (chosen)" } else { "" },
                f.not_enrolled.to_string(),
                f.eval.probes.to_string(),
                f4(f.eval.rank1()),
                f.eval.no_score.to_string(),
                f4(f.eval.eer),
                f4(f.eval.ratio),
                format!(
                    "{} of {}",
                    f.eval.fallbacks.with_fallback, f.eval.fallbacks.comparisons
                ),
            ]);
        }
    }
    rep.heading(2, "Identification and verification");
    rep.table_csv("figures.csv", &header, &rows)?;
    Ok(rows)
}

/// Per set, the scans that could not be enrolled or described, with why.
fn unusable_section(rep: &mut Report, sets: &[Set], processed: &[(Vec<BntGrid>, Processed)]) {
    for ((name, (g, p)), (_, pr)) in sets.iter().zip(processed) {
        let named = |s: &Spec, r: Option<&String>| r.map(|e| format!("{}: {e}", s.name));
        let failed: Vec<String> = g
            .iter()
            .zip(&pr.templates)
            .filter_map(|(s, t)| named(s, t.as_ref().err()))
            .chain(
                p.iter()
                    .zip(&pr.probes)
                    .filter_map(|(s, d)| named(s, d.as_ref().err())),
            )
            .collect();
        rep.heading(3, &format!("{name}: scans that could not be used"));
        if failed.is_empty() {
            rep.para("none");
        } else {
            rep.list(&failed);
        }
        // What preparation substituted on the scans that were used (the notes of their
        // templates and probes).
        let noted: Vec<String> = g
            .iter()
            .zip(&pr.templates)
            .filter_map(|(s, t)| Some((s, &t.as_ref().ok()?.notes)))
            .chain(p.iter().zip(&pr.probe_notes))
            .filter(|(_, n)| !n.is_empty())
            .map(|(s, n)| format!("{}: {}", s.name, n.join("; ")))
            .collect();
        rep.heading(3, &format!("{name}: what preparation substituted"));
        rep.para(&format!(
            "{} of {} scans (the template's or the probe's notes):",
            noted.len(),
            g.len() + p.len()
        ));
        rep.list(&noted);
        println!("{name}: preparation substituted on {} scans", noted.len());
    }
}

/// The tuning set's EER threshold at the chosen gate, and each set's error rates at
/// `facematch::VERIFY_THRESHOLD` (also printed).
fn threshold_section(rep: &mut Report, per_set: &[PerSet], chosen: f64, o: &MatchOptions) {
    let Some((_, f)) = per_set[0].1.iter().find(|(g, _)| *g == chosen) else {
        return;
    };
    let e = eer(&f.eval.genuine, &f.eval.impostor);
    rep.heading(2, "Verification threshold");
    let mut lines = vec![format!(
        "tuning set at the chosen gate: EER {} at score {} (facematch::VERIFY_THRESHOLD is {})",
        f4(e.rate),
        f4(e.threshold),
        o.verify_threshold
    )];
    for (name, fs) in per_set {
        if let Some((_, f)) = fs.iter().find(|(g, _)| *g == chosen) {
            let (g, i) = (&f.eval.genuine, &f.eval.impostor);
            let (frr, far) = error_rates(g, i, o.verify_threshold);
            lines.push(format!(
                "{name} at VERIFY_THRESHOLD {}: same person refused {} of {} ({}), other person accepted {} of {} ({})",
                o.verify_threshold,
                (frr * g.len() as f64).round(),
                g.len(),
                f4(frr),
                (far * i.len() as f64).round(),
                i.len(),
                f4(far)
            ));
        }
    }
    for l in &lines {
        println!("{l}");
    }
    rep.list(&lines);
}

/// Per set at the chosen gate: the fallbacks by kind, `scores-SET.csv` and the score
/// histogram.
fn fallbacks_section(rep: &mut Report, per_set: &[PerSet], chosen: f64) -> Result<()> {
    for (name, fs) in per_set {
        let Some((_, f)) = fs.iter().find(|(g, _)| *g == chosen) else {
            continue;
        };
        rep.heading(3, &format!("{name}: fallbacks at the chosen gate"));
        let l = f.eval.fallbacks.kinds();
        if l.is_empty() {
            rep.para("none");
        } else {
            rep.list(&l);
        }
        rep.csv(&format!("scores-{name}.csv"), &SCORE_COLUMNS, &f.rows)?;
        let file = format!("scores-{name}.svg");
        viz::histogram(
            rep.path(&file),
            &format!("{name} set, gate {}", gate_label(chosen)),
            "score",
            &[
                ("same person".to_string(), f.eval.genuine.clone()),
                ("other persons".to_string(), f.eval.impostor.clone()),
            ],
            30,
        )?;
        rep.figure(
            &file,
            &format!("Scores of the {name} set at the chosen gate"),
        );
    }
    Ok(())
}

/// The costs on the tuning set's first gallery scan and first probe (also printed).
fn costs_section(
    rep: &mut Report,
    (gg, pr): &(Vec<BntGrid>, Processed),
    timing_templates: usize,
) -> Result<()> {
    let gallery: Vec<Template> = pr.templates.iter().flatten().cloned().collect();
    if let (Some(g), Some(Ok(probe)), false) = (gg.first(), pr.probes.first(), gallery.is_empty()) {
        let profile = if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        };
        rep.heading(
            2,
            &format!("Costs ({profile} build, this machine, both cores)"),
        );
        let lines = costs(g, probe, &gallery, timing_templates)?;
        for l in &lines {
            println!("{l}");
        }
        rep.list(&lines);
    }
    Ok(())
}

/// The costs: one enrolment split by step, one probe against `n` templates, template sizes.
fn costs(g: &BntGrid, probe: &Description, gallery: &[Template], n: usize) -> Result<Vec<String>> {
    let o = MatchOptions::default();
    let valid = (0..g.xyz.len()).filter(|&i| g.is_valid(i)).count();
    let t0 = Instant::now();
    let scan = prepare(ScanInput::Grid(g), &o)?;
    let t1 = Instant::now();
    let t = Template::of_scan(&scan, "x", "x.bnt", &o, false)?;
    let t2 = Instant::now();
    let many = Gallery {
        templates: gallery.iter().cycle().take(n).cloned().collect(),
    };
    let t3 = Instant::now();
    let ranking = many.identify(probe, &o);
    let t4 = Instant::now();
    let sizes: Vec<usize> = gallery.iter().map(|t| t.to_bytes().len()).collect();
    let ms = |d: std::time::Duration| format!("{:.0} ms", 1e3 * d.as_secs_f64());
    let st = scan.times;
    Ok(vec![
        format!(
            "enrolment of one scan ({} valid samples of {} x {}): {} = prepare {} (clean {}, detect {}, the crop finishing the cleaning {}, detect again {}) + template {} (descriptions and {} views); {} bytes",
            valid,
            g.ncols,
            g.nrows,
            ms(t2 - t0),
            ms(t1 - t0),
            ms(st.clean),
            ms(st.detect),
            ms(st.crop_clean),
            ms(st.crop_detect),
            ms(t2 - t1),
            t.views.len(),
            t.to_bytes().len()
        ),
        format!(
            "one probe (its {} moved descriptors) against {} templates: {} ({} identities ranked)",
            probe.moved.iter().map(Vec::len).sum::<usize>(),
            many.templates.len(),
            ms(t4 - t3),
            ranking.len()
        ),
        format!(
            "template size: mean {:.0} kB, max {:.0} kB over {} templates",
            sizes.iter().sum::<usize>() as f64 / sizes.len().max(1) as f64 / 1e3,
            sizes.iter().copied().max().unwrap_or(0) as f64 / 1e3,
            sizes.len()
        ),
    ])
}
