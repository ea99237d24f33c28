//! Fitting and evaluation speed on noisy circles (the size of a face's level curves).
#![allow(missing_docs)] // criterion macros generate undocumented items

use bspline::{BSpline3, FitOptions};
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::TAU;

fn noisy_circle(n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let a = i as f64 / n as f64 * TAU;
            DVec3::new(30.0 * a.cos(), 30.0 * a.sin(), 0.0)
                + 0.1 * DVec3::new(rng.random(), rng.random(), rng.random())
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    for n in [50usize, 200, 1000] {
        let pts = noisy_circle(n, 1);
        let closed = FitOptions {
            closed: true,
            ..FitOptions::default()
        };
        c.bench_function(&format!("fit_closed_{n}"), |b| {
            b.iter(|| BSpline3::fit(black_box(&pts), &closed).unwrap())
        });
        let open = FitOptions::default();
        let arc = &pts[..n * 3 / 4];
        c.bench_function(&format!("fit_open_{}", arc.len()), |b| {
            b.iter(|| BSpline3::fit(black_box(arc), &open).unwrap())
        });
    }
    let pts = noisy_circle(200, 2);
    let s = BSpline3::fit(&pts, &FitOptions::default()).unwrap();
    c.bench_function("derivative_x1000_open", |b| {
        b.iter(|| {
            let mut acc = DVec3::ZERO;
            for i in 0..1000 {
                acc += s.derivative(black_box(i as f64 / 1000.0));
            }
            acc
        })
    });
    c.bench_function("closest_param_x100_open", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for p in pts.iter().take(100) {
                acc += s.closest_param(black_box(*p + DVec3::splat(0.3)));
            }
            acc
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
