#![allow(missing_docs)] // criterion_group! generates an undocumented function
//! Criterion benches of the exact geodesic solver: setup and one solve on the level-5
//! icosphere (10,242 vertices), one solve on the level-6 icosphere (40,962 vertices), and
//! solves on a paper-set face (skipped when the data is absent), among them the two fields of
//! `bipolar describe` (vertex 1507, uncut and cut at 11.8 cm).

use criterion::{criterion_group, criterion_main, Criterion};
use geodesic::{ExactGeodesic, GeodesicSolver, SolveOptions, Source, TriMesh};
use glam::DVec3;
use meshcore::shapes::icosphere;
use std::hint::black_box;
use std::path::PathBuf;

/// `v`/`f` lines of an OBJ file (mesh-io is a separate crate; this keeps the bench standalone).
fn read_obj(path: &std::path::Path) -> Option<TriMesh> {
    let text = std::fs::read_to_string(path).ok()?;
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).filter_map(|s| s.parse().ok()).collect();
                v.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let idx: Vec<u32> = it
                    .filter_map(|s| s.split('/').next()?.parse::<u32>().ok())
                    .map(|i| i - 1)
                    .collect();
                for k in 1..idx.len().saturating_sub(1) {
                    f.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    TriMesh::new(v, f).ok()
}

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
    let shared = std::env::var("BIPOLAR_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
    let face = shared.join("faces/ict-facekit/paper-set/id1_neutral.obj");
    match read_obj(&face) {
        Some(m) => {
            let s = ExactGeodesic::new(&m).unwrap();
            g.bench_function("solve/face_id1_neutral", |b| {
                b.iter(|| {
                    s.distances(&[Source::Vertex(black_box(3000))], &SolveOptions::default())
                        .unwrap()
                })
            });
            g.bench_function("solve_v1507/face_id1_neutral", |b| {
                b.iter(|| {
                    s.distances(&[Source::Vertex(black_box(1507))], &SolveOptions::default())
                        .unwrap()
                })
            });
            g.bench_function("solve_v1507_cutoff_11.8cm/face_id1_neutral", |b| {
                b.iter(|| {
                    s.distances(
                        &[Source::Vertex(black_box(1507))],
                        &SolveOptions {
                            max_distance: Some(11.8),
                        },
                    )
                    .unwrap()
                })
            });
            g.bench_function("solve_cutoff_5cm/face_id1_neutral", |b| {
                b.iter(|| {
                    s.distances(
                        &[Source::Vertex(black_box(3000))],
                        &SolveOptions {
                            max_distance: Some(5.0),
                        },
                    )
                    .unwrap()
                })
            });
        }
        None => println!("skipping face bench: {} not found", face.display()),
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench
}
criterion_main!(benches);
