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

use crate::pipeline::bar;
use crate::report::{f4, Report};
use crate::scans::{sample_weights, scan_seed, ScanSettings};
use anyhow::{Context, Result};
use facematch::{prepare, Comparison, Description, Gallery, MatchOptions, ScanInput, Template};
use facemodel::FaceModel;
use mesh_io::BntGrid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangescan::{Artifacts, HeadPose, Holes, ScanOptions, Spikes};
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

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

/// A scan to make: name, identity, face weights, scanner options.
struct Spec {
    name: String,
    identity: usize,
    identity_weights: Vec<f64>,
    expression_weights: Vec<f64>,
    scan: ScanOptions,
}

/// The scanner options of the tuning set's scans (the scan benchmark's scanner).
fn benchmark_scan(settings: ScanSettings, seed: u64) -> ScanOptions {
    ScanOptions {
        input_mm_per_unit: 10.0,
        pitch_mm: settings.pitch_mm,
        pose: HeadPose {
            yaw_deg: settings.yaw_deg,
            pitch_deg: settings.pitch_deg,
        },
        artifacts: settings.artifacts(),
        seed,
        ..ScanOptions::default()
    }
}

/// The tuning set: gallery specs (neutral, frontal) and probe specs, as the scan benchmark
/// samples them.
fn tuning_specs(model: &FaceModel, a: &Args) -> (Vec<Spec>, Vec<Spec>) {
    let base = ScanSettings {
        pitch_mm: 0.5,
        noise_mm: 0.1,
        quantisation_mm: 0.0,
        spikes: true,
        holes: true,
        yaw_deg: 0.0,
        pitch_deg: 0.0,
    };
    let weights = sample_weights(model, a.identities, a.expressions, a.seed);
    let mut rng = ChaCha8Rng::seed_from_u64(scan_seed(a.seed, u64::MAX));
    let mut n = 0u64;
    let mut spec = |i: usize, e: usize, st: ScanSettings, tag: String| {
        n += 1;
        Spec {
            name: format!("id{i:02}-e{e}{tag}"),
            identity: i,
            identity_weights: weights[i].0.clone(),
            expression_weights: weights[i].1[e].clone(),
            scan: benchmark_scan(st, scan_seed(a.seed, n)),
        }
    };
    let gallery = (0..a.identities)
        .map(|i| spec(i, 0, base, String::new()))
        .collect();
    let mut probes = Vec::new();
    for i in 0..a.identities {
        for e in 1..a.expressions {
            let yaw = rng.random_range(0..=45) as f64 * if rng.random() { 1.0 } else { -1.0 };
            let noise = [0.1, 0.2, 0.4][rng.random_range(0..3)];
            let st = ScanSettings {
                yaw_deg: yaw,
                noise_mm: noise,
                ..base
            };
            probes.push(spec(i, e, st, format!("-yaw{yaw}-noise{noise}")));
        }
    }
    (gallery, probes)
}

/// The held-out set's scanner: settings drawn from `rng` outside the benchmark's.
fn other_scanner(rng: &mut ChaCha8Rng, seed: u64) -> ScanOptions {
    let sl = Artifacts::structured_light();
    let spike_min = rng.random_range(3.0..8.0);
    let hole_min = rng.random_range(1.0..3.0);
    ScanOptions {
        input_mm_per_unit: 10.0,
        pitch_mm: rng.random_range(0.4..=0.8),
        pose: HeadPose {
            yaw_deg: rng.random_range(-20.0..=20.0),
            pitch_deg: rng.random_range(-10.0..=10.0),
        },
        artifacts: Artifacts {
            noise: Some(rangescan::DepthNoise {
                sigma_mm: rng.random_range(0.05..0.3),
            }),
            spikes: Some(Spikes {
                fraction: rng.random_range(0.0005..0.003),
                min_mm: spike_min,
                max_mm: rng.random_range(spike_min..=15.0),
            }),
            holes: Some(Holes {
                count: rng.random_range(2..=8),
                min_radius_mm: hole_min,
                max_radius_mm: rng.random_range(hole_min..=6.0),
            }),
            ..sl
        },
        seed,
        ..ScanOptions::default()
    }
}

/// The held-out set: per person a gallery scan and a probe scan, each from its own draw of the
/// other scanner, the probe with an expression half the time.
fn held_out_specs(model: &FaceModel, a: &Args) -> (Vec<Spec>, Vec<Spec>) {
    let weights = sample_weights(model, a.held_out, 2, a.held_out_seed);
    let mut rng = ChaCha8Rng::seed_from_u64(scan_seed(a.held_out_seed, u64::MAX));
    let mut gallery = Vec::new();
    let mut probes = Vec::new();
    for (i, (w, ex)) in weights.iter().enumerate() {
        for k in 0..2 {
            let seed = scan_seed(a.held_out_seed, (2 * i + k) as u64);
            let expression = if k == 1 && rng.random::<bool>() {
                ex[1].clone()
            } else {
                Vec::new()
            };
            let s = Spec {
                name: format!("p{i:02}-s{k}"),
                identity: i,
                identity_weights: w.clone(),
                expression_weights: expression,
                scan: other_scanner(&mut rng, seed),
            };
            if k == 0 {
                gallery.push(s)
            } else {
                probes.push(s)
            }
        }
    }
    (gallery, probes)
}

/// Scans every spec (in parallel, in order) and writes each grid as `dir/NAME.bnt`.
fn scan_all(model: &FaceModel, specs: &[Spec], dir: &Path, msg: &str) -> Result<Vec<BntGrid>> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    let pb = bar(specs.len(), msg);
    let out = specs
        .par_iter()
        .map(|s| {
            let face = model.sample(&s.identity_weights, &s.expression_weights)?;
            let grid = rangescan::scan(&face, &s.scan)?.grid;
            mesh_io::write_bnt(dir.join(format!("{}.bnt", s.name)), &grid)?;
            pb.inc(1);
            Ok(grid)
        })
        .collect::<Result<Vec<_>>>();
    pb.finish();
    out
}

/// One side of a set through the public API: templates of the gallery (`Err`: why not) and
/// the probes' descriptions with the search.
struct Processed {
    templates: Vec<Result<Template, String>>,
    probes: Vec<Result<Description, String>>,
}

fn process(
    gallery: &[Spec],
    grids_g: &[BntGrid],
    probes: &[Spec],
    grids_p: &[BntGrid],
    o: &MatchOptions,
) -> Processed {
    let pb = bar(gallery.len(), "enrol");
    let templates = gallery
        .par_iter()
        .zip(grids_g)
        .map(|(s, g)| {
            let t = facematch::enroll(
                ScanInput::Grid(g),
                &s.identity.to_string(),
                &format!("{}.bnt", s.name),
                o,
            )
            .map_err(|e| e.to_string());
            pb.inc(1);
            t
        })
        .collect();
    pb.finish();
    let pb = bar(probes.len(), "probes");
    let probes = probes
        .par_iter()
        .zip(grids_p)
        .map(|(_, g)| {
            let d = prepare(ScanInput::Grid(g), o)
                .and_then(|s| s.describe(o, true))
                .map_err(|e| e.to_string());
            pb.inc(1);
            d
        })
        .collect();
    pb.finish();
    Processed { templates, probes }
}

/// Figures of one set at one gate.
#[derive(Debug, Default, Clone)]
struct Figures {
    probes: usize,
    /// Gallery scans that could not be enrolled.
    not_enrolled: usize,
    identified: usize,
    no_score: usize,
    eer: f64,
    /// min(impostor) / max(genuine) over every scored comparison.
    ratio: f64,
    genuine: Vec<f64>,
    impostor: Vec<f64>,
    /// Comparisons with at least one fallback, and the fallbacks by kind.
    with_fallback: usize,
    fallbacks: std::collections::BTreeMap<String, usize>,
    comparisons: usize,
    /// Per comparison: probe, template, same person, score, the pair that scored, the view
    /// used, the fallbacks.
    rows: Vec<Vec<String>>,
}

/// The columns of [`Figures::rows`] (`scores-SET.csv`).
const SCORE_COLUMNS: [&str; 7] = [
    "probe",
    "template",
    "same person",
    "score",
    "scored by",
    "view",
    "fallbacks",
];

/// A view use in a word or two (the kind, and the matched view's turn).
fn view_label(v: &facematch::ViewUse) -> String {
    match v {
        facematch::ViewUse::Off => "off".into(),
        facematch::ViewUse::Own { .. } => "own".into(),
        facematch::ViewUse::Matched { yaw_deg, .. } => format!("view {yaw_deg:+}"),
        facematch::ViewUse::Fallback { .. } => "own (fallback)".into(),
    }
}

/// Equal error rate of genuine (lower is same) and impostor scores.
fn eer(genuine: &[f64], impostor: &[f64]) -> f64 {
    eer_at(genuine, impostor).0
}

/// The equal error rate and the threshold (a score; at or below it: the same person) where it
/// is reached.
fn eer_at(genuine: &[f64], impostor: &[f64]) -> (f64, f64) {
    let mut t: Vec<f64> = genuine.iter().chain(impostor).copied().collect();
    t.sort_by(f64::total_cmp);
    let mut best = (f64::INFINITY, 1.0, f64::NAN);
    for &th in &t {
        let (frr, far) = error_rates(genuine, impostor, th);
        if (frr - far).abs() < best.0 {
            best = ((frr - far).abs(), 0.5 * (frr + far), th);
        }
    }
    (best.1, best.2)
}

/// The share of genuine scores above `th` (same person refused) and of impostor scores at or
/// below it (other person accepted).
fn error_rates(genuine: &[f64], impostor: &[f64], th: f64) -> (f64, f64) {
    let frr = genuine.iter().filter(|&&g| g > th).count() as f64 / genuine.len().max(1) as f64;
    let far = impostor.iter().filter(|&&i| i <= th).count() as f64 / impostor.len().max(1) as f64;
    (frr, far)
}

fn figures(p: &Processed, probes: &[Spec], o: &MatchOptions) -> Figures {
    let templates: Vec<Template> = p.templates.iter().flatten().cloned().collect();
    let gallery = Gallery { templates };
    let mut f = Figures {
        probes: p.probes.len(),
        not_enrolled: p.templates.iter().filter(|t| t.is_err()).count(),
        ..Figures::default()
    };
    for (d, spec) in p.probes.iter().zip(probes) {
        let id = spec.identity;
        let Ok(d) = d else {
            f.no_score += 1;
            continue;
        };
        let cs: Vec<Comparison> = gallery.compare_all(d, o);
        for c in &cs {
            f.comparisons += 1;
            let fb = c.fallbacks();
            if !fb.is_empty() {
                f.with_fallback += 1;
            }
            for k in c.fallback_kinds() {
                *f.fallbacks.entry(k).or_default() += 1;
            }
        }
        // A comparison without a score counts as refused: infinitely far.
        for (t, c) in gallery.templates.iter().zip(&cs) {
            let score = if c.score.is_finite() {
                c.score
            } else {
                f64::INFINITY
            };
            let same = t.identity == id.to_string();
            if same {
                f.genuine.push(score);
            } else {
                f.impostor.push(score);
            }
            f.rows.push(vec![
                spec.name.clone(),
                t.source.clone(),
                same.to_string(),
                f4(c.score),
                c.scored_by.map_or("", |p| p.name()).to_string(),
                view_label(&c.view),
                c.fallback_kinds().join("; "),
            ]);
        }
        let ranking = facematch::rank(&gallery.templates, cs);
        match ranking.first() {
            Some(r) if r.score.is_finite() && r.identity == id.to_string() => f.identified += 1,
            Some(r) if r.score.is_finite() => {}
            _ => f.no_score += 1,
        }
    }
    f.eer = eer(&f.genuine, &f.impostor);
    let max_g = f.genuine.iter().copied().fold(f64::NAN, f64::max);
    let min_i = f.impostor.iter().copied().fold(f64::NAN, f64::min);
    f.ratio = min_i / max_g;
    f
}

fn rank1(f: &Figures) -> f64 {
    f.identified as f64 / f.probes.max(1) as f64
}

fn gate_of(g: f64) -> Option<f64> {
    (g > 0.0).then_some(g)
}

fn gate_label(g: f64) -> String {
    match gate_of(g) {
        Some(g) => format!("{g} mm"),
        None => "none".into(),
    }
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
            "enrolment of one scan ({} valid samples of {} x {}): {} = prepare {} (clean {}, detect {}, crop and clean again {}, detect again {}) + template {} (descriptions and {} views); {} bytes",
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
    let sets = [
        ("tuning", tuning_specs(&model, &a)),
        ("held-out", held_out_specs(&model, &a)),
    ];
    let mut processed = Vec::new();
    for (name, (g, p)) in &sets {
        let dir = out.join("scans").join(name);
        let gg = scan_all(
            &model,
            g,
            &dir.join("gallery"),
            &format!("{name} gallery scans"),
        )?;
        let gp = scan_all(
            &model,
            p,
            &dir.join("probes"),
            &format!("{name} probe scans"),
        )?;
        let pr = process(g, &gg, p, &gp, &o);
        let gdir = out.join("gallery").join(name);
        std::fs::create_dir_all(&gdir)?;
        for (t, s) in pr.templates.iter().zip(g) {
            if let Ok(t) = t {
                t.write(&gdir.join(format!("{}.bpt", s.name)))?;
            }
        }
        processed.push((gg, pr));
    }
    let mut rep = Report::new(&out, "Face matching through the public API (facematch)")?;
    rep.para("Scans made by the virtual scanner and written as .bnt files (scans/), then only the public facematch API, as `bipolar enroll`, `identify` and `verify` use it: no ground truth anywhere, the crop around the detected nose tip. Gallery templates are in gallery/. The gate (residual rule of the keyed distance) is chosen on the tuning set (lowest EER, then highest rank-1); the held-out set's figures at that gate are the reported ones.");
    let mut per_set = Vec::new();
    for ((name, (_, p)), (_, pr)) in sets.iter().zip(&processed) {
        let fs: Vec<(f64, Figures)> = a
            .gates
            .iter()
            .map(|&g| {
                let og = MatchOptions {
                    gate_mm: gate_of(g),
                    ..o.clone()
                };
                (g, figures(pr, p, &og))
            })
            .collect();
        per_set.push((*name, fs));
    }
    let chosen = per_set[0]
        .1
        .iter()
        .min_by(|a, b| {
            a.1.eer
                .total_cmp(&b.1.eer)
                .then(b.1.identified.cmp(&a.1.identified))
        })
        .map(|x| x.0)
        .unwrap_or(0.0);
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
    for (name, fs) in &per_set {
        for (g, f) in fs {
            rows.push(vec![
                name.to_string(),
                gate_label(*g) + if *g == chosen { " (chosen)" } else { "" },
                f.not_enrolled.to_string(),
                f.probes.to_string(),
                f4(rank1(f)),
                f.no_score.to_string(),
                f4(f.eer),
                f4(f.ratio),
                format!("{} of {}", f.with_fallback, f.comparisons),
            ]);
        }
    }
    rep.heading(2, "Identification and verification");
    rep.table(&header, &rows);
    rep.csv("figures.csv", &header, &rows)?;
    for ((name, (g, p)), (_, pr)) in sets.iter().zip(&processed) {
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
    }
    if let Some((_, f)) = per_set[0].1.iter().find(|(g, _)| *g == chosen) {
        let (e, th) = eer_at(&f.genuine, &f.impostor);
        rep.heading(2, "Verification threshold");
        let mut lines = vec![format!(
            "tuning set at the chosen gate: EER {} at score {} (facematch::VERIFY_THRESHOLD is {})",
            f4(e),
            f4(th),
            o.verify_threshold
        )];
        for (name, fs) in &per_set {
            if let Some((_, f)) = fs.iter().find(|(g, _)| *g == chosen) {
                let (frr, far) = error_rates(&f.genuine, &f.impostor, o.verify_threshold);
                lines.push(format!(
                    "{name} at VERIFY_THRESHOLD {}: same person refused {} of {} ({}), other person accepted {} of {} ({})",
                    o.verify_threshold,
                    (frr * f.genuine.len() as f64).round(),
                    f.genuine.len(),
                    f4(frr),
                    (far * f.impostor.len() as f64).round(),
                    f.impostor.len(),
                    f4(far)
                ));
            }
        }
        for l in &lines {
            println!("{l}");
        }
        rep.list(&lines);
    }
    for (name, fs) in &per_set {
        if let Some((_, f)) = fs.iter().find(|(g, _)| *g == chosen) {
            rep.heading(3, &format!("{name}: fallbacks at the chosen gate"));
            let l: Vec<String> = f
                .fallbacks
                .iter()
                .map(|(k, n)| format!("{k}: {n}"))
                .collect();
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
                    ("same person".to_string(), f.genuine.clone()),
                    ("other persons".to_string(), f.impostor.clone()),
                ],
                30,
            )?;
            rep.figure(
                &file,
                &format!("Scores of the {name} set at the chosen gate"),
            );
        }
    }
    // Costs on the tuning set's first gallery scan and first probe.
    let (gg, pr) = &processed[0];
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
        let lines = costs(g, probe, &gallery, a.timing_templates)?;
        for l in &lines {
            println!("{l}");
        }
        rep.list(&lines);
    }
    rep.png_twins()?;
    let path = rep.finish()?;
    for r in &rows {
        println!("{}", r.join(" | "));
    }
    println!("{}", path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eer_of_separated_and_overlapping_scores() {
        assert_eq!(eer(&[0.1, 0.2], &[0.5, 0.6]), 0.0);
        // One genuine above one impostor of two each: one error each side at the best threshold.
        let e = eer(&[0.1, 0.55], &[0.5, 0.6]);
        assert!((e - 0.5).abs() < 1e-12, "{e}");
    }
}
