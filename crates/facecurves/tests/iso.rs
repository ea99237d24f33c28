//! Iso-curvature curves on analytic surfaces (constant curvatures of a sphere and a
//! cylinder, the known curvatures of an ellipsoid) and their invariance under rigid motion
//! and vertex renumbering.

mod common;

use common::{ellipsoid, ellipsoid_curvatures, moved_and_renumbered, project_to_ellipsoid};
use facecurves::{
    describe_iso_curvature, iso_curvature_distance, principal_curvature_fields, FaceCurvesError,
    IsoCurvatureOptions, IsoLevels, PrincipalField,
};
use glam::DVec3;
use meshcore::{Surface, TriMesh};
use testsupport::shapes;

fn scaled(mesh: &TriMesh, s: DVec3) -> TriMesh {
    let p = mesh.positions().iter().map(|p| *p * s).collect();
    TriMesh::new(p, mesh.triangles().to_vec()).unwrap()
}

fn explicit(k1: Vec<f64>, k2: Vec<f64>) -> IsoCurvatureOptions {
    IsoCurvatureOptions {
        levels: IsoLevels::Explicit { k1, k2 },
        ..Default::default()
    }
}

#[test]
fn sphere_curvatures_are_constant_and_no_other_level_is_crossed() {
    let r = 2.0;
    let s = Surface::new(scaled(&shapes::icosphere(4), DVec3::splat(r)));
    let (k1, k2, _) = principal_curvature_fields(&s, &Default::default()).unwrap();
    for v in 0..s.mesh().n_vertices() {
        for k in [k1[v], k2[v]] {
            assert!((k - 1.0 / r).abs() < 0.01 / r, "vertex {v}: {k}");
        }
    }
    // Levels away from 1 / r cross nothing: the network is empty, an error.
    let e =
        describe_iso_curvature(&s, None, &explicit(vec![0.4, 0.6], vec![0.4, 0.6])).unwrap_err();
    assert!(matches!(e, FaceCurvesError::NoCurves(_)), "{e}");
}

#[test]
fn cylinder_curvatures_are_one_over_r_and_zero() {
    let r = 1.5;
    let h = 6.0;
    let s = Surface::new(shapes::cylinder(r, h, 64, 48));
    let opts = IsoCurvatureOptions::default();
    let (k1, k2, radius) = principal_curvature_fields(&s, &opts).unwrap();
    // Away from the borders (one-sided fits there); within 2 % (64 chords around).
    let margin = 2.0 * radius;
    let pos = s.mesh().positions();
    let interior: Vec<bool> = pos
        .iter()
        .map(|p| p.z > margin && p.z < h - margin)
        .collect();
    for v in (0..pos.len()).filter(|&v| interior[v]) {
        assert!((k1[v] - 1.0 / r).abs() < 0.02 / r, "k1 at {v}: {}", k1[v]);
        assert!(k2[v].abs() < 0.02 / r, "k2 at {v}: {}", k2[v]);
    }
    // On the interior, levels other than 1 / r (k1) and 0 (k2) cross nothing.
    let e = describe_iso_curvature(
        &s,
        Some(&interior),
        &explicit(vec![0.5 / r, 1.5 / r], vec![-0.5 / r, 0.5 / r]),
    )
    .unwrap_err();
    assert!(matches!(e, FaceCurvesError::NoCurves(_)), "{e}");
}

#[test]
fn ellipsoid_level_sets_follow_the_analytic_curvatures() {
    let axes = DVec3::new(3.0, 2.0, 1.5);
    let s = Surface::new(ellipsoid(axes, 5));
    // Levels inside the analytic ranges: k1 in [a/c^2.. ] etc. computed at the vertices.
    let pos = s.mesh().positions();
    let exact: Vec<(f64, f64)> = pos
        .iter()
        .map(|p| ellipsoid_curvatures(axes, project_to_ellipsoid(axes, *p)))
        .collect();
    let (k1min, k1max) = exact
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), k| (a.min(k.0), b.max(k.0)));
    let (k2min, k2max) = exact
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), k| (a.min(k.1), b.max(k.1)));
    let lv = |lo: f64, hi: f64| (1..=4).map(|i| lo + (hi - lo) * i as f64 / 5.0).collect();
    let opts = explicit(lv(k1min, k1max), lv(k2min, k2max));
    let d = describe_iso_curvature(&s, None, &opts).unwrap();
    // Vertex curvatures against the analytic ones (relative to the largest curvature).
    let kmax = k1max;
    let mut worst: f64 = 0.0;
    for (v, &(e1, e2)) in exact.iter().enumerate() {
        worst = worst
            .max((d.k1[v] - e1).abs() / kmax)
            .max((d.k2[v] - e2).abs() / kmax);
    }
    assert!(
        worst < 0.02,
        "worst vertex curvature error {worst} of k_max"
    );
    // Every curve point lies where the analytic field has the curve's level.
    let mut counts = [0usize; 2];
    for c in &d.curves {
        counts[(c.field == PrincipalField::K2) as usize] += 1;
        for p in &c.points {
            let (e1, e2) = ellipsoid_curvatures(axes, project_to_ellipsoid(axes, *p));
            let e = if c.field == PrincipalField::K1 {
                e1
            } else {
                e2
            };
            assert!(
                (e - c.level).abs() < 0.03 * kmax,
                "{:?} level {} at {p}: analytic {e}",
                c.field,
                c.level
            );
        }
    }
    assert!(
        counts[0] >= 4 && counts[1] >= 4,
        "curves per field {counts:?}"
    );
}

#[test]
fn network_is_invariant_under_rigid_motion_and_renumbering() {
    let axes = DVec3::new(3.0, 2.0, 1.5);
    let mesh = ellipsoid(axes, 4);
    let (moved, _) = moved_and_renumbered(&mesh, 11);
    let a = describe_iso_curvature(&Surface::new(mesh), None, &Default::default()).unwrap();
    let b = describe_iso_curvature(&Surface::new(moved), None, &Default::default()).unwrap();
    assert_eq!(a.curves.len(), b.curves.len());
    for (x, y) in a.levels_k1.iter().zip(&b.levels_k1) {
        assert!((x - y).abs() < 1e-9 * x.abs().max(1.0), "{x} vs {y}");
    }
    let d = iso_curvature_distance(&a, &b, &Default::default()).unwrap();
    assert!(d.stats.rms_normalised < 1e-6, "{:?}", d.stats);
    // Another ellipsoid is farther.
    let other = describe_iso_curvature(
        &Surface::new(ellipsoid(DVec3::new(3.0, 1.6, 1.5), 4)),
        None,
        &Default::default(),
    )
    .unwrap();
    let e = iso_curvature_distance(&a, &other, &Default::default()).unwrap();
    assert!(e.stats.rms_normalised > 0.01, "{:?}", e.stats);
}

#[test]
fn face_network_is_invariant_under_rigid_motion_and_renumbering() {
    let Some([mesh, o_mesh]) = testsupport::paper_meshes(["id1_neutral.obj", "id2_neutral.obj"])
    else {
        return;
    };
    let (moved, perm) = moved_and_renumbered(&mesh, 5);
    // Central part: within 5 cm (ICT faces are in cm) of the nose tip (vertex 4857).
    let nose = mesh.position(4857);
    let mask: Vec<bool> = mesh
        .positions()
        .iter()
        .map(|p| (*p - nose).length() < 5.0)
        .collect();
    let mut mask_moved = vec![false; mask.len()];
    for (old, &new) in perm.iter().enumerate() {
        mask_moved[new as usize] = mask[old];
    }
    let a = describe_iso_curvature(&Surface::new(mesh), Some(&mask), &Default::default()).unwrap();
    let same = explicit(a.levels_k1.clone(), a.levels_k2.clone());
    let b = describe_iso_curvature(&Surface::new(moved), Some(&mask_moved), &same).unwrap();
    let o_mask: Vec<bool> = o_mesh
        .positions()
        .iter()
        .map(|p| (*p - o_mesh.position(4857)).length() < 5.0)
        .collect();
    let c = describe_iso_curvature(&Surface::new(o_mesh), Some(&o_mask), &same).unwrap();
    assert_eq!(a.curves.len(), b.curves.len());
    let d_same = iso_curvature_distance(&a, &b, &Default::default()).unwrap();
    let d_other = iso_curvature_distance(&a, &c, &Default::default()).unwrap();
    assert!(
        d_same.stats.rms_normalised < 1e-6,
        "moved copy: {:?}",
        d_same.stats
    );
    assert!(
        d_other.stats.rms_normalised > 100.0 * d_same.stats.rms_normalised,
        "{:?}",
        d_other.stats
    );
}
