//! `bipolar enroll`, `bipolar identify`, `bipolar verify`: face matching (`facematch`).

use anyhow::{bail, Context};
use facematch::{Comparison, Description, Gallery, MatchOptions, ScanInput, Template, ViewUse};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Options every matching command shares.
#[derive(Debug, Clone, clap::Args)]
pub struct MatchArgs {
    /// The direction toward the scanner of mesh inputs, `X,Y,Z` (a `.bnt` grid's is `+z`;
    /// without it `+z` is taken and said).
    #[arg(long, value_parser = parse_dir)]
    pub scanner: Option<meshcore::DVec3>,
    /// Residual gate (mm) of the keyed distance: pairs farther apart after the alignment are
    /// dropped and the fit repeated.
    #[arg(long)]
    pub gate: Option<f64>,
}

fn parse_dir(s: &str) -> Result<meshcore::DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] => Ok(meshcore::DVec3::new(x, y, z)),
        _ => Err(format!("{s}: expected X,Y,Z")),
    }
}

impl MatchArgs {
    fn options(&self) -> MatchOptions {
        MatchOptions {
            gate_mm: self.gate,
            ..MatchOptions::default()
        }
    }
}

/// Arguments of `bipolar enroll`.
#[derive(Debug, clap::Args)]
pub struct EnrollArgs {
    /// Scans (`.bnt` grids or meshes in any format).
    #[arg(required = true)]
    pub scans: Vec<PathBuf>,
    /// The gallery: a folder (one `STEM.bpt` per scan) or a `.bpg` file (all in one).
    #[arg(long)]
    pub out: PathBuf,
    /// A regular expression whose first capture group (or whole match) of the file name is
    /// the identity (default: the file's stem), so that several scans share one identity.
    #[arg(long)]
    pub identity_from: Option<String>,
    #[command(flatten)]
    pub common: MatchArgs,
}

/// Arguments of `bipolar identify`.
#[derive(Debug, clap::Args)]
pub struct IdentifyArgs {
    /// The probe: a scan or a template.
    pub probe: PathBuf,
    /// The gallery (a folder of `.bpt` files or a `.bpg` file from `bipolar enroll`).
    #[arg(long)]
    pub gallery: PathBuf,
    /// Print the best K identities (all by default).
    #[arg(long)]
    pub top: Option<usize>,
    /// JSON: `{probe, ranking: [{identity, template, score, ...}], notes}`.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: MatchArgs,
}

/// Arguments of `bipolar verify`.
#[derive(Debug, clap::Args)]
pub struct VerifyArgs {
    /// The first face (the probe side): a scan or a template.
    pub a: PathBuf,
    /// The second face: a scan or a template.
    pub b: PathBuf,
    /// JSON: `{score, same, threshold, ...}`.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: MatchArgs,
}

fn is_template(p: &Path) -> bool {
    p.extension().is_some_and(|e| e == "bpt")
}

/// The input of a scan file: a `.bnt` grid or a mesh with the given scanner direction.
fn with_input<T>(
    path: &Path,
    scanner: Option<meshcore::DVec3>,
    f: impl FnOnce(ScanInput<'_>) -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bnt"))
    {
        let g = mesh_io::read_bnt_grid(path)
            .with_context(|| format!("cannot load {}", path.display()))?;
        f(ScanInput::Grid(&g))
    } else {
        let m = crate::load::mesh(path)?;
        f(ScanInput::Mesh {
            mesh: &m.mesh,
            units: None,
            scanner,
        })
    }
}

/// The identity of a scan file: its stem, or the capture of `re` in its file name.
fn identity_of(path: &Path, re: Option<&regex::Regex>) -> anyhow::Result<String> {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    let stem = path
        .file_stem()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    match re {
        None => Ok(stem.to_string()),
        Some(re) => {
            let c = re
                .captures(name)
                .with_context(|| format!("--identity-from {re}: no match in {name}"))?;
            Ok(c.get(1)
                .or_else(|| c.get(0))
                .map_or("", |m| m.as_str())
                .to_string())
        }
    }
}

fn template_of(
    path: &Path,
    identity: &str,
    o: &MatchOptions,
    args: &MatchArgs,
    search: bool,
) -> anyhow::Result<Template> {
    let source = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default()
        .to_string();
    with_input(path, args.scanner, |input| {
        let scan = facematch::prepare(input, o).with_context(|| path.display().to_string())?;
        Template::of_scan(&scan, identity, &source, o, search)
            .with_context(|| path.display().to_string())
    })
}

pub fn run_enroll(a: EnrollArgs) -> anyhow::Result<()> {
    let o = a.common.options();
    let re = a
        .identity_from
        .as_deref()
        .map(regex::Regex::new)
        .transpose()
        .context("--identity-from")?;
    let ids: Vec<String> = a
        .scans
        .iter()
        .map(|p| identity_of(p, re.as_ref()))
        .collect::<anyhow::Result<_>>()?;
    let pb = ProgressBar::new(a.scans.len() as u64);
    pb.set_style(
        ProgressStyle::with_template("enrol [{bar:40}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let made: Vec<anyhow::Result<Template>> = a
        .scans
        .par_iter()
        .zip(&ids)
        .map(|(p, id)| {
            let t = template_of(p, id, &o, &a.common, false);
            pb.inc(1);
            t
        })
        .collect();
    pb.finish_and_clear();
    let mut templates = Vec::new();
    let mut failed = Vec::new();
    for (p, t) in a.scans.iter().zip(made) {
        match t {
            Ok(t) => templates.push(t),
            Err(e) => failed.push(format!("{}: {e:#}", p.display())),
        }
    }
    for f in &failed {
        eprintln!("not enrolled: {f}");
    }
    if templates.is_empty() {
        bail!("no scan could be enrolled");
    }
    let notes = templates.iter().filter(|t| !t.notes.is_empty()).count();
    if a.out.extension().is_some_and(|e| e == "bpg") {
        Gallery {
            templates: templates.clone(),
        }
        .write(&a.out)?;
    } else {
        std::fs::create_dir_all(&a.out).with_context(|| a.out.display().to_string())?;
        for t in &templates {
            let stem = Path::new(&t.source)
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scan");
            t.write(&a.out.join(format!("{stem}.bpt")))?;
        }
    }
    println!(
        "enrolled {} of {} scans into {} ({} identities); {} with notes, {} failed",
        templates.len(),
        a.scans.len(),
        a.out.display(),
        {
            let mut s: Vec<&str> = templates.iter().map(|t| t.identity.as_str()).collect();
            s.sort_unstable();
            s.dedup();
            s.len()
        },
        notes,
        failed.len()
    );
    for t in templates.iter().filter(|t| !t.notes.is_empty()) {
        println!("  {}: {}", t.source, t.notes.join("; "));
    }
    if !failed.is_empty() {
        bail!("{} scans not enrolled", failed.len());
    }
    Ok(())
}

/// A probe's description: from a template file, or prepared from a scan with the search.
fn probe_of(
    path: &Path,
    o: &MatchOptions,
    args: &MatchArgs,
) -> anyhow::Result<(Description, Vec<String>)> {
    if is_template(path) {
        let t = Template::read(path)?;
        t.check_settings(o, &path.display().to_string())?;
        return Ok(t.into_probe());
    }
    let t = template_of(path, "probe", o, args, true)?;
    Ok((t.description, t.notes))
}

fn view_json(v: &ViewUse) -> serde_json::Value {
    match v {
        ViewUse::Off => serde_json::json!({"kind": "off"}),
        ViewUse::Own { angle_deg } => serde_json::json!({"kind": "own", "angle_deg": angle_deg}),
        ViewUse::Matched {
            yaw_deg,
            angle_deg,
            off_deg,
        } => {
            serde_json::json!({"kind": "matched", "yaw_deg": yaw_deg, "angle_deg": angle_deg, "off_deg": off_deg})
        }
        ViewUse::Fallback { reason } => serde_json::json!({"kind": "fallback", "reason": reason}),
    }
}

fn num(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

fn comparison_json(c: &Comparison) -> serde_json::Value {
    serde_json::json!({
        "probe_pair": c.probe_pair.name(),
        "scored_by": c.scored_by.map(|p| p.name()),
        "pairs": facematch::Pair::ALL.iter().zip(&c.pairs).map(|(p, u)| serde_json::json!({
            "pair": p.name(), "distance": num(u.distance), "moved": u.moved, "moved_failed": u.moved_failed,
        })).collect::<Vec<_>>(),
        "view": view_json(&c.view),
        "fallbacks": c.fallbacks(),
    })
}

fn used(c: &Comparison) -> String {
    let view = match &c.view {
        ViewUse::Off => "no view matching".to_string(),
        ViewUse::Own { angle_deg } => format!("own view ({angle_deg:.1} deg)"),
        ViewUse::Matched {
            yaw_deg, angle_deg, ..
        } => format!("view {yaw_deg:+} deg (probe at {angle_deg:.1})"),
        ViewUse::Fallback { reason } => format!("own view, fallback: {reason}"),
    };
    let by = c.scored_by.map_or("none", |p| p.name());
    let fb = c.fallbacks();
    let fb = if fb.is_empty() {
        String::new()
    } else {
        format!("; {}", fb.join("; "))
    };
    format!("pair {by}, {view}{fb}")
}

pub fn run_identify(a: IdentifyArgs) -> anyhow::Result<()> {
    let o = a.common.options();
    let gallery = Gallery::open(&a.gallery, &o)?;
    let (probe, notes) = probe_of(&a.probe, &o, &a.common)?;
    let mut ranking = gallery.identify(&probe, &o);
    if let Some(k) = a.top {
        ranking.truncate(k);
    }
    if a.json {
        let j = serde_json::json!({
            "probe": a.probe.display().to_string(),
            "templates": gallery.templates.len(),
            "notes": notes,
            "ranking": ranking.iter().map(|r| serde_json::json!({
                "identity": r.identity, "template": r.template, "score": num(r.score),
                "comparison": comparison_json(&r.comparison),
            })).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&j)?);
        return Ok(());
    }
    for n in &notes {
        println!("note: {n}");
    }
    for (k, r) in ranking.iter().enumerate() {
        println!(
            "{:>3}  {:<24} {:>10.6}  {}  [{}]",
            k + 1,
            r.identity,
            r.score,
            r.template,
            used(&r.comparison)
        );
    }
    Ok(())
}

pub fn run_verify(a: VerifyArgs) -> anyhow::Result<()> {
    let o = a.common.options();
    let (probe, mut notes) = probe_of(&a.a, &o, &a.common)?;
    let other = if is_template(&a.b) {
        let t = Template::read(&a.b)?;
        t.check_settings(&o, &a.b.display().to_string())?;
        t
    } else {
        template_of(&a.b, "b", &o, &a.common, false)?
    };
    notes.extend(other.notes.iter().cloned());
    let c = facematch::compare(&probe, &other, &o);
    let same = c.same_person(&o);
    if a.json {
        let j = serde_json::json!({
            "score": num(c.score), "same": same, "threshold": o.verify_threshold,
            "comparison": comparison_json(&c), "notes": notes,
        });
        println!("{}", serde_json::to_string_pretty(&j)?);
        return Ok(());
    }
    println!("{:.6}", c.score);
    println!(
        "{} (threshold {}; {})",
        if same {
            "same person"
        } else {
            "different persons"
        },
        o.verify_threshold,
        used(&c)
    );
    for n in &notes {
        println!("note: {n}");
    }
    Ok(())
}
