//! Facial curves: level curves of the geodesic distance from a pole, invariant under rigid
//! motion and vertex renumbering, on an analytic mesh and on a face of the paper set.

mod common;

use common::{ellipsoid, moved_and_renumbered};
use facecurves::{
    describe_facial_curves, describe_facial_curves_from, facial_curves_distance, Aggregate,
    ElasticOptions, FaceCurvesError, FacialCurvesDescriptor, FacialCurvesOptions,
};
use geodesic::{new_solver, Method, Source};
use glam::DVec3;
use meshcore::{Surface, TriMesh};

fn top_vertex(mesh: &TriMesh, dir: DVec3) -> u32 {
    (0..mesh.n_vertices() as u32)
        .max_by(|&a, &b| {
            mesh.position(a)
                .dot(dir)
                .total_cmp(&mesh.position(b).dot(dir))
        })
        .unwrap()
}

fn describe(mesh: &TriMesh, pole: u32, opts: &FacialCurvesOptions) -> FacialCurvesDescriptor {
    let s = Surface::new(mesh.clone());
    let solver = new_solver(mesh, Method::Exact).unwrap();
    describe_facial_curves_from(&s, solver.as_ref(), Source::Vertex(pole), opts).unwrap()
}

/// The facial curves of `mesh` from `pole`, and those of its moved and renumbered copy
/// ([`moved_and_renumbered`] with `seed`) from the same vertex.
fn with_moved_copy(
    mesh: &TriMesh,
    pole: u32,
    opts: &FacialCurvesOptions,
    seed: u64,
) -> (FacialCurvesDescriptor, FacialCurvesDescriptor) {
    let (moved, perm) = moved_and_renumbered(mesh, seed);
    let a = describe(mesh, pole, opts);
    (a, describe(&moved, perm[pole as usize], opts))
}

fn curve_length(points: &[DVec3], closed: bool) -> f64 {
    let n = points.len();
    let segs = if closed { n } else { n - 1 };
    (0..segs)
        .map(|s| (points[(s + 1) % n] - points[s]).length())
        .sum()
}

#[test]
fn ellipsoid_curves_are_invariant_under_rigid_motion_and_renumbering() {
    let axes = DVec3::new(3.0, 2.0, 1.5);
    let mesh = ellipsoid(axes, 4);
    let pole = top_vertex(&mesh, DVec3::Z);
    let opts = FacialCurvesOptions {
        step: 0.3,
        levels: 6,
    };
    let (a, b) = with_moved_copy(&mesh, pole, &opts, 3);
    assert_eq!(a.curves.len(), 6);
    assert_eq!(b.curves.len(), 6);
    for (x, y) in a.curves.iter().zip(&b.curves) {
        assert!(x.closed && y.closed);
        let (lx, ly) = (curve_length(&x.points, true), curve_length(&y.points, true));
        assert!(
            (lx - ly).abs() < 1e-9 * lx,
            "level {}: {lx} vs {ly}",
            x.level
        );
    }
    let el = ElasticOptions::default();
    let same = facial_curves_distance(&a, &b, Aggregate::RootSumSquare, &el).unwrap();
    let scale = a
        .curves
        .iter()
        .map(|c| curve_length(&c.points, c.closed))
        .sum::<f64>()
        .sqrt();
    assert!(same.distance < 0.01 * scale, "{} vs {scale}", same.distance);
    assert_eq!(same.unmatched, 0);
    // A different ellipsoid is far.
    let other = ellipsoid(DVec3::new(2.2, 2.0, 1.5), 4);
    let c = describe(&other, top_vertex(&other, DVec3::Z), &opts);
    let diff = facial_curves_distance(&a, &c, Aggregate::RootSumSquare, &el).unwrap();
    assert!(
        diff.distance > 10.0 * same.distance,
        "{} vs {}",
        diff.distance,
        same.distance
    );
    // The sum is at least the root sum of squares.
    let sum = facial_curves_distance(&a, &c, Aggregate::Sum, &el).unwrap();
    assert!(sum.distance >= diff.distance);
}

#[test]
fn levels_beyond_the_surface_are_missing_and_errors_are_named() {
    let mesh = ellipsoid(DVec3::new(1.0, 1.0, 1.0), 3);
    let s = Surface::new(mesh.clone());
    let pole = top_vertex(&mesh, DVec3::Z);
    // The farthest point is at pi: levels beyond it are absent.
    let d = describe(
        &mesh,
        pole,
        &FacialCurvesOptions {
            step: 0.5,
            levels: 8,
        },
    );
    assert!(
        d.curves.len() == 6,
        "{:?}",
        d.curves.iter().map(|c| c.level).collect::<Vec<_>>()
    );
    let e = describe_facial_curves(
        &s,
        &[0.0; 3],
        &FacialCurvesOptions {
            step: 0.5,
            levels: 2,
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, FaceCurvesError::VertexCount { what: "field", .. }),
        "{e}"
    );
    let mut f = vec![1.0; mesh.n_vertices()];
    f[7] = f64::NAN;
    let e = describe_facial_curves(
        &s,
        &f,
        &FacialCurvesOptions {
            step: 0.5,
            levels: 2,
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, FaceCurvesError::NonFiniteField { vertex: 7, .. }),
        "{e}"
    );
    let e = describe_facial_curves(
        &s,
        &f,
        &FacialCurvesOptions {
            step: -1.0,
            levels: 2,
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("step"), "{e}");
    let far = vec![10.0; mesh.n_vertices()];
    let e = describe_facial_curves(
        &s,
        &far,
        &FacialCurvesOptions {
            step: 0.5,
            levels: 2,
        },
    )
    .unwrap_err();
    assert!(matches!(e, FaceCurvesError::NoCurves(_)), "{e}");
}

#[test]
fn face_curves_are_invariant_under_rigid_motion_and_renumbering() {
    let Some([mesh, other]) = testsupport::paper_meshes(["id1_neutral.obj", "id2_neutral.obj"])
    else {
        return;
    };
    const NOSE: u32 = 4857;
    // ICT faces are in cm: 8 curves 0.6 cm apart.
    let opts = FacialCurvesOptions {
        step: 0.6,
        levels: 8,
    };
    let (a, b) = with_moved_copy(&mesh, NOSE, &opts, 9);
    let c = describe(&other, NOSE, &opts);
    assert_eq!(a.curves.len(), 8);
    assert_eq!(
        a.curves
            .iter()
            .map(|c| (c.level, c.closed, c.pieces))
            .collect::<Vec<_>>(),
        b.curves
            .iter()
            .map(|c| (c.level, c.closed, c.pieces))
            .collect::<Vec<_>>()
    );
    let el = ElasticOptions::default();
    let same = facial_curves_distance(&a, &b, Aggregate::RootSumSquare, &el).unwrap();
    let diff = facial_curves_distance(&a, &c, Aggregate::RootSumSquare, &el).unwrap();
    assert!(
        same.distance < 0.05 * diff.distance,
        "moved copy {} vs other person {}",
        same.distance,
        diff.distance
    );
}
