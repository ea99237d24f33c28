#![allow(missing_docs)] // criterion_group! generates an undocumented function
//! Criterion benches of the exact geodesic solver: setup and one solve on the level-5
//! icosphere (10,242 vertices), one solve on the level-6 icosphere (40,962 vertices), and
//! solves on a paper-set face (skipped when the data is absent), among them the two fields of
//! `bipolar describe` (vertex 1507, uncut and cut at 11.8 cm).

use criterion::{criterion_group, criterion_main, Criterion};
use geodesic::{ExactGeodesic, GeodesicSolver, SolveOptions, Source};
use meshcore::shapes::icosphere;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let ico5 = icosphere(5);
    let mut g = c.benchmark_group("exact");
    g.sample_size(10);
    g.bench_function("setup/ico5", |b| {
        b.iter(|| ExactGeodesic::new(black_box(&ico5)).unwrap())
    });
    let s = ExactGeodesic::new(&ico5).unwrap();
    g.bench_function("solve/ico5", |b| {
        b.iter(|| {
            s.distances(&[Source::Vertex(black_box(0))], &SolveOptions::default())
                .unwrap()
        })
    });
    let ico6 = ExactGeodesic::new(&icosphere(6)).unwrap();
    g.bench_function("solve/ico6", |b| {
        b.iter(|| {
            ico6.distances(&[Source::Vertex(black_box(0))], &SolveOptions::default())
                .unwrap()
        })
    });
    if let Some(face) = testsupport::paper_face("id1_neutral.obj") {
        let s = ExactGeodesic::new(&testsupport::read_mesh(face)).unwrap();
        for (name, v, max_distance) in [
            ("solve/face_id1_neutral", 3000, None),
            ("solve_v1507/face_id1_neutral", 1507, None),
            (
                "solve_v1507_cutoff_11.8cm/face_id1_neutral",
                1507,
                Some(11.8),
            ),
            ("solve_cutoff_5cm/face_id1_neutral", 3000, Some(5.0)),
        ] {
            let o = SolveOptions { max_distance };
            g.bench_function(name, |b| {
                b.iter(|| s.distances(&[Source::Vertex(black_box(v))], &o).unwrap())
            });
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench
}
criterion_main!(benches);
