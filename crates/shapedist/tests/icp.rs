//! ICP without correspondences: local convergence, global strategy, normalisations.

mod common;

use common::*;
use proptest::prelude::*;
use rand::Rng;
use shapedist::glam::{DAffine3, DMat3, DVec3};
use shapedist::*;

fn rotated(p: &[DVec3], r: DMat3, t: DVec3) -> Vec<DVec3> {
    p.iter().map(|&x| r * x + t).collect()
}

#[test]
fn plain_icp_converges_from_a_small_rotation_both_variants() {
    let mut r = rng(1);
    let a = patch(&mut r, 1500, 0);
    let rot = rotation_by(&mut r, 15.0);
    // b = rot^T a, so R(b -> a) = rot.
    let b = rotated(&a, rot.transpose(), DVec3::new(3.0, -1.0, 2.0));
    let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
    for variant in [IcpVariant::PointToPoint, IcpVariant::PointToPlane] {
        let res = icp(
            &pa,
            &pb,
            DMat3::IDENTITY,
            &IcpOptions {
                variant,
                max_iterations: 200,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            angle_deg(res.motion.matrix3, rot) < 1e-6,
            "{variant:?}: {}",
            angle_deg(res.motion.matrix3, rot)
        );
        assert!(res.rmse < 1e-8);
        assert!(res.converged);
    }
}

#[test]
fn plain_icp_fails_from_180_degrees_but_the_global_strategy_does_not() {
    let mut r = rng(2);
    let a = patch(&mut r, 2000, 3);
    let rot = rotation_by(&mut r, 180.0);
    let b = rotated(&a, rot.transpose(), DVec3::ZERO);
    let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
    let plain = icp(&pa, &pb, DMat3::IDENTITY, &IcpOptions::default()).unwrap();
    assert!(
        angle_deg(plain.motion.matrix3, rot) > 20.0,
        "plain ICP found it: the test is too easy"
    );
    let d = icp_distance(&pa, &pb, &GlobalOptions::default()).unwrap();
    assert!(
        angle_deg(d.motion.matrix3, rot) < 1e-6,
        "{}",
        angle_deg(d.motion.matrix3, rot)
    );
    assert!(d.stats.hausdorff_normalised < 1e-9);
    assert!(d.stats.mean_normalised < 1e-9);
}

#[test]
fn global_icp_recovers_random_rotations_of_a_resampled_noisy_copy() {
    let mut r = rng(3);
    for trial in 0..4 {
        let a = patch(&mut r, 1200, trial);
        let other = patch(&mut r, 1200, trial); // independent sample of the same surface
        let rot = random_rotation(&mut r);
        let b: Vec<DVec3> = other
            .iter()
            .map(|&p| rot.transpose() * p + noise(&mut r, 0.01))
            .collect();
        let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
        let d = icp_distance(&pa, &pb, &GlobalOptions::default()).unwrap();
        // Resampled sets have no exact match: the objective's minimum is a few degrees from
        // the true rotation at this density. The global search must reach that minimum (ICP
        // started at the true rotation), not a different basin.
        let from_truth = icp(&pa, &pb, rot, &GlobalOptions::default().refine).unwrap();
        let err = angle_deg(d.motion.matrix3, rot);
        assert!(err < 8.0, "trial {trial}: {err} deg off");
        assert!(
            d.rmse <= from_truth.rmse * 1.02,
            "trial {trial}: {} vs {}",
            d.rmse,
            from_truth.rmse
        );
        assert!(
            d.stats.mean_normalised < 0.02,
            "{}",
            d.stats.mean_normalised
        );
    }
}

#[test]
fn trimmed_icp_ignores_a_partial_overlap() {
    let mut r = rng(4);
    let a = patch(&mut r, 2000, 1);
    let rot = rotation_by(&mut r, 20.0);
    // B misses a third of A (a hole), plus 5 % far outliers.
    let mut b: Vec<DVec3> = a
        .iter()
        .filter(|p| p.x < 0.3)
        .map(|&p| rot.transpose() * p)
        .collect();
    let nb = b.len();
    for _ in 0..nb / 20 {
        b.push(DVec3::new(r.random(), r.random(), r.random::<f64>() + 2.0));
    }
    let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
    let opts = GlobalOptions {
        refine: IcpOptions {
            trim: 0.1,
            translation: true,
            max_iterations: 200,
            ..Default::default()
        },
        ..Default::default()
    };
    let d = icp_distance(&pa, &pb, &opts).unwrap();
    let err = angle_deg(d.motion.matrix3, rot);
    assert!(err < 0.5, "{err}");
}

#[test]
fn reflection_is_not_a_rotation_for_icp_either() {
    let mut r = rng(5);
    let a = patch(&mut r, 1500, 2);
    let m: Vec<DVec3> = a.iter().map(|p| DVec3::new(-p.x, p.y, p.z)).collect();
    let (pa, pm) = (prepared(&a, Which::A), prepared(&m, Which::B));
    let d = icp_distance(&pa, &pm, &GlobalOptions::default()).unwrap();
    assert!((d.motion.matrix3.determinant() - 1.0).abs() < 1e-9);
    assert!(
        d.stats.mean_normalised > 0.01,
        "{}",
        d.stats.mean_normalised
    );
}

#[test]
fn closest_point_stats_match_brute_force_and_are_symmetric() {
    let mut r = rng(6);
    let a = random_cloud(&mut r, 150, 1.0);
    let b = random_cloud(&mut r, 97, 1.7);
    let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
    let rot = random_rotation(&mut r);
    let s = closest_point_stats(&pa, &pb, &DAffine3::from_mat3(rot));
    let s_rev = closest_point_stats(&pb, &pa, &DAffine3::from_mat3(rot.transpose()));
    let (ca, cb) = (pa.points(), pb.points());
    let nn = |p: DVec3, set: &[DVec3]| {
        set.iter()
            .map(|q| (p - *q).length())
            .fold(f64::INFINITY, f64::min)
    };
    let db: Vec<f64> = cb.iter().map(|&p| nn(rot * p, ca)).collect();
    let da: Vec<f64> = ca.iter().map(|&p| nn(rot.transpose() * p, cb)).collect();
    let h = db.iter().chain(&da).fold(0.0f64, |m, &x| m.max(x));
    let mean = 0.5 * (db.iter().sum::<f64>() / 97.0 + da.iter().sum::<f64>() / 150.0);
    assert!((s.hausdorff - h).abs() < 1e-12);
    assert!((s.mean - mean).abs() < 1e-12);
    assert!((s.hausdorff - s_rev.hausdorff).abs() < 1e-12);
    assert!((s.mean - s_rev.mean).abs() < 1e-12);
    assert!((s.rms_normalised - s_rev.rms_normalised).abs() < 1e-12);
    let rho = pa.radius() + pb.radius();
    assert!((s.hausdorff_normalised - h / rho).abs() < 1e-12);
}

#[test]
fn bad_input_is_rejected() {
    let o = PrepareOptions::default();
    assert_eq!(
        PreparedSet::new(&[], &o, Which::A).unwrap_err(),
        ShapeDistError::Empty(Which::A)
    );
    let mut p = vec![DVec3::X, DVec3::Y, DVec3::Z];
    p[1].z = f64::INFINITY;
    assert!(matches!(
        PreparedSet::new(&p, &o, Which::B).unwrap_err(),
        ShapeDistError::NonFinite {
            which: Which::B,
            index: 1
        }
    ));
    let line: Vec<DVec3> = (0..10).map(|i| DVec3::X * i as f64).collect();
    assert!(matches!(
        PreparedSet::new(&line, &o, Which::A).unwrap_err(),
        ShapeDistError::Degenerate { .. }
    ));
    let mut r = rng(8);
    let a = prepared(&random_cloud(&mut r, 20, 1.0), Which::A);
    let bad = IcpOptions {
        trim: 0.95,
        ..Default::default()
    };
    assert!(matches!(
        icp(&a, &a, DMat3::IDENTITY, &bad),
        Err(ShapeDistError::InvalidOption(_))
    ));
}

#[test]
fn many_points_sharing_one_coordinate_do_not_break_the_tree() {
    // A grid: thousands of points share each x value (kiddo's mutable tree can panic here).
    let a: Vec<DVec3> = (0..4000)
        .map(|i| {
            DVec3::new(
                (i % 5) as f64,
                ((i / 5) % 40) as f64 * 0.1,
                (i / 200) as f64 * 0.01,
            )
        })
        .collect();
    let pa = prepared(&a, Which::A);
    let d = icp_distance(&pa, &pa, &GlobalOptions::default()).unwrap();
    assert!(d.stats.hausdorff < 1e-9);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    #[test]
    fn prop_global_icp_finds_any_rotation_of_an_identical_copy(seed in 0u64..1_000_000) {
        let mut r = rng(seed);
        let a = patch(&mut r, 800, seed % 5);
        let rot = random_rotation(&mut r);
        let b = rotated(&a, rot.transpose(), DVec3::new(1.0, 2.0, 3.0));
        let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
        let d = icp_distance(&pa, &pb, &GlobalOptions::default()).unwrap();
        prop_assert!(angle_deg(d.motion.matrix3, rot) < 1e-5, "{} deg", angle_deg(d.motion.matrix3, rot));
        prop_assert!(d.stats.hausdorff_normalised < 1e-8);
    }

    #[test]
    fn prop_normalised_icp_distances_lie_in_unit_interval(seed in 0u64..1_000_000, s in 0.1f64..10.0) {
        let mut r = rng(seed);
        let a = random_cloud(&mut r, 60, 1.0);
        let b: Vec<DVec3> = random_cloud(&mut r, 45, s).iter().map(|p| *p * DVec3::new(1.0, 0.2, 3.0)).collect();
        let (pa, pb) = (prepared(&a, Which::A), prepared(&b, Which::B));
        let rot = random_rotation(&mut r);
        let st = closest_point_stats(&pa, &pb, &DAffine3::from_mat3(rot));
        for v in [st.hausdorff_normalised, st.mean_normalised, st.rms_normalised] {
            prop_assert!((0.0..=1.0).contains(&v));
        }
        prop_assert!(st.mean_normalised <= st.hausdorff_normalised + 1e-15);
    }
}
