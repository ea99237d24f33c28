//! Criterion benches: keyed closed form on 10k pairs, point-to-point ICP on 10k points
//! (50 iterations, plain and coarse-to-fine), global ICP from 30, 90 and 180 degrees.
//!
//! Everything runs on one thread (a one-thread rayon pool), as the comparison with Open3D
//! (`OMP_NUM_THREADS=1`) in `docs/bench-shapedist.md`.
//!
//! The point sets follow the ICP peers' `make_clouds.py` patch (a smooth asymmetric height
//! field over an ellipse, noise sigma 0.005); `examples/icp_compare.rs` runs on the peers' own
//! `.npy` files for the side-by-side with Open3D.
#![allow(missing_docs)]

// The point sets of the tests (the peers' patch, uniform noise).
#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use shapedist::glam::{DMat3, DVec3};
use shapedist::*;

fn case(deg: f64) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut r = ChaCha8Rng::seed_from_u64(1);
    let src = common::patch(&mut r, 10_000, 0);
    let rot = DMat3::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), deg.to_radians());
    let tgt = src
        .iter()
        .map(|&p| rot * p + common::noise(&mut r, 0.017))
        .collect();
    (tgt, src)
}

fn benches(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("one-thread pool");
    let mut g = c.benchmark_group("shapedist");
    g.sample_size(10);
    let (tgt, src) = case(30.0);
    let keys: Vec<u64> = (0..10_000u64)
        .map(|k| k.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .collect();
    g.bench_function("keyed_kabsch_10k_pairs", |bch| {
        bch.iter(|| {
            pool.install(|| {
                keyed_distance(&keys, &tgt, &keys, &src, &KeyedOptions::default()).unwrap()
            })
        })
    });
    // Keys already in the same ascending order in both sets (as the example's 0..n): the
    // pairing sorts are then linear.
    let sorted: Vec<u64> = (0..10_000u64).collect();
    g.bench_function("keyed_kabsch_10k_pairs_sorted_keys", |bch| {
        bch.iter(|| {
            pool.install(|| {
                keyed_distance(&sorted, &tgt, &sorted, &src, &KeyedOptions::default()).unwrap()
            })
        })
    });
    let po = PrepareOptions::default();
    // One-off preparation of a set (trees, subsample, neighbour graphs), which the ICP rows
    // below reuse.
    g.bench_function("prepare_set_10k", |bch| {
        bch.iter(|| pool.install(|| PreparedSet::new(&tgt, &po, Which::A).unwrap()))
    });
    for deg in [30.0, 90.0, 180.0] {
        let (tgt, src) = case(deg);
        let (a, b) = (
            common::prepared(&tgt, Which::A),
            common::prepared(&src, Which::B),
        );
        let plain = IcpOptions {
            max_iterations: 50,
            tolerance: 0.0,
            ..Default::default()
        };
        g.bench_function(format!("icp_p2p_10k_50it_from_{deg}deg"), |bch| {
            bch.iter(|| pool.install(|| icp(&a, &b, DMat3::IDENTITY, &plain).unwrap()))
        });
        let sched = IcpOptions {
            max_iterations: 10,
            tolerance: 0.0,
            coarse_iterations: 40,
            ..Default::default()
        };
        g.bench_function(format!("icp_p2p_10k_40it@500+10it_from_{deg}deg"), |bch| {
            bch.iter(|| pool.install(|| icp(&a, &b, DMat3::IDENTITY, &sched).unwrap()))
        });
        g.bench_function(format!("global_icp_10k_from_{deg}deg"), |bch| {
            bch.iter(|| pool.install(|| global_icp(&a, &b, &GlobalOptions::default()).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(shapedist_benches, benches);
criterion_main!(shapedist_benches);
