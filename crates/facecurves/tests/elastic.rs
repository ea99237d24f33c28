//! The elastic (SRVF) curve distance: zero for reparametrised, rotated, translated copies,
//! symmetric, positive for different shapes.

use facecurves::{elastic_distance, ElasticOptions, FaceCurvesError, Resampling};
use glam::{DAffine3, DMat3, DVec3};
use proptest::prelude::*;
use std::f64::consts::TAU;

/// A closed, non-planar space curve (a three-lobed wavy loop), at parameter `t` (period 1).
fn lobes(t: f64) -> DVec3 {
    let r = 1.0 + 0.3 * (3.0 * TAU * t).cos();
    DVec3::new(
        r * (TAU * t).cos(),
        r * (TAU * t).sin(),
        0.4 * (2.0 * TAU * t).sin(),
    )
}

/// An open helix arc with a bend, at parameter `t` in [0, 1].
fn helix(t: f64) -> DVec3 {
    DVec3::new((4.0 * t).cos(), (4.0 * t).sin(), 0.8 * t + 0.3 * t * t)
}

/// A monotone reparametrisation of [0, 1] (periodic part vanishes at the ends).
fn warp(t: f64) -> f64 {
    t + 0.1 * (TAU * t).sin()
}

fn length(p: &[DVec3], closed: bool) -> f64 {
    let n = p.len();
    let segs = if closed { n } else { n - 1 };
    (0..segs).map(|s| (p[(s + 1) % n] - p[s]).length()).sum()
}

fn motion() -> DAffine3 {
    DAffine3::from_mat3_translation(
        DMat3::from_axis_angle(DVec3::new(0.3, -0.8, 0.5).normalize(), 2.1),
        DVec3::new(4.0, -2.0, 7.5),
    )
}

fn sample_closed(n: usize, f: impl Fn(f64) -> DVec3) -> Vec<DVec3> {
    (0..n).map(|i| f(i as f64 / n as f64)).collect()
}

fn sample_open(n: usize, f: impl Fn(f64) -> DVec3) -> Vec<DVec3> {
    (0..=n).map(|i| f(i as f64 / n as f64)).collect()
}

fn param(samples: usize, window: usize) -> ElasticOptions {
    ElasticOptions {
        samples,
        resampling: Resampling::Parameter,
        window,
        ..Default::default()
    }
}

#[test]
fn closed_copy_reparametrised_rotated_translated_and_restarted_is_at_zero() {
    let a = sample_closed(400, lobes);
    let m = motion();
    // Start point moved by 0.37 of the period, then a non-uniform parametrisation.
    let b: Vec<DVec3> = (0..400)
        .map(|i| m.transform_point3(lobes(warp(i as f64 / 400.0) + 0.37)))
        .collect();
    let scale = length(&a, true).sqrt();
    let d = elastic_distance(&a, true, &b, true, &ElasticOptions::default()).unwrap();
    assert!(
        d.distance < 0.01 * scale,
        "{} vs sqrt(length) {scale}",
        d.distance
    );
    // The rotation found is the inverse of the applied one (b was warped onto a) or the
    // applied one (a onto b).
    let want = if d.warped_first {
        m.matrix3
    } else {
        m.matrix3.transpose()
    };
    let angle = meshcore::linalg::rotation_angle_between(d.rotation, want);
    assert!(angle < 0.01, "rotation off by {angle} rad");
    // The start point lies between two resampled points: found by the fractional search.
    assert!(
        d.start_shift.fract() != 0.0,
        "start shift {}",
        d.start_shift
    );
}

#[test]
fn dynamic_programming_does_the_work_on_parameter_resampling() {
    // Parameter resampling keeps the non-uniform parametrisation: only the reparametrisation
    // search can remove it. Warps forbidden (window 1) against the default window.
    let open_a = sample_open(300, helix);
    let m = motion();
    let open_b: Vec<DVec3> = (0..=300)
        .map(|i| m.transform_point3(helix(warp(i as f64 / 300.0))))
        .collect();
    let scale = length(&open_a, false).sqrt();
    let rigid = elastic_distance(&open_a, false, &open_b, false, &param(100, 1)).unwrap();
    let elastic = elastic_distance(&open_a, false, &open_b, false, &param(100, 3)).unwrap();
    assert!(
        elastic.distance < 0.05 * scale,
        "{} vs {scale}",
        elastic.distance
    );
    assert!(
        rigid.distance > 5.0 * elastic.distance,
        "open: rigid {} vs elastic {}",
        rigid.distance,
        elastic.distance
    );
    assert_eq!(elastic.start_shift, 0.0);
    // The reparametrisation is increasing from (0, 0) to (1, 1).
    let g = &elastic.gamma;
    assert_eq!((g[0], g[g.len() - 1]), ((0.0, 0.0), (1.0, 1.0)));
    assert!(g.windows(2).all(|w| w[0].0 < w[1].0 && w[0].1 <= w[1].1));
    // Closed: the start point and the warp are searched together (less accurate, see
    // docs/section6.md), still far below the rigid comparison.
    let a = sample_closed(400, lobes);
    let b: Vec<DVec3> = (0..400).map(|i| lobes(warp(i as f64 / 400.0))).collect();
    let rigid = elastic_distance(&a, true, &b, true, &param(100, 1)).unwrap();
    let elastic = elastic_distance(&a, true, &b, true, &param(100, 3)).unwrap();
    assert!(
        rigid.distance > 4.0 * elastic.distance,
        "closed: rigid {} vs elastic {}",
        rigid.distance,
        elastic.distance
    );
}

#[test]
fn symmetric_and_positive_for_different_shapes() {
    let circle = sample_closed(200, |t| DVec3::new((TAU * t).cos(), (TAU * t).sin(), 0.0));
    let ellipse = sample_closed(200, |t| {
        DVec3::new(1.4 * (TAU * t).cos(), 0.7 * (TAU * t).sin(), 0.0)
    });
    let wavy = sample_closed(300, lobes);
    let open = sample_open(150, helix);
    let opts = ElasticOptions::default();
    let shapes: [(&[DVec3], bool); 4] = [
        (&circle, true),
        (&ellipse, true),
        (&wavy, true),
        (&open, false),
    ];
    for (i, &(a, ca)) in shapes.iter().enumerate() {
        for &(b, cb) in &shapes[i + 1..] {
            let ab = elastic_distance(a, ca, b, cb, &opts).unwrap();
            let ba = elastic_distance(b, cb, a, ca, &opts).unwrap();
            assert_eq!(ab.distance, ba.distance);
            let scale = length(a, ca).sqrt().min(length(b, cb).sqrt());
            assert!(ab.distance > 0.1 * scale, "{i}: {} vs {scale}", ab.distance);
        }
    }
    // Circle against ellipse of the same length: positive with scale invariance as well.
    let s = ElasticOptions {
        scale: true,
        ..opts
    };
    let d = elastic_distance(&circle, true, &ellipse, true, &s).unwrap();
    assert!(
        d.distance > 0.05 && d.distance <= std::f64::consts::PI,
        "{}",
        d.distance
    );
}

#[test]
fn scale_invariance_is_optional() {
    let a = sample_closed(300, lobes);
    let b: Vec<DVec3> = a.iter().map(|p| *p * 2.5 + DVec3::X).collect();
    let scaled = ElasticOptions {
        scale: true,
        ..Default::default()
    };
    let d = elastic_distance(&a, true, &b, true, &scaled).unwrap();
    assert!(d.distance < 1e-6, "{}", d.distance);
    let d = elastic_distance(&a, true, &b, true, &ElasticOptions::default()).unwrap();
    // |q_b| = sqrt(2.5) |q_a|: the distance is (sqrt(2.5) - 1) sqrt(L_a), with L_a the length
    // of the resampled polygon (its chords make it up to 1e-3 shorter than the input's).
    let want = (2.5f64.sqrt() - 1.0) * length(&a, true).sqrt();
    assert!(
        d.distance <= want && d.distance > (1.0 - 1e-3) * want,
        "{} vs {want}",
        d.distance
    );
}

#[test]
fn bad_input_is_an_error() {
    let ok = sample_closed(10, lobes);
    let opts = ElasticOptions::default();
    let e = elastic_distance(&ok[..2], true, &ok, true, &opts).unwrap_err();
    assert!(
        matches!(e, FaceCurvesError::TooFewPoints { needed: 3, .. }),
        "{e}"
    );
    let mut nan = ok.clone();
    nan[4].y = f64::NAN;
    let e = elastic_distance(&ok, true, &nan, true, &opts).unwrap_err();
    assert!(
        matches!(
            e,
            FaceCurvesError::NonFinitePoint {
                which: "second",
                index: 4
            }
        ),
        "{e}"
    );
    let flat = vec![DVec3::ONE; 5];
    let e = elastic_distance(&flat, false, &ok, true, &opts).unwrap_err();
    assert!(
        matches!(e, FaceCurvesError::ZeroLength { which: "first" }),
        "{e}"
    );
    let e =
        elastic_distance(&ok, true, &ok, true, &ElasticOptions { samples: 2, ..opts }).unwrap_err();
    assert!(e.to_string().contains("samples"), "{e}");
}

/// Coarse polygons (as few points as the rings of a 16-sector polar descriptor) against
/// themselves and a rigid copy: the start-point refinement must not trade the exact start for
/// a fractional one whose resampling cuts the corners differently (it did when it maximised
/// the trace alone, which a longer resampling raises).
#[test]
fn coarse_polygons_are_at_zero_from_themselves_and_rigid_copies() {
    for n in [7, 12, 16, 23] {
        // Irregular spacing: the polygon's corners fall between the resampled points.
        let a: Vec<DVec3> = (0..n)
            .map(|i| {
                let t = (i as f64 + 0.35 * ((i * 7 % 5) as f64 / 5.0)) / n as f64;
                lobes(t) * (1.0 + 0.2 * (i % 3) as f64)
            })
            .collect();
        let b: Vec<DVec3> = a.iter().map(|p| motion().transform_point3(*p)).collect();
        let scale = length(&a, true).sqrt();
        for opts in [
            ElasticOptions::default(),
            ElasticOptions {
                samples: 50,
                start_candidates: 1,
                iterations: 1,
                ..Default::default()
            },
        ] {
            for other in [&a, &b] {
                let d = elastic_distance(&a, true, other, true, &opts).unwrap();
                assert!(d.distance < 1e-6 * scale, "{n} points: {}", d.distance);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    #[test]
    fn rigid_copies_are_at_zero(
        ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in 0.1f64..1.0, angle in -3.1f64..3.1,
        tx in -50.0f64..50.0, ty in -50.0f64..50.0, tz in -50.0f64..50.0,
    ) {
        let a = sample_closed(120, lobes);
        let m = DAffine3::from_mat3_translation(
            DMat3::from_axis_angle(DVec3::new(ax, ay, az).normalize(), angle),
            DVec3::new(tx, ty, tz),
        );
        let b: Vec<DVec3> = a.iter().map(|p| m.transform_point3(*p)).collect();
        let opts = ElasticOptions { samples: 60, ..Default::default() };
        let d = elastic_distance(&a, true, &b, true, &opts).unwrap();
        prop_assert!(d.distance < 1e-5 * length(&a, true).sqrt(), "{}", d.distance);
    }
}
