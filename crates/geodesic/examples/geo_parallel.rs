//! One exact field with the serial schedule and with the banded one on 1 and 2 threads,
//! alternated in one process (for the parallel single solve of docs/bench-geodesic-exact.md):
//!
//! ```text
//! cargo run --release -p geodesic --example geo_parallel -- MESH SOURCE [CUTOFF|-] [ROUNDS] [THREADS...]
//! ```
//!
//! SOURCE is a vertex index; THREADS the banded runs' thread counts (default `1 2`). Each round
//! solves once per variant, the variants in a rotated order. Prints per variant the median
//! and minimum wall time and CPU time of the whole process (every thread's, from
//! `/proc/self/task/*/schedstat`), the window propagations, and whether the field is the same
//! bit for bit as the first banded run's, with its largest relative difference to the serial
//! field.

use geodesic::{ExactGeodesic, ExactSchedule, SolveOptions, Source};
use std::time::Instant;

/// CPU time of every thread of this process so far (seconds).
fn process_cpu_s() -> f64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    dir.filter_map(|e| {
        let p = e.ok()?.path().join("schedstat");
        let s = std::fs::read_to_string(p).ok()?;
        s.split_whitespace().next()?.parse::<f64>().ok()
    })
    .sum::<f64>()
        * 1e-9
}

fn stats(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0])
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 3 {
        eprintln!("usage: geo_parallel MESH SOURCE [CUTOFF|-] [ROUNDS] [THREADS...]");
        std::process::exit(2);
    }
    let mesh = testsupport::read_mesh(&a[1]);
    let src = [Source::Vertex(a[2].parse().expect("source vertex"))];
    let opts = SolveOptions {
        max_distance: a
            .get(3)
            .filter(|s| s.as_str() != "-")
            .map(|s| s.parse().expect("cut-off")),
    };
    let rounds: usize = a.get(4).map_or(3, |s| s.parse().expect("rounds"));
    let threads: Vec<usize> = if a.len() > 5 {
        a[5..].iter().map(|s| s.parse().expect("threads")).collect()
    } else {
        vec![1, 2]
    };
    let serial = ExactGeodesic::new(&mesh).expect("solver");
    let banded = serial.clone().with_schedule(ExactSchedule::Banded);
    let pools: Vec<rayon::ThreadPool> = threads
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .expect("pool")
        })
        .collect();
    // Variant 0: serial; 1..: banded on pools[i - 1].
    let nv = 1 + pools.len();
    let run = |k: usize| -> (Vec<f64>, u64) {
        if k == 0 {
            serial.distances_with_stats(&src, &opts).expect("solve")
        } else {
            pools[k - 1].install(|| banded.distances_with_stats(&src, &opts).expect("solve"))
        }
    };
    let (mut wall, mut cpu) = (vec![Vec::new(); nv], vec![Vec::new(); nv]);
    let mut fields: Vec<Option<(Vec<f64>, u64)>> = vec![None; nv];
    for r in 0..rounds {
        for i in 0..nv {
            let k = (r + i) % nv;
            let (t, c) = (Instant::now(), process_cpu_s());
            let out = run(k);
            wall[k].push(t.elapsed().as_secs_f64());
            cpu[k].push(process_cpu_s() - c);
            if let Some((f, _)) = &fields[k] {
                assert!(
                    f.iter()
                        .zip(&out.0)
                        .all(|(x, y)| x.to_bits() == y.to_bits()),
                    "variant {k}: another field in round {r}"
                );
            }
            fields[k] = Some(out);
        }
    }
    let base = fields[0].as_ref().expect("serial field").0.clone();
    let first_banded = fields.get(1).and_then(|f| f.as_ref()).map(|f| f.0.clone());
    for k in 0..nv {
        let (f, props) = fields[k].as_ref().expect("field");
        let rel = f
            .iter()
            .zip(&base)
            .filter(|(x, y)| x.is_finite() || y.is_finite())
            .map(|(x, y)| (x - y).abs() / y.abs().max(1e-300))
            .fold(0.0f64, f64::max);
        let same = first_banded
            .as_ref()
            .is_none_or(|b| k == 0 || b.iter().zip(f).all(|(x, y)| x.to_bits() == y.to_bits()));
        let (wm, wmin) = stats(wall[k].clone());
        let (cm, cmin) = stats(cpu[k].clone());
        let name = if k == 0 {
            "serial".to_string()
        } else {
            format!("banded_{}t", threads[k - 1])
        };
        println!(
            "JSON {{\"variant\": \"{name}\", \"rounds\": {rounds}, \"wall_median_s\": {wm:.4}, \"wall_min_s\": {wmin:.4}, \"cpu_median_s\": {cm:.4}, \"cpu_min_s\": {cmin:.4}, \"propagations\": {props}, \"same_as_banded_1\": {same}, \"max_rel_vs_serial\": {rel:.3e}}}"
        );
    }
}
