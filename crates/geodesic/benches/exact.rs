#![allow(missing_docs)] // criterion_group! generates an undocumented function
//! Criterion benches of the exact geodesic solver: setup and one solve on the level-5
//! icosphere (10,242 vertices) and on a paper-set face (skipped when the data is absent).

use criterion::{criterion_group, criterion_main, Criterion};
use geodesic::{ExactGeodesic, GeodesicSolver, SolveOptions, Source, TriMesh};
use glam::DVec3;
use std::hint::black_box;
use std::path::PathBuf;

fn icosphere(level: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| DVec3::from_array(*p).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut nf = Vec::with_capacity(f.len() * 4);
        let mut m = |a: u32, b: u32, v: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push((v[a as usize] + v[b as usize]).normalize());
                (v.len() - 1) as u32
            })
        };
        for &[a, b, c] in &f {
            let ab = m(a, b, &mut v);
            let bc = m(b, c, &mut v);
            let ca = m(c, a, &mut v);
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    TriMesh::new(v, f).expect("valid icosphere")
}

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
