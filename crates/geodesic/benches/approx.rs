//! Criterion benches of the approximate methods (fast marching, heat method, Dijkstra): setup
//! and per-source solve, on a level-5 icosphere (10,242 vertices) and on a paper-set face
//! (`id1_neutral.obj` of the shared data, 6,706 vertices; skipped when absent). Single-threaded (faer's global parallelism is set to sequential).
//!
//! `cargo bench -p geodesic --bench approx`

use criterion::{criterion_main, Criterion};
use geodesic::{Dijkstra, FastMarching, GeodesicSolver, HeatMethod, SolveOptions, Source, TriMesh};
use meshcore::shapes::icosphere;

/// The paper-set face, or `None` (after the skip line of `testsupport`) without the data.
fn face_mesh() -> Option<TriMesh> {
    testsupport::paper_face("id1_neutral.obj").map(testsupport::read_mesh)
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
