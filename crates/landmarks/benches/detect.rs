//! Landmark detection on a paper-set face (6,706 vertices, cm, default generic model) and the
//! curvature stage alone (on that face and on a UV sphere). The face comes from the shared data
//! folder (found by `testsupport`); without it only the sphere is measured. Run with
//! `cargo bench -p landmarks`.

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use landmarks::{curvature::vertex_curvatures, CurvatureOptions, GenericModel};
use meshcore::{DVec3, TriMesh};
use std::hint::black_box;

/// A UV sphere of radius 5 (model units, about a face's size) with `n` latitude bands.
fn uv_sphere(n: usize) -> TriMesh {
    testsupport::shapes::uv_sphere(n, 2 * n)
        .transformed(&meshcore::DAffine3::from_scale(DVec3::splat(5.0)))
}

fn bench(c: &mut Criterion) {
    let model = GenericModel::default_model().expect("the shipped model loads");
    let copt = CurvatureOptions::with_radius(model.params.curvature_radius);
    let mut g = c.benchmark_group("landmarks");
    g.sample_size(20);
    match testsupport::paper_face("id1_happiness.obj") {
        Some(path) => {
            let face = testsupport::read_mesh(path);
            g.bench_function("detect/face-6706", |b| {
                b.iter(|| black_box(landmarks::detect(black_box(&face), &model).is_ok()))
            });
            let plain = landmarks::DetectOptions {
                use_regressor: false,
                ..Default::default()
            };
            g.bench_function("detect-template-only/face-6706", |b| {
                b.iter(|| {
                    black_box(landmarks::detect_with(black_box(&face), &model, &plain).is_ok())
                })
            });
            g.bench_function("curvature/face-6706", |b| {
                b.iter(|| black_box(vertex_curvatures(black_box(&face), &copt).len()))
            });
        }
        None => {
            eprintln!("paper-set face not available; benchmarking the curvature of a sphere only")
        }
    }
    let sphere = uv_sphere(58);
    g.bench_function(format!("curvature/sphere-{}", sphere.n_vertices()), |b| {
        b.iter(|| black_box(vertex_curvatures(black_box(&sphere), &copt).len()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
