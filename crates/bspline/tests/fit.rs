//! Fitting tests: analytic oracles and property tests.

use bspline::{
    data_params, dedup_consecutive, BSpline3, BSplineError, FitOptions, Parametrization,
};
use glam::{DQuat, DVec3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::TAU;

fn cubic(c: &[DVec3; 4], t: f64) -> DVec3 {
    c[0] + t * (c[1] + t * (c[2] + t * c[3]))
}

fn cubic_d(c: &[DVec3; 4], t: f64) -> DVec3 {
    c[1] + t * (2.0 * c[2] + 3.0 * t * c[3])
}

fn cubic_dd(c: &[DVec3; 4], t: f64) -> DVec3 {
    2.0 * c[2] + 6.0 * t * c[3]
}

fn circle(n: usize, r: f64) -> Vec<DVec3> {
    (0..n)
        .map(|i| {
            let a = i as f64 / n as f64 * TAU;
            DVec3::new(r * a.cos(), r * a.sin(), 0.0)
        })
        .collect()
}

/// [`circle`] with Gaussian noise of deviation `sigma` on every coordinate (ChaCha8 seeded by
/// `seed`).
fn noisy_circle(n: usize, r: f64, sigma: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    circle(n, r)
        .into_iter()
        .map(|p| p + sigma * DVec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)))
        .collect()
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    // Box-Muller.
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

fn closed_opts(n: Option<usize>, smoothing: f64) -> FitOptions {
    FitOptions {
        closed: true,
        n_control: n,
        smoothing,
        ..FitOptions::default()
    }
}

#[test]
fn open_fit_reproduces_cubic_polynomial_with_given_params() {
    let c = [
        DVec3::new(1.0, -2.0, 0.5),
        DVec3::new(3.0, 1.0, -1.0),
        DVec3::new(-2.0, 4.0, 2.0),
        DVec3::new(1.5, -3.0, 0.7),
    ];
    let n = 40;
    let ts: Vec<f64> = (0..n)
        .map(|i| (i as f64 / (n - 1) as f64).powf(1.2))
        .collect();
    let pts: Vec<DVec3> = ts.iter().map(|&t| cubic(&c, t)).collect();
    for nc in [4, 7, 12, 20] {
        let opts = FitOptions {
            n_control: Some(nc),
            smoothing: 0.0,
            ..FitOptions::default()
        };
        let s = BSpline3::fit_with_params(&pts, &ts, &opts).unwrap();
        for i in 0..=100 {
            let u = i as f64 / 100.0;
            assert!((s.eval(u) - cubic(&c, u)).length() < 1e-9, "nc {nc} u {u}");
            assert!((s.derivative(u) - cubic_d(&c, u)).length() < 1e-8);
            assert!((s.second_derivative(u) - cubic_dd(&c, u)).length() < 1e-6);
        }
    }
}

#[test]
fn open_fit_reproduces_uniform_line_with_chord_params() {
    // A straight line sampled uniformly: chord-length parameters equal the true ones, so the
    // fit through `fit` (not `fit_with_params`) must reproduce it, even with smoothing (the
    // second-difference penalty vanishes on linear control polygons).
    let a = DVec3::new(1.0, 2.0, 3.0);
    let b = DVec3::new(-4.0, 0.5, 7.0);
    let pts: Vec<DVec3> = (0..25).map(|i| a.lerp(b, i as f64 / 24.0)).collect();
    for p in [Parametrization::ChordLength, Parametrization::Centripetal] {
        let opts = FitOptions {
            parametrization: p,
            smoothing: 0.1,
            ..FitOptions::default()
        };
        let s = BSpline3::fit(&pts, &opts).unwrap();
        for i in 0..=50 {
            let u = i as f64 / 50.0;
            assert!((s.eval(u) - a.lerp(b, u)).length() < 1e-9);
            assert!((s.derivative(u) - (b - a)).length() < 1e-8);
            assert!(s.second_derivative(u).length() < 1e-6);
        }
    }
}

#[test]
fn closed_fit_reproduces_periodic_spline_samples() {
    // Build a periodic spline from random control points by fitting with n_control = number of
    // points (interpolation), sample it, and refit the samples with the same parameters.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let base: Vec<DVec3> = (0..10)
        .map(|i| {
            let a = i as f64 / 10.0 * TAU;
            DVec3::new(a.cos(), a.sin(), 0.0)
                + 0.2 * DVec3::new(rng.random(), rng.random(), rng.random())
        })
        .collect();
    let truth = BSpline3::fit(&base, &closed_opts(Some(10), 0.0)).unwrap();
    let m = 57;
    let us: Vec<f64> = (0..m)
        .map(|i| (i as f64 + 0.3 * ((i * 7 % 5) as f64) / 5.0) / m as f64)
        .collect();
    let samples: Vec<DVec3> = us.iter().map(|&u| truth.eval(u)).collect();
    let refit = BSpline3::fit_with_params(&samples, &us, &closed_opts(Some(10), 0.0)).unwrap();
    for i in 0..200 {
        let u = i as f64 / 200.0;
        assert!((refit.eval(u) - truth.eval(u)).length() < 1e-10);
        assert!((refit.derivative(u) - truth.derivative(u)).length() < 1e-8);
    }
    for (a, b) in refit.control_points().iter().zip(truth.control_points()) {
        assert!((*a - *b).length() < 1e-10);
    }
}

#[test]
fn closed_curve_is_periodic_and_c2() {
    let pts = noisy_circle(60, 2.0, 0.05, 3);
    let s = BSpline3::fit(&pts, &closed_opts(None, 1e-3)).unwrap();
    let e = 1e-12;
    assert!((s.eval(0.0) - s.eval(1.0 - e)).length() < 1e-9);
    assert!((s.derivative(0.0) - s.derivative(1.0 - e)).length() < 1e-8);
    assert!((s.second_derivative(0.0) - s.second_derivative(1.0 - e)).length() < 1e-6);
    assert!((s.eval(0.3) - s.eval(2.3)).length() < 1e-12);
    assert!((s.eval(0.3) - s.eval(-0.7)).length() < 1e-12);
    // Continuity across every knot (uniform, spacing 1/nc).
    let nc = s.control_points().len();
    for k in 0..nc {
        let u = k as f64 / nc as f64;
        assert!((s.eval(u - 1e-10) - s.eval(u + 1e-10)).length() < 1e-8);
        assert!((s.derivative(u - 1e-10) - s.derivative(u + 1e-10)).length() < 1e-6);
    }
}

#[test]
fn circle_tangent_error_shrinks_with_sampling() {
    // Noiseless circle of radius 10: the tangent angle error at the data points must be small
    // and decrease as the sampling gets denser (the control spacing follows the sampling).
    let mut prev = f64::INFINITY;
    for n in [24, 48, 96, 192] {
        let pts = circle(n, 10.0);
        for closed in [true, false] {
            let (pts, opts) = if closed {
                (pts.clone(), closed_opts(None, 1e-3))
            } else {
                // Open arc of 3/4 of the circle.
                let k = 3 * n / 4;
                (pts[..k].to_vec(), FitOptions::default())
            };
            let s = BSpline3::fit(&pts, &opts).unwrap();
            let mut worst: f64 = 0.0;
            for (i, (&u, p)) in s.params().iter().zip(&pts).enumerate() {
                if !closed && (i < 4 || i + 4 >= pts.len()) {
                    continue; // end effects
                }
                let t_true = DVec3::new(-p.y, p.x, 0.0).normalize();
                let t = s.tangent(u);
                worst = worst.max(t.dot(t_true).clamp(-1.0, 1.0).acos());
            }
            let bound = 40.0 / (n * n) as f64;
            assert!(worst < bound, "n {n} closed {closed}: {worst} >= {bound}");
            if closed {
                assert!(worst < prev);
                prev = worst;
            }
        }
    }
}

#[test]
fn circle_tangent_better_than_finite_differences_under_noise() {
    let r = 30.0;
    let n = 200; // spacing ~0.94
    let sigma = 0.1;
    let pts = noisy_circle(n, r, sigma, 11);
    let s = BSpline3::fit(&pts, &closed_opts(None, 1e-3)).unwrap();
    let (mut err_fit, mut err_fd) = (0.0, 0.0);
    for i in 0..n {
        let p = pts[i];
        let t_true = DVec3::new(-p.y, p.x, 0.0).normalize();
        let fd = (pts[(i + 1) % n] - pts[(i + n - 1) % n]).normalize();
        err_fd += fd.dot(t_true).clamp(-1.0, 1.0).acos();
        err_fit += s.tangent(s.params()[i]).dot(t_true).clamp(-1.0, 1.0).acos();
    }
    assert!(
        err_fit * 3.0 < err_fd,
        "fit {err_fit} vs finite differences {err_fd}"
    );
}

#[test]
fn fit_reduces_noise() {
    let r = 20.0;
    let n = 150;
    let sigma = 0.2;
    let pts = noisy_circle(n, r, sigma, 5);
    let dist_circle = |p: DVec3| ((p.x.hypot(p.y) - r).powi(2) + p.z * p.z).sqrt();
    let noisy: f64 = pts.iter().map(|&p| dist_circle(p)).sum::<f64>() / n as f64;
    for closed in [true, false] {
        let opts = FitOptions {
            closed,
            ..FitOptions::default()
        };
        let s = BSpline3::fit(&pts, &opts).unwrap();
        let mut fitted = 0.0;
        let mut count = 0;
        for (i, &u) in s.params().iter().enumerate() {
            if !closed && (i < 5 || i + 5 >= n) {
                continue;
            }
            fitted += dist_circle(s.eval(u));
            count += 1;
        }
        fitted /= count as f64;
        assert!(fitted < 0.5 * noisy, "closed {closed}: {fitted} vs {noisy}");
    }
}

#[test]
fn smoothing_increases_smoothness() {
    let pts = noisy_circle(80, 5.0, 0.1, 9);
    let roughness = |s: &BSpline3| -> f64 {
        (0..400)
            .map(|i| s.second_derivative(i as f64 / 400.0).length_squared())
            .sum()
    };
    let mut prev = f64::INFINITY;
    for lam in [0.0, 1e-2, 1.0, 100.0] {
        let s = BSpline3::fit(&pts, &closed_opts(Some(40), lam)).unwrap();
        let r = roughness(&s);
        assert!(r < prev, "lambda {lam}: {r} >= {prev}");
        prev = r;
    }
}

#[test]
fn closest_param_finds_projection() {
    let pts = circle(64, 3.0);
    let s = BSpline3::fit(&pts, &closed_opts(None, 1e-3)).unwrap();
    for i in 0..37 {
        let a = i as f64 / 37.0 * TAU + 0.01;
        let q = DVec3::new(3.5 * a.cos(), 3.5 * a.sin(), 0.2);
        let u = s.closest_param(q);
        let c = s.eval(u);
        // Optimality: the residual is orthogonal to the tangent.
        let g = (c - q).dot(s.tangent(u));
        assert!(g.abs() < 1e-8, "gradient {g}");
        // And it is the global minimum of a dense sampling.
        let best = (0..5000)
            .map(|k| s.eval(k as f64 / 5000.0).distance(q))
            .fold(f64::INFINITY, f64::min);
        assert!(c.distance(q) <= best + 1e-9);
    }
    // Open curve: a point beyond the end projects to the end.
    let arc: Vec<DVec3> = pts[..30].to_vec();
    let s = BSpline3::fit(&arc, &FitOptions::default()).unwrap();
    let beyond = arc[0] + (arc[0] - arc[1]) * 5.0;
    assert_eq!(s.closest_param(beyond), 0.0);
    // Newton from each data parameter recovers (approximately) the data parameters on exact
    // data.
    for (&u, &p) in s.params().iter().zip(&arc) {
        let v = s.closest_param_from(p, u);
        assert!((v - u).abs() < 1e-3);
        assert!(s.eval(v).distance(p) <= s.eval(u).distance(p) + 1e-15);
    }
}

#[test]
fn params_are_chord_or_centripetal() {
    let pts = vec![
        DVec3::ZERO,
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 4.0, 0.0),
        DVec3::new(1.0, 4.0, 9.0),
    ];
    let u = data_params(&pts, false, Parametrization::ChordLength).unwrap();
    let expect = [0.0, 1.0 / 14.0, 5.0 / 14.0, 1.0];
    for (a, b) in u.iter().zip(expect) {
        assert!((a - b).abs() < 1e-15);
    }
    let u = data_params(&pts, false, Parametrization::Centripetal).unwrap();
    let expect = [0.0, 1.0 / 6.0, 3.0 / 6.0, 1.0];
    for (a, b) in u.iter().zip(expect) {
        assert!((a - b).abs() < 1e-15);
    }
    // Closed: the closing chord |(1,4,9)| = sqrt(98) counts.
    let u = data_params(&pts, true, Parametrization::ChordLength).unwrap();
    let total = 14.0 + 98f64.sqrt();
    assert!((u[3] - 5.0 / total).abs() < 1e-15 || (u[3] - 14.0 / total).abs() < 1e-15);
    assert!((u[3] - 14.0 / total).abs() < 1e-15);
    let s = BSpline3::fit(&pts, &FitOptions::default()).unwrap();
    assert_eq!(s.params().len(), 4);
    assert_eq!(s.domain(), (0.0, 1.0));
}

#[test]
fn errors_are_reported() {
    let o = FitOptions::default();
    let three = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    assert_eq!(
        BSpline3::fit(&three, &o),
        Err(BSplineError::TooFewPoints { got: 3, need: 4 })
    );
    let mut pts = circle(10, 1.0);
    pts[4].y = f64::NAN;
    assert!(matches!(
        BSpline3::fit(&pts, &o),
        Err(BSplineError::NonFinite { index: 4, .. })
    ));
    let mut pts = circle(10, 1.0);
    pts[6] = pts[5];
    assert_eq!(
        BSpline3::fit(&pts, &o),
        Err(BSplineError::CoincidentPoints { index: 6, prev: 5 })
    );
    let mut pts = circle(10, 1.0);
    pts.push(pts[0]);
    assert!(BSpline3::fit(&pts, &o).is_ok()); // open: fine
    assert_eq!(
        BSpline3::fit(&pts, &closed_opts(None, 1e-3)),
        Err(BSplineError::CoincidentPoints { index: 0, prev: 10 })
    );
    let (dd, idx) = dedup_consecutive(&pts, 1e-12, true);
    assert_eq!(dd.len(), 10);
    assert_eq!(idx, (0..10).collect::<Vec<_>>());
    assert!(BSpline3::fit(&dd, &closed_opts(None, 1e-3)).is_ok());
    let pts = circle(10, 1.0);
    let mut invalid: Vec<FitOptions> = [3, 11]
        .map(|bad| FitOptions {
            n_control: Some(bad),
            ..o.clone()
        })
        .to_vec();
    for bad in [-1.0, f64::NAN] {
        invalid.push(FitOptions {
            smoothing: bad,
            ..o.clone()
        });
        invalid.push(FitOptions {
            control_spacing: Some(bad),
            ..o.clone()
        });
    }
    for opts in &invalid {
        assert!(
            matches!(
                BSpline3::fit(&pts, opts),
                Err(BSplineError::InvalidOption(_))
            ),
            "{opts:?}"
        );
    }
    let us = vec![0.0, 0.5, 0.4, 0.6, 0.7, 0.8, 0.9, 0.95, 0.97, 1.0];
    assert!(matches!(
        BSpline3::fit_with_params(&pts, &us, &o),
        Err(BSplineError::InvalidParams(_))
    ));
    let us: Vec<f64> = (0..10).map(|i| i as f64 / 9.0).collect();
    assert!(matches!(
        BSpline3::fit_with_params(&pts, &us, &closed_opts(None, 0.0)),
        Err(BSplineError::InvalidParams(_))
    ));
    // All parameters crowded in one span with no smoothing -> singular, reported.
    let us: Vec<f64> = (0..10).map(|i| 0.001 * i as f64).collect();
    let opts = FitOptions {
        closed: true,
        n_control: Some(10),
        smoothing: 0.0,
        ..o.clone()
    };
    assert!(matches!(
        BSpline3::fit_with_params(&pts, &us, &opts),
        Err(BSplineError::Singular { .. })
    ));
}

fn arb_curve() -> impl Strategy<Value = (Vec<DVec3>, bool)> {
    (
        prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), 3),
        8usize..60,
        any::<bool>(),
        any::<u64>(),
    )
        .prop_map(|(coef, n, closed, seed)| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let c: Vec<DVec3> = coef.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            let pts = (0..n)
                .map(|i| {
                    let a = i as f64 / n as f64 * TAU;
                    DVec3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0)
                        + c[0] * (2.0 * a).sin()
                        + c[1] * (3.0 * a).cos()
                        + 0.02 * c[2] * gauss(&mut rng)
                })
                .collect();
            (pts, closed)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn derivatives_match_finite_differences((pts, closed) in arb_curve(), lam in 0.0f64..0.1) {
        let opts = FitOptions { closed, smoothing: lam, ..FitOptions::default() };
        let s = BSpline3::fit(&pts, &opts).unwrap();
        let h = 1e-6;
        let scale = s.control_points().iter().map(|p| p.length()).fold(1.0, f64::max);
        for i in 1..50 {
            let u = i as f64 / 50.0 + 0.003;
            let fd1 = (s.eval(u + h) - s.eval(u - h)) / (2.0 * h);
            let fd2 = (s.derivative(u + h) - s.derivative(u - h)) / (2.0 * h);
            let d1 = s.derivative(u);
            let d2 = s.second_derivative(u);
            prop_assert!((fd1 - d1).length() < 1e-5 * scale * (1.0 + d1.length()), "u {} {} {}", u, fd1, d1);
            prop_assert!((fd2 - d2).length() < 1e-4 * scale * (1.0 + d2.length()), "u {} {} {}", u, fd2, d2);
        }
    }

    #[test]
    fn fit_is_invariant_under_rigid_motion(
        (pts, closed) in arb_curve(),
        axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
        angle in -3.0f64..3.0,
        shift in (-50.0f64..50.0, -50.0f64..50.0, -50.0f64..50.0),
        centripetal in any::<bool>(),
    ) {
        let q = DQuat::from_axis_angle(DVec3::new(axis.0, axis.1, axis.2).normalize(), angle);
        let t = DVec3::new(shift.0, shift.1, shift.2);
        let moved: Vec<DVec3> = pts.iter().map(|&p| q * p + t).collect();
        let parametrization = if centripetal { Parametrization::Centripetal } else { Parametrization::ChordLength };
        let opts = FitOptions { closed, parametrization, ..FitOptions::default() };
        let a = BSpline3::fit(&pts, &opts).unwrap();
        let b = BSpline3::fit(&moved, &opts).unwrap();
        prop_assert_eq!(a.control_points().len(), b.control_points().len());
        for (ua, ub) in a.params().iter().zip(b.params()) {
            prop_assert!((ua - ub).abs() < 1e-12);
        }
        for i in 0..=40 {
            let u = i as f64 / 40.0;
            prop_assert!((q * a.eval(u) + t - b.eval(u)).length() < 1e-9);
            prop_assert!((q * a.derivative(u) - b.derivative(u)).length() < 1e-8);
        }
    }
}

#[test]
fn parametrization_names_round_trip() {
    testsupport::check_choice_error::<bspline::Parametrization>("uniform", |e| {
        matches!(e, bspline::BSplineError::UnknownChoice(_))
    });
}
