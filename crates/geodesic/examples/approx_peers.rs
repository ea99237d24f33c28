//! Side-by-side accuracy and timing of the approximate methods, printed as Markdown tables:
//!
//! ```text
//! cargo run --release -p geodesic --example approx_peers -- [peers] [faces]
//! ```
//!
//! * `peers`: the peer sphere meshes. Needs the meshes written by `make_meshes.py` of
//!   `../shared/peers/geodesic` (and, for the "vs exact" and peer columns, the outputs of its
//!   `bench.py`) in the folder named by `GEODESIC_PEERS_DIR` (default `/tmp/peers-geo`); says
//!   so and does nothing when they are absent. `GEODESIC_CASES`, `GEODESIC_METHODS`,
//!   `GEODESIC_REPEAT`, `GEODESIC_PEERS_OUT`, `GEODESIC_BINS` and `GEODESIC_WHERE` choose the
//!   cases, methods, repetitions, peer output folder and the extra error breakdowns.
//! * `faces`: paper-set faces id1 and id2 against the exact solver (needs `../shared`).
//!
//! Without an argument both run.

use geodesic::{
    Dijkstra, FastMarching, FmmUpdate, GeodesicSolver, HeatMethod, SolveOptions, Source, TriMesh,
};
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;
use testsupport::fields::{max_abs_diff, max_rel_err, mean_abs_diff, sphere_geodesic};

/// The solver named `name`: `fmm` (the default rule), `fmm_point`, `fmm_plane`, `fmm_blend`,
/// `fmm_curved`, `heat` or `dijkstra`.
fn solver(mesh: &TriMesh, name: &str) -> Box<dyn GeodesicSolver> {
    let fmm = |rule| FastMarching::with_update(mesh, rule).unwrap();
    match name {
        "fmm" => Box::new(FastMarching::new(mesh).unwrap()),
        "fmm_point" => Box::new(fmm(FmmUpdate::PointSource)),
        "fmm_plane" => Box::new(fmm(FmmUpdate::PlaneWave)),
        "fmm_blend" => Box::new(fmm(FmmUpdate::Blend)),
        "fmm_curved" => Box::new(fmm(FmmUpdate::CurvedFront)),
        "heat" => Box::new(HeatMethod::new(mesh).unwrap()),
        "dijkstra" => Box::new(Dijkstra::new(mesh).unwrap()),
        other => panic!("unknown method {other}"),
    }
}

fn load_txt(path: &Path) -> Option<Vec<f64>> {
    let text = std::fs::read_to_string(path).ok()?;
    Some(text.lines().map(|l| l.trim().parse().unwrap()).collect())
}

struct Err3 {
    mae: f64,
    max: f64,
    rel: f64,
    /// Analytic distance where the max error occurs.
    at: f64,
}

fn errors(d: &[f64], g: &[f64]) -> Err3 {
    let (mut s, mut m, mut r, mut nr, mut at) = (0.0, 0.0f64, 0.0, 0usize, 0.0);
    for (a, b) in d.iter().zip(g) {
        let e = (a - b).abs();
        s += e;
        if e > m {
            m = e;
            at = *b;
        }
        if *b > 0.05 {
            r += e / b;
            nr += 1;
        }
    }
    Err3 {
        mae: s / d.len() as f64,
        max: m,
        rel: r / nr as f64,
        at,
    }
}

/// Latitude and longitude (degrees, about the z axis) of the direction of `p`.
fn lat_lon_deg(p: DVec3) -> (f64, f64) {
    let q = p.normalize();
    (q.z.asin().to_degrees(), q.y.atan2(q.x).to_degrees())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn fmt_t(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.0} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.1} ms", s * 1e3)
    } else {
        format!("{:.2} s", s)
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    for a in &args {
        assert!(
            a == "peers" || a == "faces",
            "unknown part {a:?} (peers or faces)"
        );
    }
    let part = |name: &str| args.is_empty() || args.iter().any(|a| a == name);
    if part("peers") {
        peer_comparison();
    }
    if part("faces") {
        face_comparison_against_exact();
    }
}

/// The table of the peer sphere meshes (see the file header).
fn peer_comparison() {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = PathBuf::from(
        std::env::var("GEODESIC_PEERS_DIR").unwrap_or_else(|_| "/tmp/peers-geo".to_string()),
    );
    if !dir.join("meshes").is_dir() {
        println!("skipping: no peer meshes in {}", dir.display());
        return;
    }
    let cases = std::env::var("GEODESIC_CASES")
        .unwrap_or_else(|_| "ico4:0,ico5:0,ico6:0,ico7:0,uv10k:0,uv10k:4901,jitter5:0".to_string());
    let methods = std::env::var("GEODESIC_METHODS")
        .unwrap_or_else(|_| "fmm,fmm_point,fmm_blend,heat,dijkstra".to_string());
    let repeat: usize = std::env::var("GEODESIC_REPEAT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    println!("| mesh:source | nV | method | setup | solve | total | MAE | max err | mean rel err | max vs exact |");
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    for case in cases.split(',') {
        let (name, src) = case.split_once(':').unwrap();
        let src: u32 = src.parse().unwrap();
        let path = dir.join("meshes").join(format!("{name}.obj"));
        if !path.exists() {
            println!("| {case} | missing mesh |");
            continue;
        }
        let mesh = testsupport::read_mesh(&path);
        let g = sphere_geodesic(&mesh, mesh.position(src), 1.0);
        let out = dir.join(std::env::var("GEODESIC_PEERS_OUT").unwrap_or_else(|_| "out".into()));
        let exact = load_txt(&out.join(format!("{name}_s{src}_exact_gdist.txt")));
        let vs_exact = |d: &[f64]| exact.as_ref().map_or(f64::NAN, |x| max_abs_diff(d, x));
        for peer in ["fmm_pp3d", "heat_igl"] {
            if let Some(d) = load_txt(&out.join(format!("{name}_s{src}_{peer}.txt"))) {
                let e = errors(&d, &g);
                println!(
                    "| {case} | {} | {peer} (peer, errors only) | | | | {:.2e} | {:.2e} | {:.2e} | {:.1e} |",
                    g.len(),
                    e.mae,
                    e.max,
                    e.rel,
                    vs_exact(&d)
                );
            }
        }
        for m in methods.split(',') {
            let (mut setups, mut solves) = (Vec::new(), Vec::new());
            let mut d = Vec::new();
            for _ in 0..repeat {
                let t0 = Instant::now();
                let solver = solver(&mesh, m);
                let t1 = Instant::now();
                d = solver
                    .distances(&[Source::Vertex(src)], &SolveOptions::default())
                    .unwrap();
                let t2 = Instant::now();
                setups.push((t1 - t0).as_secs_f64());
                solves.push((t2 - t1).as_secs_f64());
            }
            let (su, so) = (median(setups), median(solves));
            let e = errors(&d, &g);
            if std::env::var("GEODESIC_BINS").is_ok() {
                let mut bins = vec![(0.0f64, 0.0f64, 0usize, 0.0f64); 16];
                let ex = exact.as_ref().unwrap();
                for ((a, b), x) in d.iter().zip(&g).zip(ex) {
                    let k = ((b / std::f64::consts::PI * 16.0) as usize).min(15);
                    bins[k].0 += a - b;
                    bins[k].1 += a - x;
                    bins[k].2 += 1;
                    bins[k].3 = bins[k].3.max((a - x).abs());
                }
                for (k, bn) in bins.iter().enumerate() {
                    println!(
                        "  bin {k:2}: mean signed err vs sphere {:+.2e}, vs exact {:+.2e}, max |vs exact| {:.2e}",
                        bn.0 / bn.2 as f64,
                        bn.1 / bn.2 as f64,
                        bn.3
                    );
                }
            }
            if std::env::var("GEODESIC_WHERE").is_ok() {
                println!("max error of {m} at analytic distance {:.3}", e.at);
                // The worst vertices: latitude / longitude (degrees, about the z axis), analytic
                // distance, signed error against the sphere and against the exact polyhedral
                // distance.
                let mut idx: Vec<usize> = (0..d.len()).collect();
                idx.sort_by(|&i, &j| (d[j] - g[j]).abs().total_cmp(&(d[i] - g[i]).abs()));
                for &i in idx.iter().take(8) {
                    let (lat, lon) = lat_lon_deg(mesh.position(i as u32));
                    println!(
                        "  v{i}: lat {lat:+.1} lon {lon:+.1} dist {:.4} err {:+.2e} vs exact {:+.2e}",
                        g[i],
                        d[i] - g[i],
                        exact.as_ref().map(|x| d[i] - x[i]).unwrap_or(f64::NAN)
                    );
                }
            }
            println!(
                "| {case} | {} | {m} (ours) | {} | {} | {} | {:.2e} | {:.2e} | {:.2e} | {:.1e} |",
                g.len(),
                fmt_t(su),
                fmt_t(so),
                fmt_t(su + so),
                e.mae,
                e.max,
                e.rel,
                vs_exact(&d)
            );
        }
    }
}

/// The table of paper-set faces id1 and id2 against the exact solver from vertex 3721.
fn face_comparison_against_exact() {
    faer::set_global_parallelism(faer::Par::Seq);
    let Some(dir) = testsupport::shared_path(testsupport::PAPER_SET) else {
        return;
    };
    println!(
        "| face | method | setup | solve | MAE vs exact | max vs exact | max rel (d > 1 cm) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for face in ["id1_neutral", "id2_neutral"] {
        let mesh = testsupport::read_mesh(dir.join(format!("{face}.obj")));
        let src = [Source::Vertex(3721)];
        let exact = geodesic::ExactGeodesic::new(&mesh)
            .unwrap()
            .distances(&src, &SolveOptions::default())
            .unwrap();
        for m in ["fmm", "fmm_point", "fmm_blend", "heat", "dijkstra"] {
            let t0 = Instant::now();
            let solver = solver(&mesh, m);
            let t1 = Instant::now();
            let d = solver.distances(&src, &SolveOptions::default()).unwrap();
            let t2 = Instant::now();
            let n_inf = d.iter().filter(|x| !x.is_finite()).count();
            let n_inf_exact = exact.iter().filter(|x| !x.is_finite()).count();
            if n_inf + n_inf_exact > 0 {
                println!("{m}: {n_inf} non-finite values (exact: {n_inf_exact})");
            }

            println!(
                "| {face} | {m} | {} | {} | {:.2e} | {:.2e} | {:.2e} |",
                fmt_t((t1 - t0).as_secs_f64()),
                fmt_t((t2 - t1).as_secs_f64()),
                mean_abs_diff(&d, &exact),
                max_abs_diff(&d, &exact),
                max_rel_err(&d, &exact, 1.0)
            );
        }
    }
}
