//! Side-by-side figures on the ICP peers' point sets (`make_clouds.py` output, `.npy`).
//!
//! ```text
//! python make_clouds.py --resample --out /tmp/clouds
//! cargo run --release -p shapedist --example icp_compare -- /tmp/clouds [N] [degs] [variant] [plain|once]
//! ```
//! Prints one line per method: wall time and CPU time (medians of 5), iterations, rotation
//! error against the ground truth, NN-RMSE (source -> target) and correspondence RMSE, as
//! `icp_peer.py` does. `plain`: only the fixed 50-iteration point-to-point row; `once`: that
//! row run once without the brute-force checks (for profilers). Run with
//! `RAYON_NUM_THREADS=1` for single-threaded figures.

use std::time::Instant;

use shapedist::glam::{DAffine3, DMat3, DVec3};
use shapedist::*;

fn read_npy(path: &str) -> Vec<DVec3> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    assert_eq!(&bytes[..6], b"\x93NUMPY", "{path}: not a .npy file");
    let (hlen, start) = if bytes[6] == 1 {
        (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10)
    } else {
        (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        )
    };
    let header = std::str::from_utf8(&bytes[start..start + hlen]).unwrap();
    assert!(
        header.contains("'<f8'") && header.contains("'fortran_order': False"),
        "{header}"
    );
    let data = &bytes[start + hlen..];
    data.chunks_exact(24)
        .map(|c| {
            let f = |i: usize| f64::from_le_bytes(c[i * 8..i * 8 + 8].try_into().unwrap());
            DVec3::new(f(0), f(1), f(2))
        })
        .collect()
}

fn read_gt(path: &str) -> DMat3 {
    let s = std::fs::read_to_string(path).unwrap();
    let v: Vec<f64> = s
        .split("\"R\"")
        .nth(1)
        .unwrap()
        .split(']')
        .take(3)
        .flat_map(|row| {
            row.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
                .filter(|t| !t.is_empty() && *t != "-")
                .map(|t| t.parse::<f64>().unwrap())
                .collect::<Vec<_>>()
        })
        .collect();
    // rows -> column-major
    DMat3::from_cols_array(&[v[0], v[3], v[6], v[1], v[4], v[7], v[2], v[5], v[8]])
}

/// CPU time of the whole process (all threads) in ms, from the scheduler's per-thread
/// run-time counters (`/proc/self/task/*/schedstat`, nanoseconds); `None` off Linux.
fn cpu_ms() -> Option<f64> {
    let mut ns = 0u64;
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let s = std::fs::read_to_string(e.ok()?.path().join("schedstat")).ok()?;
        ns += s.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-6)
}

thread_local! {
    /// Median CPU time of the last [`median_ms`] call.
    static LAST_CPU: std::cell::Cell<f64> = const { std::cell::Cell::new(f64::NAN) };
}

fn median_ms<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::new();
    let mut cpu = Vec::new();
    let mut out = None;
    for _ in 0..reps {
        let c0 = cpu_ms();
        let t0 = Instant::now();
        out = Some(f());
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        if let (Some(c0), Some(c1)) = (c0, cpu_ms()) {
            cpu.push(c1 - c0);
        }
    }
    times.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    LAST_CPU.with(|c| c.set(cpu.get(reps / 2).copied().unwrap_or(f64::NAN)));
    (times[reps / 2], out.unwrap())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).map_or("/tmp/dist-icp/clouds", String::as_str);
    let n: usize = args.get(2).map_or(10000, |s| s.parse().unwrap());
    let degs: Vec<u32> = args
        .get(3)
        .map_or("30,90,180".into(), String::clone)
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let variant = args.get(4).map_or("tgt", String::as_str);
    // "plain": only the fixed 50-iteration point-to-point row (the like-for-like one).
    let only_plain = args.get(5).is_some_and(|s| s == "plain" || s == "once");
    // "once": one run of the plain row, no brute-force check (for profilers).
    let once = args.get(5).is_some_and(|s| s == "once");
    // `REPS=N` in the environment: medians of N calls instead of 5 (noisy machines).
    let reps = if once {
        1
    } else {
        std::env::var("REPS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(5)
    };
    println!("| N | rot | set | method | ms (median of {reps}) | CPU ms (median) | iters | rot err (deg) | NN-RMSE | corr-RMSE |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for deg in degs {
        let stem = format!("{dir}/patch_N{n}_rot{deg}");
        let src = read_npy(&format!("{stem}_src.npy"));
        let tgt = read_npy(&format!("{stem}_{variant}.npy"));
        let rtrue = read_gt(&format!("{stem}_gt.json"));
        // The peers move the source onto the target: target = A (tree), source = B.
        let po = PrepareOptions::default();
        let a = PreparedSet::new(&tgt, &po, Which::A).unwrap();
        let b = PreparedSet::new(&src, &po, Which::B).unwrap();
        // One-off preparation of the target (trees, subsample, neighbour graphs), which the ICP
        // rows below reuse (as a distance matrix does); Open3D builds its k-d tree inside each
        // registration call, so compare it with the ICP row plus this one.
        let (prep_ms, _) = median_ms(reps, || {
            let p = PreparedSet::new(&tgt, &po, Which::A).unwrap();
            p.graph().len()
        });
        let (graph_ms, _) = median_ms(reps, || nn::NeighbourGraph::new(a.point_tree()).len());
        println!(
            "<!-- prepare target: {prep_ms:.2} ms, of which neighbour graph {graph_ms:.2} ms -->"
        );
        let row = |name: &str, ms: f64, iters: String, r: DMat3| {
            if once {
                println!("{name}: {ms:.2} ms, {iters} iterations");
                return;
            }
            let err = meshcore::linalg::rotation_angle_between(r, rtrue).to_degrees();
            let st = closest_point_stats(&a, &b, &DAffine3::from_mat3(r));
            let nn = {
                // source -> target RMSE only (as the peers' NN-RMSE)
                let mut s = 0.0;
                let ap = a.points();
                let tree_rmse: f64 = b
                    .points()
                    .iter()
                    .map(|p| {
                        let q = r * *p;
                        ap.iter()
                            .map(|x| (*x - q).length_squared())
                            .fold(f64::INFINITY, f64::min)
                    })
                    .sum::<f64>();
                s += tree_rmse;
                (s / b.points().len() as f64).sqrt()
            };
            let corr = if variant == "tgt" {
                let ss: f64 = a
                    .points()
                    .iter()
                    .zip(b.points())
                    .map(|(x, y)| (*x - r * *y).length_squared())
                    .sum();
                format!("{:.5}", (ss / n as f64).sqrt())
            } else {
                "-".into()
            };
            let _ = st;
            let cpu = LAST_CPU.with(|c| c.get());
            println!("| {n} | {deg} | {variant} | {name} | {ms:.2} | {cpu:.2} | {iters} | {err:.3} | {nn:.5} | {corr} |");
        };
        let fixed50 = IcpOptions {
            max_iterations: 50,
            tolerance: 0.0,
            ..Default::default()
        };
        let (ms, res) = median_ms(reps, || icp(&a, &b, DMat3::IDENTITY, &fixed50).unwrap());
        row(
            "shapedist p2p, 50 iterations (no early exit)",
            ms,
            res.iterations.to_string(),
            res.motion.matrix3,
        );
        println!(
            "<!-- tree queries: {} of {} pair searches ({:.1} %) -->",
            res.tree_queries,
            res.pair_searches,
            100.0 * res.tree_queries as f64 / res.pair_searches.max(1) as f64
        );
        if only_plain {
            continue;
        }
        // (row name, options, whether the iterations column shows coarse + fine)
        let runs = [
            (
                "shapedist p2p, 40 it @500 + 10 it @all",
                IcpOptions {
                    max_iterations: 10,
                    tolerance: 0.0,
                    coarse_iterations: 40,
                    ..Default::default()
                },
                true,
            ),
            (
                "shapedist p2p, <=50 it @500 + <=50 it @all, tol 1e-6",
                IcpOptions {
                    max_iterations: 50,
                    tolerance: 1e-6,
                    coarse_iterations: 50,
                    ..Default::default()
                },
                true,
            ),
            (
                "shapedist p2p, <=500 it, tol 1e-6",
                IcpOptions {
                    max_iterations: 500,
                    ..Default::default()
                },
                false,
            ),
            (
                "shapedist point-to-plane <=50 (normals not timed)",
                IcpOptions {
                    variant: IcpVariant::PointToPlane,
                    ..Default::default()
                },
                false,
            ),
        ];
        for (name, o, coarse) in &runs {
            if o.variant == IcpVariant::PointToPlane {
                let _ = a.normals();
            }
            let (ms, res) = median_ms(reps, || icp(&a, &b, DMat3::IDENTITY, o).unwrap());
            let iters = if *coarse {
                format!("{}+{}", res.coarse_iterations, res.iterations)
            } else {
                res.iterations.to_string()
            };
            row(name, ms, iters, res.motion.matrix3);
        }
        for (name, g) in [
            (
                "shapedist global (28 starts@500 + p2p refine <=100)",
                GlobalOptions::default(),
            ),
            (
                "shapedist global + 10 plane warm-up + p2p <=100",
                GlobalOptions {
                    plane_warmup: 10,
                    ..GlobalOptions::default()
                },
            ),
        ] {
            let (ms, res) = median_ms(reps, || global_icp(&a, &b, &g).unwrap());
            row(
                name,
                ms,
                format!(
                    "{}x{}+{}",
                    res.starts, g.coarse_iterations, res.icp.iterations
                ),
                res.icp.motion.matrix3,
            );
        }
        let keys: Vec<u64> = (0..n as u64).collect();
        if variant == "tgt" {
            for m in [RotationMethod::Kabsch, RotationMethod::Horn] {
                let o = KeyedOptions {
                    method: m,
                    ..Default::default()
                };
                let (ms, res) =
                    median_ms(21, || keyed_distance(&keys, &tgt, &keys, &src, &o).unwrap());
                row(
                    &format!("shapedist keyed {m:?} (pairing incl.)"),
                    ms,
                    "1".into(),
                    res.motion.matrix3,
                );
            }
        }
    }
}
