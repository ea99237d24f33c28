//! Closed-form keyed distance: exact recovery, symmetry, reflections, bad input, robustness.

mod common;

use common::*;
use proptest::prelude::*;
use rand::seq::SliceRandom;
use rand::Rng;
use shapedist::glam::{DMat3, DVec3};
use shapedist::*;

/// The options with rotation solver `method`, the rest default.
fn with_method(method: RotationMethod) -> KeyedOptions {
    KeyedOptions {
        method,
        ..Default::default()
    }
}

/// Both rotation solvers.
const METHODS: [RotationMethod; 2] = [RotationMethod::Kabsch, RotationMethod::Horn];

/// The keyed distance by each rotation solver, after checking that each recovers `rot` to
/// 1e-9 rad (a failure names the solver and `case`).
fn recovered_by_both(
    ka: &[u64],
    a: &[DVec3],
    kb: &[u64],
    b: &[DVec3],
    rot: DMat3,
    case: &str,
) -> [KeyedDistance; 2] {
    METHODS.map(|method| {
        let d = keyed_distance(ka, a, kb, b, &with_method(method)).unwrap();
        assert!(
            angle_deg(d.motion.matrix3, rot).to_radians() < 1e-9,
            "{method:?} {case}"
        );
        d
    })
}

fn keyed_copy(seed: u64, n: usize) -> (Vec<u64>, Vec<DVec3>, Vec<u64>, Vec<DVec3>, DMat3, DVec3) {
    let mut r = rng(seed);
    let a = random_cloud(&mut r, n, 10.0);
    let keys: Vec<u64> = (0..n as u64).map(|k| k * 7919 + 3).collect();
    let rot = random_rotation(&mut r);
    let t = DVec3::new(r.random(), r.random(), r.random()) * 100.0;
    // b = R^T (a - t), permuted: then a = R b + t.
    let mut idx: Vec<usize> = (0..n).collect();
    idx.shuffle(&mut r);
    let b: Vec<DVec3> = idx.iter().map(|&i| rot.transpose() * (a[i] - t)).collect();
    let kb: Vec<u64> = idx.iter().map(|&i| keys[i]).collect();
    (keys, a, kb, b, rot, t)
}

#[test]
fn known_rotations_are_recovered_to_1e9_by_kabsch_and_horn() {
    for seed in 0..20 {
        let (ka, a, kb, b, rot, t) = keyed_copy(seed, 50 + seed as usize * 13);
        for d in recovered_by_both(&ka, &a, &kb, &b, rot, &format!("seed {seed}")) {
            assert!((d.motion.translation - t).length() < 1e-9 * 100.0);
            assert!(d.distance < 1e-12, "{}", d.distance);
            assert_eq!(d.shared_keys, a.len());
            assert_eq!((d.share_a, d.share_b), (1.0, 1.0));
        }
    }
}

#[test]
fn rotations_of_180_degrees_and_near_planar_sets_are_recovered() {
    let mut r = rng(7);
    // Nearly planar: the reflection guard matters most here.
    let a: Vec<DVec3> = (0..200)
        .map(|_| {
            DVec3::new(
                r.random::<f64>(),
                r.random::<f64>(),
                1e-6 * r.random::<f64>(),
            )
        })
        .collect();
    let keys: Vec<u64> = (0..200).collect();
    for (axis, deg) in [
        (DVec3::Z, 180.0),
        (DVec3::new(1.0, 1.0, 0.0), 180.0),
        (DVec3::X, 179.9),
    ] {
        let rot = DMat3::from_axis_angle(axis.normalize(), f64::to_radians(deg));
        let b: Vec<DVec3> = a.iter().map(|&p| rot.transpose() * p).collect();
        for d in recovered_by_both(&keys, &a, &keys, &b, rot, &format!("{deg}")) {
            assert!(d.distance < 1e-9);
        }
    }
}

#[test]
fn a_reflection_is_not_mistaken_for_a_rotation() {
    let mut r = rng(3);
    let a = random_cloud(&mut r, 100, 1.0);
    let keys: Vec<u64> = (0..100).collect();
    let mirrored: Vec<DVec3> = a.iter().map(|p| DVec3::new(-p.x, p.y, p.z)).collect();
    for method in METHODS {
        let o = with_method(method);
        let d = keyed_distance(&keys, &a, &keys, &mirrored, &o).unwrap();
        assert!((d.motion.matrix3.determinant() - 1.0).abs() < 1e-12);
        assert!(d.distance > 0.2, "mirror image at distance {}", d.distance);
    }
    // A planar set IS its own mirror image up to a rotation: distance 0 there.
    let flat: Vec<DVec3> = a.iter().map(|p| DVec3::new(p.x, p.y, 0.0)).collect();
    let flat_m: Vec<DVec3> = flat.iter().map(|p| DVec3::new(-p.x, p.y, 0.0)).collect();
    let d = keyed_distance(&keys, &flat, &keys, &flat_m, &KeyedOptions::default()).unwrap();
    assert!(d.distance < 1e-12);
}

#[test]
fn distance_matches_the_singular_value_formula_and_kabsch_equals_horn() {
    let mut r = rng(11);
    let a = random_cloud(&mut r, 60, 2.0);
    let b = random_cloud(&mut r, 60, 3.0);
    let keys: Vec<u64> = (0..60).collect();
    let dk = keyed_distance(&keys, &a, &keys, &b, &KeyedOptions::default()).unwrap();
    let dh = keyed_distance(&keys, &a, &keys, &b, &with_method(RotationMethod::Horn)).unwrap();
    assert!(angle_deg(dk.motion.matrix3, dh.motion.matrix3) < 1e-9);
    assert!((dk.distance - dh.distance).abs() < 1e-12);
    let (ca, cb) = (points::centroid(&a), points::centroid(&b));
    let k = a
        .iter()
        .zip(&b)
        .fold(DMat3::ZERO, |m, (&x, &y)| m + points::outer(x - ca, y - cb));
    let s = meshcore::linalg::svd3(k);
    let na: f64 = a.iter().map(|p| (*p - ca).length_squared()).sum();
    let nb: f64 = b.iter().map(|p| (*p - cb).length_squared()).sum();
    let expect = ((na + nb - 2.0 * (s.s[0] + s.s[1] + s.s[2])) / (na + nb)).sqrt();
    assert!((dk.distance - expect).abs() < 1e-12);
    // Brute force: no rotation on a coarse grid does better.
    for g in shapedist::icp::cube_group() {
        for ang in [0.1, 0.7, 2.0] {
            let rr = g * DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), ang);
            let ss: f64 = a
                .iter()
                .zip(&b)
                .map(|(&x, &y)| ((x - ca) - rr * (y - cb)).length_squared())
                .sum();
            assert!((ss / (na + nb)).sqrt() >= dk.distance - 1e-12);
        }
    }
}

#[test]
fn noise_increases_the_distance_about_linearly() {
    let (ka, a, kb, b, _, _) = keyed_copy(5, 400);
    let mut r = rng(99);
    let dirs = random_cloud(&mut r, 400, 2.0);
    let d = |s: f64| {
        let bn: Vec<DVec3> = b.iter().zip(&dirs).map(|(&p, &e)| p + e * s).collect();
        keyed_distance(&ka, &a, &kb, &bn, &KeyedOptions::default())
            .unwrap()
            .distance
    };
    let (d1, d2, d4) = (d(0.01), d(0.02), d(0.04));
    assert!(d1 > 0.0);
    assert!((d2 / d1 - 2.0).abs() < 0.1, "{d1} {d2}");
    assert!((d4 / d1 - 4.0).abs() < 0.2, "{d1} {d4}");
}

#[test]
fn ambiguous_keys_are_dropped_and_shares_reported() {
    let ka = vec![1, 2, 3, 4, 5, 5, 6];
    let kb = vec![9, 6, 5, 4, 3, 2, 2];
    let p = pair_by_keys(&ka, &kb);
    // 5 is repeated in A, 2 in B: shared unique keys are 3, 4, 6.
    assert_eq!(p.pairs, vec![(2, 4), (3, 3), (6, 1)]);
    assert_eq!((p.ambiguous_a, p.ambiguous_b), (2, 2));
    let a: Vec<DVec3> = (0..7)
        .map(|i| DVec3::new(i as f64, (i * i) as f64, (i % 3) as f64))
        .collect();
    let b: Vec<DVec3> = (0..7)
        .map(|i| DVec3::new((i * 2) as f64, 1.0 - i as f64, (i % 2) as f64))
        .collect();
    let d = keyed_distance(&ka, &a, &kb, &b, &KeyedOptions::default()).unwrap();
    assert_eq!(d.shared_keys, 3);
    assert!((d.share_a - 3.0 / 7.0).abs() < 1e-15);
    assert!((d.share_b - 3.0 / 7.0).abs() < 1e-15);
}

#[test]
fn bad_input_gives_clear_errors() {
    let o = KeyedOptions::default();
    let a = vec![DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
    let k: Vec<u64> = vec![1, 2, 3, 4];
    assert_eq!(
        keyed_distance(&[], &[], &k, &a, &o).unwrap_err(),
        ShapeDistError::Empty(Which::A)
    );
    let mut nan = a.clone();
    nan[2].y = f64::NAN;
    assert_eq!(
        keyed_distance(&k, &a, &k, &nan, &o).unwrap_err(),
        ShapeDistError::NonFinite {
            which: Which::B,
            index: 2
        }
    );
    assert!(matches!(
        keyed_distance(&k, &a, &[1, 2, 9, 9], &a, &o).unwrap_err(),
        ShapeDistError::TooFewPairs { found: 2, .. }
    ));
    assert!(matches!(
        keyed_distance(&k[..3], &a, &k, &a, &o).unwrap_err(),
        ShapeDistError::LengthMismatch {
            which: Which::A,
            ..
        }
    ));
    let line: Vec<DVec3> = (0..4).map(|i| DVec3::splat(i as f64)).collect();
    let e = keyed_distance(&k, &line, &k, &a, &o).unwrap_err();
    assert!(
        matches!(
            e,
            ShapeDistError::Degenerate {
                which: Which::A,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("collinear"));
    let same = vec![DVec3::ONE; 4];
    let e = keyed_distance(&k, &a, &k, &same, &o).unwrap_err();
    assert!(e.to_string().contains("coincide"), "{e}");
}

fn with_outliers(seed: u64) -> (Vec<u64>, Vec<DVec3>, Vec<u64>, Vec<DVec3>, DMat3) {
    let (ka, a, kb, mut b, rot, _) = keyed_copy(seed, 300);
    let mut r = rng(seed + 1000);
    // 10 % wrong matches, far away (as keys that sit on the nose in one face and the forehead
    // in the other).
    for p in b.iter_mut().take(30) {
        *p += DVec3::new(r.random::<f64>() - 0.5, r.random::<f64>() - 0.5, 1.0) * 8.0;
    }
    (ka, a, kb, b, rot)
}

#[test]
fn residual_gate_removes_wrong_matches() {
    let (ka, a, kb, b, rot) = with_outliers(21);
    let gate = KeyedOptions {
        gate: Some(2.0),
        ..Default::default()
    };
    let [plain, gated] =
        [KeyedOptions::default(), gate].map(|o| keyed_distance(&ka, &a, &kb, &b, &o).unwrap());
    assert!(plain.distance > 0.1);
    assert!(gated.distance < 1e-9, "{}", gated.distance);
    assert!(angle_deg(gated.motion.matrix3, rot) < 1e-7);
    assert_eq!(gated.gated, 30);
    assert_eq!(gated.pairs_used, 270);
}

#[test]
fn irls_weights_reduce_the_influence_of_outliers() {
    let (ka, a, kb, b, rot) = with_outliers(22);
    let robust = |loss| KeyedOptions {
        robust: Some(loss),
        irls_iterations: 10,
        ..Default::default()
    };
    let [plain, tukey, huber] = [
        KeyedOptions::default(),
        robust(RobustLoss::Tukey(4.685)),
        robust(RobustLoss::Huber(1.345)),
    ]
    .map(|o| keyed_distance(&ka, &a, &kb, &b, &o).unwrap());
    let (ep, et, eh) = (
        angle_deg(plain.motion.matrix3, rot),
        angle_deg(tukey.motion.matrix3, rot),
        angle_deg(huber.motion.matrix3, rot),
    );
    assert!(et < 1e-6, "tukey {et} deg");
    assert!(eh < ep * 0.5, "huber {eh} vs plain {ep}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn prop_distance_is_symmetric_bounded_and_zero_for_rotated_copies(
        seed in 0u64..1_000_000, n in 3usize..60, scale_b in 0.1f64..10.0,
    ) {
        let mut r = rng(seed);
        let a = random_cloud(&mut r, n, 1.0);
        let b = random_cloud(&mut r, n, scale_b);
        let keys: Vec<u64> = (0..n as u64).collect();
        let o = KeyedOptions::default();
        match (keyed_distance(&keys, &a, &keys, &b, &o), keyed_distance(&keys, &b, &keys, &a, &o)) {
            (Ok(ab), Ok(ba)) => {
                prop_assert!((0.0..=1.0).contains(&ab.distance));
                prop_assert!((ab.distance - ba.distance).abs() < 1e-12);
                // The rotations are inverse to each other.
                prop_assert!(angle_deg(ab.motion.matrix3.transpose(), ba.motion.matrix3) < 1e-6);
            }
            (Err(e), _) | (_, Err(e)) => {
                prop_assert!(matches!(e, ShapeDistError::Degenerate { .. }), "{}", e);
            }
        }
        let rot = random_rotation(&mut r);
        let ra: Vec<DVec3> = a.iter().map(|&p| rot * p + DVec3::splat(5.0)).collect();
        if let Ok(d) = keyed_distance(&keys, &a, &keys, &ra, &o) {
            prop_assert!(d.distance < 1e-9, "{}", d.distance);
        }
    }
}

#[test]
fn option_names_round_trip_and_bad_names_list_the_choices() {
    use shapedist::{IcpVariant, RotationMethod, ShapeDistError};
    meshcore::choice::check_choice::<RotationMethod>("svd").unwrap();
    meshcore::choice::check_choice::<IcpVariant>("normal").unwrap();
    assert_eq!(
        "point-to-plane".parse::<IcpVariant>().unwrap(),
        IcpVariant::PointToPlane
    );
    match "svd".parse::<RotationMethod>() {
        Err(ShapeDistError::UnknownChoice(e)) => assert_eq!(e.expected, ["kabsch", "horn"]),
        other => panic!("{other:?}"),
    }
}
