#![allow(missing_docs)] // criterion_group! generates an undocumented function
//! Criterion benches of the exact geodesic solver: setup and one solve on the level-5
//! icosphere (10,242 vertices), one solve on the level-6 icosphere (40,962 vertices), and
//! solves on a paper-set face (skipped when the data is absent), among them the two fields of
//! `bipolar describe` (vertex 1507, uncut and cut at 11.8 cm), and the many-sources cases of
//! the reference-point search (3 poles, 18 moved poles: one by one, with a reused
//! [`ExactWorkspace`], and through `ExactGeodesic::distances_many`).

use criterion::{criterion_group, criterion_main, Criterion};
use geodesic::{ExactGeodesic, ExactWorkspace, GeodesicSolver, SolveOptions, Source};
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
        let mesh = testsupport::read_mesh(face);
        let s = ExactGeodesic::new(&mesh).unwrap();
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
        // Many sources on one mesh (the face matcher's reference-point search): three poles
        // and each moved by 0.2 cm in 6 directions of the x-y plane, cut at 11.8 cm; the
        // poles' three fields one after another, and the 18 moved fields one by one, with a
        // reused workspace, and through `distances_many` (parallel, reused buffers).
        let poles = [1507u32, 3721, 3000];
        let own: Vec<Vec<Source>> = poles.iter().map(|&p| vec![Source::Vertex(p)]).collect();
        let mut moved: Vec<Vec<Source>> = Vec::new();
        for &p in &poles {
            let c = mesh.positions()[p as usize];
            for k in 0..6 {
                let t = std::f64::consts::TAU * f64::from(k) / 6.0;
                let q = c + 0.2 * glam::DVec3::new(t.cos(), t.sin(), 0.0);
                moved.push(vec![Source::Vertex(testsupport::nearest_vertex(&mesh, q))]);
            }
        }
        let o = SolveOptions {
            max_distance: Some(11.8),
        };
        g.bench_function("many/own_3_one_by_one/face_id1_neutral", |b| {
            b.iter(|| {
                for x in &own {
                    black_box(s.distances(x, &o).unwrap());
                }
            })
        });
        g.bench_function("many/moved_18_one_by_one/face_id1_neutral", |b| {
            b.iter(|| {
                for x in &moved {
                    black_box(s.distances(x, &o).unwrap());
                }
            })
        });
        g.bench_function("many/moved_18_workspace/face_id1_neutral", |b| {
            let mut ws = ExactWorkspace::new();
            b.iter(|| {
                for x in &moved {
                    black_box(s.distances_with(&mut ws, x, &o).unwrap());
                }
            })
        });
        g.bench_function("many/moved_18_distances_many/face_id1_neutral", |b| {
            b.iter(|| black_box(s.distances_many(&moved, &o).unwrap()))
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench
}
criterion_main!(benches);
