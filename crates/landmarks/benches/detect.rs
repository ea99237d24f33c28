//! Landmark detection on a paper-set face (6,706 vertices, cm, default generic model) and the
//! curvature stage alone (on that face and on a UV sphere). The face is read from
//! `$BIPOLAR_SHARED` (default `../shared` relative to the workspace root); without it only the
//! sphere is measured. Run with `cargo bench -p landmarks`.

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use landmarks::{curvature::vertex_curvatures, CurvatureOptions, GenericModel};
use meshcore::{DVec3, TriMesh};
use std::hint::black_box;
use std::path::PathBuf;

fn shared_dir() -> PathBuf {
    std::env::var_os("BIPOLAR_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared"))
}

/// A UV sphere of radius 5 (model units, about a face's size) with `n` latitude bands.
fn uv_sphere(n: usize) -> TriMesh {
    let m = 2 * n;
    let mut pos = vec![DVec3::new(0.0, 0.0, 5.0)];
    for i in 1..n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..m {
            let ph = std::f64::consts::TAU * j as f64 / m as f64;
            pos.push(5.0 * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    pos.push(DVec3::new(0.0, 0.0, -5.0));
    let last = (pos.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * m + j % m) as u32;
    let mut tri = Vec::new();
    for j in 0..m {
        tri.push([0, ring(1, j), ring(1, j + 1)]);
        tri.push([last, ring(n - 1, j + 1), ring(n - 1, j)]);
    }
    for i in 1..n - 1 {
        for j in 0..m {
            tri.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
            tri.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
        }
    }
    TriMesh::new(pos, tri).expect("valid sphere")
}

fn bench(c: &mut Criterion) {
    let model = GenericModel::default_model().expect("the shipped model loads");
    let copt = CurvatureOptions::with_radius(model.params.curvature_radius);
    let mut g = c.benchmark_group("landmarks");
    g.sample_size(20);
    let path = shared_dir().join("faces/ict-facekit/paper-set/id1_happiness.obj");
    match mesh_io::read_mesh(&path) {
        Ok(loaded) => {
            let face = loaded.mesh;
            g.bench_function("detect/face-6706", |b| {
                b.iter(|| black_box(landmarks::detect(black_box(&face), &model).is_ok()))
            });
            g.bench_function("curvature/face-6706", |b| {
                b.iter(|| black_box(vertex_curvatures(black_box(&face), &copt).len()))
            });
        }
        Err(e) => eprintln!(
            "paper-set face not available ({e}); benchmarking the curvature of a sphere only"
        ),
    }
    let sphere = uv_sphere(58);
    g.bench_function(format!("curvature/sphere-{}", sphere.n_vertices()), |b| {
        b.iter(|| black_box(vertex_curvatures(black_box(&sphere), &copt).len()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
