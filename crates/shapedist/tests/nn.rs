//! The fast path of ICP against brute force: the exact nearest-neighbour tree (single,
//! warm-started and grouped queries, ties included), its K-nearest queries, the neighbour
//! graph and its certified walk, and whole ICP runs against a reference ICP written with
//! brute-force correspondences.

mod common;

use common::*;
use meshcore::linalg::kabsch_rotation;
use proptest::prelude::*;
use rand::Rng;
use shapedist::glam::{DMat3, DVec3};
use shapedist::nn::{
    dist2, nearest_brute_force, nearest_k_brute_force, NeighbourGraph, PointTree, GRAPH_K, GROUP,
};
use shapedist::points::outer;
use shapedist::*;

/// Points on a small integer grid (many duplicates and exactly equal distances).
fn grid_cloud(r: &mut rand_chacha::ChaCha8Rng, n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|_| {
            DVec3::new(
                r.random_range(-3..=3) as f64,
                r.random_range(-3..=3) as f64,
                r.random_range(-1..=1) as f64,
            )
        })
        .collect()
}

fn cloud(r: &mut rand_chacha::ChaCha8Rng, n: usize, kind: u8) -> Vec<DVec3> {
    match kind {
        0 => patch(r, n, 3),
        1 => random_cloud(r, n, 2.0),
        _ => grid_cloud(r, n),
    }
}

/// The generator of case `seed` (after drawing the points), a cloud of `n` points of `kind` and
/// its tree.
fn tree_case(seed: u64, n: usize, kind: u8) -> (rand_chacha::ChaCha8Rng, Vec<DVec3>, PointTree) {
    let mut r = rng(seed);
    let pts = cloud(&mut r, n, kind);
    let tree = PointTree::new(&pts);
    (r, pts, tree)
}

/// `(seed, n, kind)` of a [`tree_case`] with `1 <= n < max_n`.
fn case(max_n: usize) -> impl Strategy<Value = (u64, usize, u8)> {
    (0u64..1_000_000, 1usize..max_n, 0u8..3)
}

/// A uniform random offset in the cube of side `scale` centred at the origin.
fn jitter(r: &mut rand_chacha::ChaCha8Rng, scale: f64) -> DVec3 {
    DVec3::new(
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
    ) * scale
}

/// A valid warm-start candidate for `q`: a random point of `pts` and its squared distance.
fn random_candidate(r: &mut rand_chacha::ChaCha8Rng, pts: &[DVec3], q: DVec3) -> (f64, u32) {
    let j = r.random_range(0..pts.len());
    (dist2(pts[j], q), j as u32)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn prop_tree_queries_equal_brute_force((seed, n, kind) in case(400), far in 0.0f64..3.0) {
        let (mut r, pts, tree) = tree_case(seed, n, kind);
        prop_assert_eq!(tree.len(), n);
        // Queries near and far from the set; on the grid, half-integer offsets give ties.
        let qs: Vec<DVec3> = (0..3 * GROUP + 3)
            .map(|k| {
                let base = pts[r.random_range(0..n)];
                if kind == 2 && k % 2 == 0 {
                    base + DVec3::new(0.5, -0.5, 0.0) * (k % 4) as f64
                } else {
                    base + jitter(&mut r, far)
                }
            })
            .collect();
        let want: Vec<(f64, u32)> = qs.iter().map(|&q| nearest_brute_force(&pts, q)).collect();
        for (q, w) in qs.iter().zip(&want) {
            prop_assert_eq!(tree.nearest(*q), *w);
            // Warm start from any valid candidate gives the same exact answer.
            let mut best = random_candidate(&mut r, &pts, *q);
            tree.nearest_from(*q, &mut best);
            prop_assert_eq!(best, *w);
            // A group of one (its group box is the point itself: the same pruning bound).
            let mut one = [(f64::INFINITY, u32::MAX)];
            tree.nearest_group(&[*q], &mut one);
            prop_assert_eq!(one[0], *w);
        }
        // Grouped queries, some seeded, some not.
        let mut got: Vec<(f64, u32)> = qs
            .iter()
            .enumerate()
            .map(|(k, &q)| {
                if k % 3 == 0 {
                    (f64::INFINITY, u32::MAX)
                } else {
                    random_candidate(&mut r, &pts, q)
                }
            })
            .collect();
        tree.nearest_group(&qs, &mut got);
        prop_assert_eq!(got, want);
        // The leaf order is a permutation of the points.
        let mut ids = tree.leaf_order_ids().to_vec();
        ids.sort_unstable();
        prop_assert_eq!(ids, (0..n as u32).collect::<Vec<_>>());
        for (p, &i) in tree.leaf_order_points().iter().zip(tree.leaf_order_ids()) {
            prop_assert_eq!(*p, pts[i as usize]);
        }
    }
}

#[test]
fn ties_go_to_the_lowest_index_and_a_wrong_seed_is_detected() {
    // Four points at the same distance from the origin, inserted in scrambled order.
    let pts = vec![
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(5.0, 5.0, 5.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(-1.0, 0.0, 0.0),
    ];
    let tree = PointTree::new(&pts);
    assert_eq!(tree.nearest(DVec3::ZERO), (1.0, 0));
    assert_eq!(nearest_brute_force(&pts, DVec3::ZERO), (1.0, 0));
    let mut seeded = (1.0, 4);
    tree.nearest_from(DVec3::ZERO, &mut seeded);
    assert_eq!(seeded, (1.0, 0));
    // A candidate with a false (too small) distance is not a valid seed: the answer is then
    // wrong, and the comparison with brute force says so (the checks above can fail).
    let mut bad = (0.5, 1);
    tree.nearest_from(DVec3::ZERO, &mut bad);
    assert_ne!(bad, nearest_brute_force(&pts, DVec3::ZERO));
    assert!(PointTree::new(&[]).is_empty());
    assert_eq!(PointTree::new(&[]).nearest(DVec3::ONE).1, u32::MAX);
}

#[test]
fn duplicates_spread_over_many_leaves_resolve_to_the_first_copy() {
    // 300 copies of one point (spread over many leaves by the median splits) among others;
    // seeded with the last copy, every search must still return the first one: subtrees at
    // exactly the best distance are not skipped.
    let mut r = rng(5);
    let mut pts = random_cloud(&mut r, 1000, 1.0);
    let p = DVec3::new(0.1, 0.2, 0.3);
    let copies: Vec<u32> = (0..300).map(|k| 3 * k + 7).collect();
    for &i in &copies {
        pts[i as usize] = p;
    }
    let tree = PointTree::new(&pts);
    for q in [
        p,
        p + DVec3::new(1e-3, 0.0, 0.0),
        p + DVec3::new(0.0, -0.02, 0.01),
    ] {
        let last = *copies.last().unwrap();
        let want = (dist2(p, q), copies[0]);
        assert_eq!(nearest_brute_force(&pts, q), want);
        let mut best = (dist2(p, q), last);
        tree.nearest_from(q, &mut best);
        assert_eq!(best, want);
        let mut g = [(dist2(p, q), last), (f64::INFINITY, u32::MAX)];
        tree.nearest_group(&[q, q], &mut g);
        assert_eq!(g, [want, want]);
        assert_eq!(tree.nearest(q), want);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn prop_k_nearest_queries_equal_brute_force((seed, n, kind) in case(300), far in 0.0f64..2.0) {
        let (mut r, pts, tree) = tree_case(seed, n, kind);
        let qs: Vec<DVec3> = (0..2 * GROUP + 5)
            .map(|_| {
                pts[r.random_range(0..n)]
                    + DVec3::new(r.random::<f64>() - 0.5, r.random::<f64>() - 0.5, 0.3) * far
            })
            .collect();
        // Seeds: none, or one valid candidate.
        let mut got: Vec<[(f64, u32); 5]> = qs
            .iter()
            .enumerate()
            .map(|(k, &q)| {
                let mut b = [(f64::INFINITY, u32::MAX); 5];
                if k % 2 == 1 {
                    b[0] = random_candidate(&mut r, &pts, q);
                }
                b
            })
            .collect();
        tree.nearest_k_group(&qs, &mut got);
        for (q, g) in qs.iter().zip(&got) {
            prop_assert_eq!(*g, nearest_k_brute_force::<5>(&pts, *q));
        }
    }

    #[test]
    fn prop_neighbour_graph_is_the_exact_k_nearest_graph((seed, n, kind) in case(300)) {
        let (_, pts, tree) = tree_case(seed, n, kind);
        let graph = NeighbourGraph::new(&tree);
        prop_assert_eq!(graph.len(), n);
        for (i, &p) in pts.iter().enumerate() {
            // Brute force: the K + 1 nearest, the point itself dropped (duplicates of it stay).
            let want: Vec<u32> = nearest_k_brute_force::<{ GRAPH_K + 1 }>(&pts, p)
                .iter()
                .filter(|b| b.1 != u32::MAX && b.1 != i as u32)
                .take(GRAPH_K)
                .map(|b| b.1)
                .collect();
            prop_assert_eq!(graph.neighbours(i as u32), want, "point {}", i);
        }
    }

    #[test]
    fn prop_certified_graph_walks_equal_brute_force((seed, n, kind) in case(400), off in 0.0f64..0.3) {
        let (mut r, pts, tree) = tree_case(seed, n, kind);
        let graph = NeighbourGraph::new(&tree);
        let mut certified = 0;
        let trials = 200;
        for k in 0..trials {
            let base = pts[r.random_range(0..n)];
            // Near a point (where walks certify), on the grid also at exact ties.
            let q = if kind == 2 && k % 3 == 0 {
                base + DVec3::new(0.5, 0.0, 0.0)
            } else {
                base + jitter(&mut r, off)
            };
            let start = r.random_range(0..n) as u32;
            let (got, sure) = graph.descend(q, start, 64);
            // Always a valid seed: the distance is that of the returned point.
            prop_assert!(got.1 != u32::MAX);
            prop_assert_eq!(got.0, dist2(pts[got.1 as usize], q));
            if sure {
                certified += 1;
                prop_assert_eq!(got, nearest_brute_force(&pts, q), "query {:?} from {}", q, start);
            }
        }
        // The certificate is not vacuous: small sets are certified everywhere, near-surface
        // queries on a patch mostly.
        if n <= GRAPH_K {
            prop_assert_eq!(certified, trials);
        }
        if kind == 0 && n >= 100 && off < 0.02 {
            prop_assert!(certified > trials / 2, "{} of {} certified", certified, trials);
        }
    }
}

#[test]
fn a_walk_is_not_certified_where_a_far_point_is_nearer() {
    // A dense row of points and one isolated point: from the row, a query right next to the
    // isolated point must not be certified at a row point (the isolated point is nearer and
    // is not among the row points' neighbours).
    let mut pts: Vec<DVec3> = (0..40)
        .map(|i| DVec3::new(i as f64 * 0.01, 0.0, 0.0))
        .collect();
    pts.push(DVec3::new(0.2, 5.0, 0.0));
    let tree = PointTree::new(&pts);
    let graph = NeighbourGraph::new(&tree);
    let q = DVec3::new(0.2, 4.9, 0.0);
    let (got, sure) = graph.descend(q, 20, 8);
    let want = nearest_brute_force(&pts, q);
    assert_eq!(want.1, 40);
    assert!(!sure || got == want, "certified a wrong answer {got:?}");
    // Near the row, the walk certifies the right point.
    let q = DVec3::new(0.101, 0.002, 0.0);
    let (got, sure) = graph.descend(q, 0, 64);
    assert!(sure);
    assert_eq!(got, nearest_brute_force(&pts, q));
    assert_eq!(got.1, 10);
}

/// Reference ICP (the same mathematics, brute-force correspondences, sums in input order):
/// returns the rotation, translation and the RMS of the kept pairs at the final pose.
fn reference_icp(
    a: &[DVec3],
    b: &[DVec3],
    init: DMat3,
    iters: usize,
    trim: f64,
    translation: bool,
) -> (DMat3, DVec3, f64) {
    let pairs = |r: DMat3, t: DVec3| -> (Vec<(f64, u32)>, f64) {
        let c: Vec<(f64, u32)> = b
            .iter()
            .map(|&x| nearest_brute_force(a, r * x + t))
            .collect();
        let keep = ((c.len() as f64) * (1.0 - trim)).ceil().max(3.0) as usize;
        let thr = if trim <= 0.0 || keep >= c.len() {
            f64::INFINITY
        } else {
            let mut d: Vec<f64> = c.iter().map(|p| p.0).collect();
            d.sort_by(f64::total_cmp);
            d[keep - 1]
        };
        (c, thr)
    };
    let (mut r, mut t) = (init, DVec3::ZERO);
    for _ in 0..iters {
        let (c, thr) = pairs(r, t);
        let (mut n, mut sa, mut sb, mut k) = (0.0, DVec3::ZERO, DVec3::ZERO, DMat3::ZERO);
        for (p, x) in c.iter().zip(b) {
            if p.0 <= thr {
                let y = a[p.1 as usize];
                n += 1.0;
                sa += y;
                sb += *x;
                k += outer(y, *x);
            }
        }
        if n < 3.0 {
            break;
        }
        if translation {
            let (ma, mb) = (sa / n, sb / n);
            r = kabsch_rotation(k - outer(ma, mb) * n).0;
            t = ma - r * mb;
        } else {
            r = kabsch_rotation(k).0;
        }
    }
    let (c, thr) = pairs(r, t);
    let kept: Vec<f64> = c.iter().map(|p| p.0).filter(|&d| d <= thr).collect();
    (r, t, (kept.iter().sum::<f64>() / kept.len() as f64).sqrt())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn prop_icp_equals_the_brute_force_reference(
        seed in 0u64..1_000_000,
        n in 20usize..250,
        deg in 0.0f64..120.0,
        trim_on in any::<bool>(),
        translation in any::<bool>(),
        kind in 0u8..2,
    ) {
        let mut r = rng(seed);
        let src = cloud(&mut r, n, kind);
        let rot = rotation_by(&mut r, deg);
        let tgt: Vec<DVec3> = cloud(&mut r, n + 17, kind)
            .iter()
            .map(|&p| rot * p + DVec3::new(0.3, -0.1, 0.2))
            .collect();
        let (a, b) = (prepared(&tgt, Which::A), prepared(&src, Which::B));
        let trim = if trim_on { 0.2 } else { 0.0 };
        let iters = 25;
        let opts = IcpOptions {
            max_iterations: iters,
            tolerance: 0.0,
            trim,
            translation,
            ..Default::default()
        };
        let got = icp(&a, &b, DMat3::IDENTITY, &opts).unwrap();
        let (rr, rt, rrmse) = reference_icp(a.points(), b.points(), DMat3::IDENTITY, iters, trim, translation);
        // The sums are formed in another order (leaf order, chunks): equal to rounding.
        let err = (got.motion.matrix3 - rr).to_cols_array().iter().fold(0.0f64, |m, x| m.max(x.abs()));
        prop_assert!(err < 1e-9, "rotation differs by {err:e}");
        prop_assert!((got.motion.translation - rt).length() < 1e-9 * (1.0 + a.radius()));
        prop_assert!((got.rmse - rrmse).abs() <= 1e-9 * (1.0 + rrmse), "{} vs {}", got.rmse, rrmse);
    }
}

#[test]
fn icp_results_do_not_depend_on_the_thread_count() {
    // Large enough for the parallel correspondence path.
    let mut r = rng(77);
    let src = patch(&mut r, 3000, 5);
    let rot = rotation_by(&mut r, 40.0);
    let tgt: Vec<DVec3> = patch(&mut r, 3100, 5).iter().map(|&p| rot * p).collect();
    let (a, b) = (prepared(&tgt, Which::A), prepared(&src, Which::B));
    let opts = IcpOptions {
        max_iterations: 8,
        tolerance: 0.0,
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| icp(&a, &b, DMat3::IDENTITY, &opts).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(
        one.motion.matrix3.to_cols_array(),
        two.motion.matrix3.to_cols_array()
    );
    assert_eq!(one.rmse.to_bits(), two.rmse.to_bits());
    assert_eq!(one.iterations, 8);
    // And the iterations did move the source (the comparison is not between two no-ops).
    assert!(meshcore::linalg::rotation_angle_between(one.motion.matrix3, DMat3::IDENTITY) > 0.1);
}
