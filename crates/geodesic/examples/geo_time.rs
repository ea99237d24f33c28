//! Times one geodesic field of ours on a mesh file, for the side-by-side benchmark
//! (`scripts` of docs/bench-geodesic-exact.md drive it together with the peers):
//!
//! ```text
//! cargo run --release -p geodesic --example geo_time -- MESH METHOD SOURCE [CUTOFF] [REPEAT] [OUT]
//! ```
//!
//! METHOD is exact, fmm, heat or dijkstra; SOURCE a vertex index (or `a,b,c` for several);
//! CUTOFF `-` for none. Prints one line `JSON {...}` with the median setup and solve times
//! (seconds; both also as CPU time of the thread), the window propagations (exact) and the peak RSS; OUT (optional) receives the
//! field, one value per line (`inf` beyond the cut-off).

use geodesic::{new_solver, ExactGeodesic, Method, SolveOptions, Source};
use std::time::Instant;

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// CPU time of this thread so far (seconds), from `/proc/thread-self/schedstat` (NaN if absent).
fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 4 {
        eprintln!("usage: geo_time MESH METHOD SOURCE [CUTOFF|-] [REPEAT] [OUT]");
        std::process::exit(2);
    }
    let mesh = testsupport::read_mesh(&a[1]);
    let method: Method = a[2].parse().expect("method");
    let sources: Vec<Source> = a[3]
        .split(',')
        .map(|s| Source::Vertex(s.parse().expect("source vertex")))
        .collect();
    let max_distance = a
        .get(4)
        .filter(|s| s.as_str() != "-")
        .map(|s| s.parse::<f64>().expect("cut-off"));
    let repeat: usize = a.get(5).map_or(3, |s| s.parse().expect("repeat"));
    let opts = SolveOptions { max_distance };
    let (mut setup, mut setup_cpu) = (Vec::new(), Vec::new());
    let (mut solve, mut cpu) = (Vec::new(), Vec::new());
    let mut field = Vec::new();
    for _ in 0..repeat {
        let (t, c) = (Instant::now(), thread_cpu_s());
        let s = new_solver(&mesh, method).expect("solver");
        setup.push(t.elapsed().as_secs_f64());
        setup_cpu.push(thread_cpu_s() - c);
        let (t, c) = (Instant::now(), thread_cpu_s());
        field = s.distances(&sources, &opts).expect("solve");
        solve.push(t.elapsed().as_secs_f64());
        cpu.push(thread_cpu_s() - c);
    }
    let props = if method == Method::Exact {
        let g = ExactGeodesic::new(&mesh).expect("solver");
        g.distances_with_stats(&sources, &opts).expect("solve").1
    } else {
        0
    };
    let (st, stc) = (median(setup), median(setup_cpu));
    let (so, sc) = (median(solve), median(cpu));
    println!(
        "JSON {{\"nV\": {}, \"method\": \"{}\", \"setup_s\": {st:.6}, \"setup_cpu_s\": {stc:.6}, \"solve_s\": {so:.6}, \"solve_cpu_s\": {sc:.6}, \"total_s\": {:.6}, \"propagations\": {props}, \"peak_rss_mb\": {:.1}}}",
        mesh.positions().len(),
        method.name(),
        st + so,
        peak_rss_mb()
    );
    if let Some(out) = a.get(6) {
        let text: String = field.iter().map(|d| format!("{d:.17e}\n")).collect();
        std::fs::write(out, text).expect("writing the field");
    }
}
