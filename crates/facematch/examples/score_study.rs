//! The distances behind a choice of scoring rule: every probe of a `cargo xtask match-eval`
//! output against every template of both its sets (tuning and held-out), with the score as
//! `facematch::compare` gives it, the reverse comparison (the template as a probe against the
//! probe's template), the angles to the template's own and turned scanner directions, and the
//! distance by each pair for the template's own description and for each of its views.
//!
//! `cargo run --release -p facematch --example score_study -- MATCH_EVAL_DIR OUT_DIR
//! [--no-probe-views]` writes `OUT_DIR/pairs.csv` (the probes' templates, with the
//! reference-point search and views, are kept in `OUT_DIR/probes-SET/`); `score_study.py`
//! beside this file simulates rules on it (docs/matching.md). The templates must have been
//! made with the default options and the turns 15, 25, 35 and 45 degrees.

use facematch::{compare, Gallery, MatchOptions, ScanInput, Template};
use landmarks::GenericModel;
use meshcore::DVec3;
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;

/// The template's turned views, by column label and turn (degrees).
const TURNS: [(&str, f64); 8] = [
    ("m15", -15.0),
    ("p15", 15.0),
    ("m25", -25.0),
    ("p25", 25.0),
    ("m35", -35.0),
    ("p35", 35.0),
    ("m45", -45.0),
    ("p45", 45.0),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: score_study MATCH_EVAL_DIR OUT_DIR [--no-probe-views]";
    let me = std::path::PathBuf::from(args.next().ok_or(usage)?);
    let out = std::path::PathBuf::from(args.next().ok_or(usage)?);
    std::fs::create_dir_all(&out)?;
    // The turns the study compares (the default ones).
    let mut options = MatchOptions::default();
    if let Some(v) = &mut options.view {
        v.yaws_deg = TURNS.iter().map(|t| t.1).filter(|y| *y > 0.0).collect();
    }
    // `--no-probe-views`: the probes' templates without views (no reverse comparison).
    let probe_views = args.next().as_deref() != Some("--no-probe-views");
    let mut probe_options = options.clone();
    if !probe_views {
        probe_options.view = None;
    }
    let generic = GenericModel::default_model()?;
    let mut csv = std::fs::File::create(out.join("pairs.csv"))?;
    write!(
        csv,
        "set,gallery,probe,template,score,view,rev_score,angle_own"
    )?;
    for (v, _) in TURNS {
        write!(csv, ",off_{v}")?;
    }
    for v in std::iter::once("own").chain(TURNS.map(|t| t.0)) {
        for p in ["c", "r", "l"] {
            write!(csv, ",{v}_{p}")?;
        }
    }
    writeln!(csv)?;
    let galleries =
        ["tuning", "held-out"].map(|g| Gallery::open(&me.join("gallery").join(g), &options));
    for set in ["tuning", "held-out"] {
        let dir = me.join("scans").join(set).join("probes");
        let mut files: Vec<_> = std::fs::read_dir(&dir)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        files.sort();
        let cache = out.join(format!("probes-{set}"));
        std::fs::create_dir_all(&cache)?;
        let probes: Vec<Option<Template>> = files
            .iter()
            .map(|f| probe_template(f, &cache, &generic, &probe_options))
            .collect();
        for (f, p) in files.iter().zip(&probes) {
            let Some(p) = p else { continue };
            let name = f.file_stem().unwrap().to_string_lossy().to_string();
            for (g, gallery) in ["tuning", "held-out"].iter().zip(&galleries) {
                let gallery = gallery.as_ref().map_err(|e| e.to_string())?;
                let rows: Vec<String> = gallery
                    .templates
                    .par_iter()
                    .map(|t| row(&format!("{set},{g}"), &name, p, t, &options))
                    .collect();
                for r in rows {
                    writeln!(csv, "{r}")?;
                }
            }
        }
    }
    Ok(())
}

fn probe_template(
    f: &Path,
    cache: &Path,
    generic: &GenericModel,
    options: &MatchOptions,
) -> Option<Template> {
    let stem = f.file_stem()?.to_string_lossy().to_string();
    let c = cache.join(format!("{stem}.bpt"));
    if let Ok(t) = Template::read(&c) {
        return Some(t);
    }
    let grid = mesh_io::read_bnt_grid(f).ok()?;
    let scan = facematch::prepare_with(ScanInput::Grid(&grid), generic, options).ok()?;
    let t = Template::of_scan(&scan, &stem, &stem, options, true).ok()?;
    t.write(&c).ok()?;
    eprintln!("prepared {stem}");
    Some(t)
}

fn row(set: &str, probe: &str, p: &Template, t: &Template, o: &MatchOptions) -> String {
    let c = compare(&p.description, t, o);
    // Reverse: the template as a probe (no moved descriptors) against the probe's template.
    let rev = if p.views.is_empty() {
        f64::NAN
    } else {
        compare(&t.description, p, o).score
    };
    let mut s = format!(
        "{set},{probe},{},{},{},{}",
        t.source,
        c.score,
        c.view.label(),
        rev
    );
    let toward = facematch::probe_direction(
        &p.description.landmarks,
        p.description.scanner,
        &t.description.landmarks,
    );
    let ang = |d: DVec3| toward.map_or(f64::NAN, |w| w.angle_between(d).to_degrees());
    s.push_str(&format!(",{}", ang(t.description.scanner)));
    let view = |yaw: f64| t.views.iter().find(|v| v.yaw_deg == yaw);
    for (_, yaw) in TURNS {
        s.push_str(&format!(
            ",{}",
            view(yaw).map_or(f64::NAN, |v| ang(v.toward))
        ));
    }
    let mut plain = o.clone();
    plain.view = None;
    let mut own = t.clone();
    own.views.clear();
    let d = compare(&p.description, &own, &plain);
    for u in d.pairs {
        s.push_str(&format!(",{}", u.distance));
    }
    for (_, yaw) in TURNS {
        match view(yaw).map(|v| &v.sets) {
            Some(Ok(sets)) => {
                let mut tv = own.clone();
                tv.description.sets = sets.clone();
                let d = compare(&p.description, &tv, &plain);
                for u in d.pairs {
                    s.push_str(&format!(",{}", u.distance));
                }
            }
            _ => s.push_str(",NaN,NaN,NaN"),
        }
    }
    s
}
