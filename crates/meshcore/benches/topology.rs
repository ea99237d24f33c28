//! `Topology::new` (the adjacency every `Surface` builds) on a grid of the size of a 0.75 mm
//! range scan of a face (about 38k vertices, 75k faces). Run with
//! `cargo bench -p meshcore --bench topology`.

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use meshcore::shapes::{grid, Diagonals};
use meshcore::{DVec3, Topology};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    // A 0.75 mm grid bent like a face (a shallow cap), 200 x 190 samples.
    let mesh = grid(200, 190, Diagonals::Uniform, |i, j| {
        let (x, y) = (0.75 * i as f64 - 75.0, 0.75 * j as f64 - 71.0);
        DVec3::new(x, y, -(x * x + y * y) / 300.0)
    })
    .expect("a valid grid");
    let mut g = c.benchmark_group("topology");
    g.sample_size(20);
    g.bench_function(format!("new/grid-{}", mesh.n_vertices()), |b| {
        b.iter(|| black_box(Topology::new(black_box(&mesh)).edges().len()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
