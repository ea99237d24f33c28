//! Times `landmarks::detect_visible` on one mesh as `bipolar landmarks` runs it (default
//! options, units recognised from the face's size, a `.bnt` range grid seen from `+z`), and
//! prints what it found, so that two builds can be compared on the same file.
//!
//! ```text
//! cargo run --release -p landmarks --example detect_time -- SCAN.bnt [RUNS] [--trace]
//! ```
//!
//! Prints the wall time of every run and their median, the CPU time of the whole process over
//! the runs (all threads; `RAYON_NUM_THREADS=1` makes it the solving thread's), then the
//! landmarks with every digit (`{:?}`), their confidences and the weak-evidence reasons. With
//! `--trace` the first run prints the detector's trace with its timings (the split between
//! curvature, candidates, fits and refinement).

use landmarks::{DetectOptions, GenericModel, LandmarkName};
use meshcore::DVec3;
use std::time::Instant;

/// CPU time (user + system) of this process so far, in seconds, from `/proc/self/stat`
/// (`None` where that file is not there).
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which ends with the last ')'): utime and stime are the
    // 14th and 15th fields of the line, the 12th and 13th after the name.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    // The kernel reports clock ticks of 1/100 s on Linux (USER_HZ).
    Some(ticks / 100.0)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let trace = args.iter().any(|a| a == "--trace");
    let plain: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let Some(path) = plain.first() else {
        eprintln!("usage: detect_time MESH [RUNS] [--trace]");
        std::process::exit(2);
    };
    let runs: usize = plain.get(1).map_or(5, |r| r.parse().unwrap_or(5)).max(1);
    let mesh = match mesh_io::read_mesh(path.as_str()) {
        Ok(m) => m.mesh,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    let model = GenericModel::default_model().expect("the shipped model loads");
    let scale = match landmarks::mesh_units_per_model_unit(&mesh, &model) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    let is_grid = path.to_ascii_lowercase().ends_with(".bnt");
    let options = DetectOptions {
        mesh_units_per_model_unit: scale,
        toward_viewer: is_grid.then_some(DVec3::Z),
        ..DetectOptions::default()
    };
    println!(
        "{path}: {} vertices, {} triangles, scale {scale}",
        mesh.n_vertices(),
        mesh.triangles().len()
    );
    let mut times = Vec::with_capacity(runs);
    let mut found = None;
    let cpu0 = process_cpu_seconds();
    for run in 0..runs {
        let opts = DetectOptions {
            trace: trace && run == 0,
            ..options
        };
        let t0 = Instant::now();
        let r = landmarks::detect_visible(&mesh, &model, &opts);
        times.push(t0.elapsed().as_secs_f64());
        found = Some(r);
    }
    let cpu = cpu0.zip(process_cpu_seconds()).map(|(a, b)| b - a);
    let ms: Vec<String> = times.iter().map(|t| format!("{:.1}", t * 1e3)).collect();
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    println!(
        "wall ms per run: {} (median {:.1}); process CPU {} s over {runs} runs",
        ms.join(" "),
        1e3 * sorted[runs / 2],
        cpu.map_or("?".into(), |c| format!("{c:.2}"))
    );
    match found.expect("at least one run") {
        Ok(v) => {
            println!(
                "confidence {:?} fit_rms {:?} inliers {:?} symmetry {:?}",
                v.confidence, v.fit_rms, v.inlier_fraction, v.symmetry
            );
            for n in LandmarkName::ALL {
                match v.get(n) {
                    Ok(l) => println!(
                        "{n}: vertex {} at {:?} confidence {:?}",
                        l.vertex, l.position, l.confidence
                    ),
                    Err(u) => println!("{n}: unseen: {u}"),
                }
                println!("{n} predicted {:?}", v.predicted[n as usize]);
            }
            for w in v.weak_evidence(&options) {
                println!("weak: {w}");
            }
        }
        Err(e) => println!("not found: {e}"),
    }
}
