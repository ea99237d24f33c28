//! Timing of the exact solver on the timed cases (paper-set face id1_neutral from vertex
//! 1507, uncut and cut at 11.8 cm; icospheres 5 and 6 from vertex 0):
//!
//! ```text
//! cargo run --release -p geodesic --example exact_timing
//! ```
//!
//! `EXACT_TIMING_REPEAT` (default 7) sets the repetitions (the median is printed);
//! `EXACT_TIMING_DUMP=dir` writes each field as raw little-endian f64 to `dir/<case>.f64`
//! so two builds can be compared bit for bit (`cmp`); `EXACT_TIMING_ONLY=prefix` runs only the
//! cases whose name starts with `prefix` (for `perf record`).

use geodesic::{ExactGeodesic, GeodesicSolver, SolveOptions, Source, TriMesh};
use std::path::PathBuf;
use std::time::Instant;

fn time_case(name: &str, m: &TriMesh, src: u32, cut: Option<f64>, repeat: usize) {
    if let Ok(only) = std::env::var("EXACT_TIMING_ONLY") {
        if !name.starts_with(&only) {
            return;
        }
    }
    let g = ExactGeodesic::new(m).unwrap();
    let opts = SolveOptions { max_distance: cut };
    let mut times = Vec::new();
    let mut d = Vec::new();
    for _ in 0..repeat {
        let t = Instant::now();
        d = g.distances(&[Source::Vertex(src)], &opts).unwrap();
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    let (_, props) = g
        .distances_with_stats(&[Source::Vertex(src)], &opts)
        .unwrap();
    println!(
        "{name}: median {:.2} ms (min {:.2}, max {:.2}, n {repeat}), propagations {props}",
        times[repeat / 2],
        times[0],
        times[repeat - 1]
    );
    assert!(d[src as usize] == 0.0);
    if let Ok(dir) = std::env::var("EXACT_TIMING_DUMP") {
        let bytes: Vec<u8> = d.iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(PathBuf::from(dir).join(format!("{name}.f64")), bytes).unwrap();
    }
}

fn main() {
    let repeat: usize = std::env::var("EXACT_TIMING_REPEAT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(7);
    // Without the shared data, paper_face says why the face cases are left out.
    if let Some(face) = testsupport::paper_face("id1_neutral.obj") {
        let m = testsupport::read_mesh(face);
        time_case("face1507", &m, 1507, None, repeat);
        time_case("face1507_cut11.8", &m, 1507, Some(11.8), repeat);
        time_case("face3721_cut11.8", &m, 3721, Some(11.8), repeat);
    }
    time_case("ico5", &testsupport::shapes::icosphere(5), 0, None, repeat);
    time_case(
        "ico6",
        &testsupport::shapes::icosphere(6),
        0,
        None,
        repeat.min(5),
    );
}
