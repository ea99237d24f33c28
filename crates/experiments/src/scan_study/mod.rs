//! `cargo xtask scan-study`: is the descriptor stable on range scans?
//!
//! The faces of the paper set (ICT, cm) are scanned by `rangescan` under several settings
//! (pitch, depth noise, head pose, 2 mm depth quantisation, seed), cleaned by `scanprep::clean`
//! (crop around the projected nose tip) and described with the experiments' reference points:
//! the scanner's ground-truth landmarks (outer eye corners, nose tip) projected onto the cleaned
//! scan. The face mesh itself, scaled to mm, is one more "scan" (the ICT sampling). Every pair
//! of scans gets four distances: bipolar with rule `All` (the experiments' rule) and with the
//! iso-angle rule, both on the static area at N levels; the single pole (`bipolar::polar`); ICP
//! of static-area points onto the other scan's surface (RMS mm, `shapedist::icp_to_target`).
//! The three pole pairs, their view matching and their reference-point search are `facematch`'s
//! (`describe_with_fields`, `describe_view`, `compare`, `pair_score`). Pairs are *same face*
//! (two scans of one face), *same person* (id1's expressions) or *other person*. The report
//! gives the distributions, the ratio min(other) / max(same face) per method, the fraction of
//! descriptor points with ambiguous keys per setting and the fallbacks of the `facematch`
//! comparisons.
//!
//! Files: `acquisition` (settings, scanning, landmarks), `variants` (the bipolar variants),
//! `description` (a scan's descriptions), `distances` (a pair's distances), `outputs`
//! (tables, report, histograms). Only composes the libraries; deterministic (the scanner's
//! seeds, rayon results collected in input order).

mod acquisition;
mod description;
mod distances;
mod outputs;
#[cfg(test)]
mod tests;
mod variants;

use crate::paths::FaceSetArgs;
use crate::report::{par_map, quantile, sorted};
use acquisition::{settings, Setting};
use anyhow::{bail, Result};
use description::{describe_scan, Described};
use facemodel::{load_face_set, Face};
use meshcore::FaceLocator;
use std::time::Instant;
use variants::{LEAST, VARIANTS};

/// Arguments of `cargo xtask scan-study`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Face set, report folder (default `target/scan-study`) and descriptor resolution (static
    /// area: levels <= N).
    #[command(flatten)]
    pub set: FaceSetArgs,
    /// Only the first `n` scan settings (of the fixed list; 0 = all).
    #[arg(long, default_value_t = 0)]
    pub settings: usize,
    /// ICP probe points per scan (static-area vertices, evenly strided).
    #[arg(long, default_value_t = 200)]
    pub icp_points: usize,
    /// Which pairs of scans are compared: `study` (every pair of two acquisitions of one face,
    /// and every pair within one setting: other persons and id1's expressions are compared
    /// under equal conditions) or `all` (every pair, which for the 8 settings is 4.6k pairs,
    /// five times as many, mostly other persons across settings).
    #[arg(long, default_value = "study", value_parser = ["study", "all"])]
    pub pairs: String,
    /// Only the faces whose name contains one of these strings (comma separated; default all).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Largest distance (mm) between a projected landmark and the cleaned scan surface; farther
    /// landmarks (occluded, in a hole, cropped) make the scan unusable.
    #[arg(long, default_value_t = 2.0)]
    pub landmark_tolerance_mm: f64,
    /// Taubin smoothing iterations of the cleaned scans (`scanprep`; 0: none).
    #[arg(long, default_value_t = 0)]
    pub smooth: usize,
    /// Radius (mm) of the reference-point search of the searched distance: each scan is also
    /// described from the poles of its three pole pairs moved by this much in 6 directions
    /// (`bipolar::SearchedPole`; 0, the default: no search and no searched distance). Measured
    /// in docs/scans.md: it does not raise the separation ratios, and it makes the run several
    /// times longer.
    #[arg(long, default_value_t = 0.0)]
    pub ref_search_mm: f64,
}

/// The `facematch` options of the three-pole-pair distances: the library's defaults with the
/// [`LEAST`] variant's band and incidence limit, the study's levels, the landmark tolerance as
/// the snap distance of a landmark carried onto a view, the reference-point search of
/// `--ref-search-mm` (all three pairs, the library's 6 directions), view matching from each
/// probe's exact direction (no stored turns), the least of the three pairs as the score, no
/// gate.
fn matching(args: &Args) -> facematch::MatchOptions {
    let v = &VARIANTS[LEAST];
    facematch::MatchOptions {
        method: geodesic::Method::Exact,
        levels: args.set.res.levels,
        boundary_margin_mm: v.margin_mm,
        max_incidence_deg: v.max_incidence_deg,
        least_pair: true,
        second_weight: 0.0,
        search: (args.ref_search_mm > 0.0).then(|| facematch::SearchOptions {
            radius_mm: args.ref_search_mm,
            all_pairs: true,
            ..facematch::SearchOptions::default()
        }),
        view: Some(facematch::ViewOptions {
            yaws_deg: Vec::new(),
            ..facematch::ViewOptions::default()
        }),
        snap_mm: args.landmark_tolerance_mm,
        gate_mm: None,
        ..facematch::MatchOptions::default()
    }
}

/// Everything measured on one scan.
struct ScanResult {
    face: usize,
    setting: usize,
    status: Result<Described, String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Relation {
    SameFace,
    SamePerson,
    Other,
}

impl Relation {
    fn name(self) -> &'static str {
        match self {
            Relation::SameFace => "same face",
            Relation::SamePerson => "same person",
            Relation::Other => "other person",
        }
    }
}

/// Two scans compared: indices into the scans, their relation, the distances (in the order of
/// [`distances::methods`]) and the kinds of the fallbacks their `facematch` comparisons took.
struct ScanPair {
    a: usize,
    b: usize,
    rel: Relation,
    d: Vec<f64>,
    fallbacks: Vec<String>,
}

/// Least, median, largest and count of the finite values of `v` (NaN and 0 when none is).
fn quantiles(v: &[f64]) -> (f64, f64, f64, usize) {
    let f = sorted(v.iter().copied().filter(|x| x.is_finite()).collect());
    let [lo, med, hi] = [0.0, 0.5, 1.0].map(|p| quantile(&f, p));
    (lo, med, hi, f.len())
}

/// The faces of the set, kept to those `--only` names.
fn load_faces(args: &Args) -> Result<Vec<Face>> {
    let dir = args.set.faces_dir();
    let mut faces = load_face_set(&dir)?;
    if !args.only.is_empty() {
        faces.retain(|f| args.only.iter().any(|o| f.name.contains(o.as_str())));
        if faces.is_empty() {
            bail!(
                "no face of {} matches --only {:?}",
                dir.display(),
                args.only
            );
        }
    }
    Ok(faces)
}

/// Every face acquired by every setting and described, in input order.
fn describe_all(faces: &[Face], sets: &[Setting], args: &Args) -> Vec<ScanResult> {
    let jobs: Vec<(usize, usize)> = (0..faces.len())
        .flat_map(|f| (0..sets.len()).map(move |s| (f, s)))
        .collect();
    par_map(&jobs, "scan, clean, describe", |&(f, s)| {
        let status = describe_scan(&faces[f], &sets[s], args).map_err(|e| format!("{e:#}"));
        ScanResult {
            face: f,
            setting: s,
            status,
        }
    })
}

/// The pairs of usable scans that `--pairs` asks for, compared.
fn compare_all(faces: &[Face], scans: &[ScanResult], args: &Args) -> Vec<ScanPair> {
    let ok: Vec<(usize, &Described)> = scans
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.status.as_ref().ok().map(|d| (i, d)))
        .collect();
    let locators: Vec<FaceLocator<'_>> =
        ok.iter().map(|(_, d)| FaceLocator::new(&d.mesh)).collect();
    let all_pairs = args.pairs == "all";
    let idx_pairs: Vec<(usize, usize)> = (0..ok.len())
        .flat_map(|a| (a + 1..ok.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| {
            let (x, y) = (&scans[ok[a].0], &scans[ok[b].0]);
            all_pairs || x.face == y.face || x.setting == y.setting
        })
        .collect();
    par_map(&idx_pairs, "distances", |&(a, b)| {
        let (ia, da) = ok[a];
        let (ib, db) = ok[b];
        let (fa, fb) = (&faces[scans[ia].face], &faces[scans[ib].face]);
        let rel = if scans[ia].face == scans[ib].face {
            Relation::SameFace
        } else if fa.person == fb.person {
            Relation::SamePerson
        } else {
            Relation::Other
        };
        let (d, fallbacks) = distances::pair_distances(da, db, &locators[a], &locators[b], args);
        ScanPair {
            a: ia,
            b: ib,
            rel,
            d,
            fallbacks,
        }
    })
}

/// Runs the study; prints the report folder on the last line.
pub fn run(args: Args) -> Result<()> {
    let t0 = Instant::now();
    let faces = load_faces(&args)?;
    let out = args.set.out.out_dir("scan-study");
    std::fs::create_dir_all(&out)?;
    let mut sets = settings();
    if args.settings > 0 {
        // Keep the mesh setting last in any case.
        let mesh = sets.pop();
        sets.truncate(args.settings);
        sets.extend(mesh);
    }
    eprintln!(
        "{} faces x {} settings from {}",
        faces.len(),
        sets.len(),
        args.set.faces_dir().display()
    );
    let scans = describe_all(&faces, &sets, &args);
    eprintln!("scans described in {:.0} s", t0.elapsed().as_secs_f64());
    let t_pairs = Instant::now();
    let pairs = compare_all(&faces, &scans, &args);
    eprintln!(
        "{} pairs compared in {:.0} s",
        pairs.len(),
        t_pairs.elapsed().as_secs_f64()
    );
    let study = outputs::Study {
        args: &args,
        faces: &faces,
        sets: &sets,
        scans: &scans,
        pairs: &pairs,
        out: &out,
    };
    study.write(t0)?;
    println!("{}", out.display());
    Ok(())
}
