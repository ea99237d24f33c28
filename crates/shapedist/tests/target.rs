//! The generic ICP loop on its targets: a rigid copy is recovered (point sets, mesh surfaces),
//! gates and trimming, option errors.

mod common;

use common::*;
use meshcore::linalg::rigid_inverse;
use meshcore::{FaceLocator, TriMesh};
use proptest::prelude::*;
use shapedist::glam::{DAffine3, DVec3};
use shapedist::*;

/// An ellipsoid (no continuous symmetry, so small motions are identifiable).
fn ellipsoid() -> TriMesh {
    let m = meshcore::shapes::icosphere(3);
    let (pos, tri) = m.into_parts();
    let pos = pos
        .into_iter()
        .map(|p| p * DVec3::new(3.0, 2.0, 1.2))
        .collect();
    TriMesh::new(pos, tri).unwrap()
}

fn motion_from(seed: u64, deg: f64, shift: f64) -> DAffine3 {
    let mut r = rng(seed);
    let rot = rotation_by(&mut r, deg);
    let t = random_cloud(&mut r, 1, shift)[0];
    DAffine3::from_mat3_translation(rot, t)
}

fn err(a: &DAffine3, b: &DAffine3) -> (f64, f64) {
    (
        angle_deg(a.matrix3, b.matrix3),
        (a.translation - b.translation).length(),
    )
}

fn opts(variant: IcpVariant) -> IcpLoopOptions {
    IcpLoopOptions {
        variant,
        max_iterations: 200,
        translation: true,
        convergence: Convergence::RelativeRmse { tolerance: 0.0 },
        ..IcpLoopOptions::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn a_rigid_copy_of_a_point_set_is_recovered(
        seed in 0u64..1000,
        deg in 0.0..12.0f64,
        plane in proptest::bool::ANY,
    ) {
        let mut r = rng(seed);
        let pts = patch(&mut r, 800, seed);
        let a = prepared(&pts, Which::A);
        let m = motion_from(seed + 1, deg, 0.05);
        // Source = m^-1 applied to the (centred) target points: ICP must find m.
        let inv = rigid_inverse(&m);
        let src: Vec<DVec3> = a.points().iter().map(|p| inv.transform_point3(*p)).collect();
        let variant = if plane { IcpVariant::PointToPlane } else { IcpVariant::PointToPoint };
        let res = icp_to_target(&a, &src, None, DAffine3::IDENTITY, &opts(variant)).unwrap();
        let (da, dt) = err(&res.motion, &m);
        prop_assert!(da < 1e-5 && dt < 1e-6, "{da} deg, {dt}; {res:?}");
        prop_assert!(res.rmse < 1e-6);
    }

    #[test]
    fn a_rigid_copy_of_a_mesh_surface_is_recovered(
        seed in 0u64..1000,
        deg in 0.0..10.0f64,
        plane in proptest::bool::ANY,
    ) {
        let mesh = ellipsoid();
        let loc = FaceLocator::new(&mesh);
        let m = motion_from(seed, deg, 0.1);
        let inv = rigid_inverse(&m);
        let src: Vec<DVec3> = mesh
            .positions()
            .iter()
            .step_by(3)
            .map(|p| inv.transform_point3(*p))
            .collect();
        let variant = if plane { IcpVariant::PointToPlane } else { IcpVariant::PointToPoint };
        let res = icp_to_target(&loc, &src, None, DAffine3::IDENTITY, &opts(variant)).unwrap();
        // Point-to-point slides slowly along the surface (linear convergence): within 200
        // iterations it is within 1e-3 degrees; point-to-plane is exact to 1e-6.
        let (da, dt) = err(&res.motion, &m);
        let tol = if plane { 1e-6 } else { 1e-3 };
        prop_assert!(da < tol && dt < tol, "{da} deg, {dt}; {res:?}");
    }
}

#[test]
fn icp_on_a_prepared_set_equals_the_loop_on_it() {
    // `icp` is the loop with `IcpOptions::loop_options` on B's points in tree leaf order.
    let mut r = rng(3);
    let pts = patch(&mut r, 1200, 3);
    let a = prepared(&pts, Which::A);
    let m = motion_from(4, 8.0, 0.0);
    let moved: Vec<DVec3> = pts.iter().map(|p| m.transform_point3(*p)).collect();
    let b = prepared(&moved, Which::B);
    let o = IcpOptions {
        trim: 0.1,
        ..IcpOptions::default()
    };
    let direct = icp(&a, &b, meshcore::DMat3::IDENTITY, &o).unwrap();
    let src = b.point_tree().leaf_order_points();
    let looped = icp_to_target(&a, src, None, DAffine3::IDENTITY, &o.loop_options()).unwrap();
    assert_eq!(direct, looped);
}

#[test]
fn gates_and_trimming_drop_outliers() {
    let mesh = ellipsoid();
    let loc = FaceLocator::new(&mesh);
    let m = motion_from(9, 5.0, 0.05);
    let inv = rigid_inverse(&m);
    let mut src: Vec<DVec3> = mesh
        .positions()
        .iter()
        .step_by(2)
        .map(|p| inv.transform_point3(*p))
        .collect();
    // 5 % of the points far off the surface.
    let n_out = src.len() / 20;
    for (k, p) in src.iter_mut().take(n_out).enumerate() {
        *p += DVec3::new(0.0, 0.0, 4.0 + k as f64 * 0.01);
    }
    let plain = icp_to_target(
        &loc,
        &src,
        None,
        DAffine3::IDENTITY,
        &opts(IcpVariant::PointToPoint),
    )
    .unwrap();
    assert!(
        err(&plain.motion, &m).0 > 0.1,
        "outliers must pull the plain fit"
    );
    for o in [
        IcpLoopOptions {
            max_distance: Some(1.0),
            ..opts(IcpVariant::PointToPoint)
        },
        IcpLoopOptions {
            trim: 0.1,
            trim_rounding: TrimRounding::Down,
            ..opts(IcpVariant::PointToPoint)
        },
    ] {
        // Point-to-point converges slowly along the surface: 200 iterations bring it within
        // 0.01 degrees, far closer than the plain fit.
        let res = icp_to_target(&loc, &src, None, DAffine3::IDENTITY, &o).unwrap();
        let (da, dt) = err(&res.motion, &m);
        assert!(da < 1e-2 && dt < 1e-3, "{da} {dt} {o:?}");
    }
}

#[test]
fn invalid_options_and_targets_are_errors() {
    let mesh = ellipsoid();
    let loc = FaceLocator::new(&mesh);
    let src = mesh.positions().to_vec();
    let id = DAffine3::IDENTITY;
    let bad = [
        IcpLoopOptions {
            trim: 0.95,
            ..IcpLoopOptions::default()
        },
        IcpLoopOptions {
            max_iterations: 0,
            ..IcpLoopOptions::default()
        },
        IcpLoopOptions {
            min_normal_dot: Some(0.5),
            ..IcpLoopOptions::default()
        },
        IcpLoopOptions {
            max_distance: Some(f64::NAN),
            ..IcpLoopOptions::default()
        },
    ];
    for o in bad {
        assert!(matches!(
            icp_to_target(&loc, &src, None, id, &o),
            Err(ShapeDistError::InvalidOption(_))
        ));
    }
    let far = DAffine3::from_scale(DVec3::splat(f64::MAX));
    assert!(matches!(
        icp_to_target(&loc, &src, None, far, &IcpLoopOptions::default()),
        Err(ShapeDistError::Mesh(_))
    ));
}
