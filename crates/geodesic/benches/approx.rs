//! Criterion benches of the approximate methods (fast marching, heat method, Dijkstra): setup
//! and per-source solve, on a level-5 icosphere (10,242 vertices) and on a paper-set face
//! (`$BIPOLAR_SHARED/faces/ict-facekit/paper-set/id1_neutral.obj`, 6,706 vertices; skipped
//! when absent). Single-threaded (faer's global parallelism is set to sequential).
//!
//! `cargo bench -p geodesic --bench approx`

use criterion::{criterion_main, Criterion};
use geodesic::{Dijkstra, FastMarching, GeodesicSolver, HeatMethod, SolveOptions, Source, TriMesh};
use glam::DVec3;
use meshcore::shapes::icosphere;
use std::path::PathBuf;

/// Minimal OBJ reader (`v` and `f` lines, polygons fan-split) so the bench does not depend on
/// another crate.
fn load_obj(path: &std::path::Path) -> Option<TriMesh> {
    let text = std::fs::read_to_string(path).ok()?;
    let (mut p, mut t) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).filter_map(|s| s.parse().ok()).collect();
                p.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let c: Vec<u32> = it
                    .filter_map(|s| s.split('/').next()?.parse::<u32>().ok())
                    .map(|i| i - 1)
                    .collect();
                for k in 1..c.len().saturating_sub(1) {
                    t.push([c[0], c[k], c[k + 1]]);
                }
            }
            _ => {}
        }
    }
    TriMesh::new(p, t).ok()
}

fn face_mesh() -> Option<TriMesh> {
    let shared = std::env::var("BIPOLAR_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
    let p = shared.join("faces/ict-facekit/paper-set/id1_neutral.obj");
    let m = load_obj(&p);
    if m.is_none() {
        eprintln!("skipping the face benches: {} not found", p.display());
    }
    m
}

fn bench_mesh(c: &mut Criterion, name: &str, mesh: &TriMesh, src: u32) {
    let mut g = c.benchmark_group(format!("approx/{name}"));
    g.sample_size(10);
    g.bench_function("fmm/setup", |b| b.iter(|| FastMarching::new(mesh).unwrap()));
    g.bench_function("heat/setup", |b| b.iter(|| HeatMethod::new(mesh).unwrap()));
    g.bench_function("dijkstra/setup", |b| {
        b.iter(|| Dijkstra::new(mesh).unwrap())
    });
    let solvers: Vec<(&str, Box<dyn GeodesicSolver>)> = vec![
        ("fmm", Box::new(FastMarching::new(mesh).unwrap())),
        ("heat", Box::new(HeatMethod::new(mesh).unwrap())),
        ("dijkstra", Box::new(Dijkstra::new(mesh).unwrap())),
    ];
    for (m, s) in &solvers {
        g.bench_function(format!("{m}/solve"), |b| {
            b.iter(|| {
                s.distances(&[Source::Vertex(src)], &SolveOptions::default())
                    .unwrap()
            })
        });
    }
    g.finish();
}

fn benches(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    bench_mesh(c, "ico5", &icosphere(5), 0);
    if let Some(m) = face_mesh() {
        // Vertex 3721: an outer eye corner of the paper-set faces.
        bench_mesh(c, "face_id1_neutral", &m, 3721);
    }
}

#[allow(missing_docs)]
mod group {
    criterion::criterion_group!(approx, super::benches);
}
use group::approx;
criterion_main!(approx);
