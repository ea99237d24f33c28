//! The descriptor against analytic oracles (plane: law of cosines; sphere: spherical law of
//! cosines), invariances, holes, errors and file round trips.

use bipolar::{
    describe, BipolarError, Descriptor, DescriptorOptions, Fields, LevelSpec, SelectionRule,
    Source, TangentMethod,
};
use glam::{DAffine3, DQuat, DVec3};
use meshcore::{Surface, TriMesh};
use proptest::prelude::*;
use testsupport::fields::{euclidean, sphere_geodesic};
use testsupport::nearest_vertex;
use testsupport::shapes::{grid_plane, icosphere};

/// The descriptor of precomputed `fields` (of the `references`, if given).
fn describe_fields(
    surface: &Surface,
    fields: &[Vec<f64>],
    references: Option<&[Source]>,
    o: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    describe(surface, Fields::Precomputed { fields, references }, o)
}

/// The descriptor of the fields `solver` computes from the `references`.
fn describe_solved(
    surface: &Surface,
    solver: &dyn geodesic::GeodesicSolver,
    references: &[Source],
    o: &DescriptorOptions,
) -> Result<Descriptor, BipolarError> {
    describe(surface, Fields::Solve { solver, references }, o)
}

/// Options with every intersection kept and gradient tangents.
fn all_gradient(levels: LevelSpec) -> DescriptorOptions {
    opts(SelectionRule::All, TangentMethod::Gradient, levels)
}

fn opts(rule: SelectionRule, tangent: TangentMethod, levels: LevelSpec) -> DescriptorOptions {
    DescriptorOptions {
        levels,
        rule,
        tangent,
        ..DescriptorOptions::default()
    }
}

/// A surface, exact distance fields from its reference vertices and the references' positions.
struct Setup {
    mesh: TriMesh,
    surface: Surface,
    fields: Vec<Vec<f64>>,
    refs: Vec<Source>,
    poles: Vec<DVec3>,
}

impl Setup {
    /// `field(mesh, position)` from each of the vertices `refs`.
    fn new(mesh: TriMesh, refs: &[u32], field: impl Fn(&TriMesh, DVec3) -> Vec<f64>) -> Self {
        let poles: Vec<DVec3> = refs.iter().map(|&v| mesh.position(v)).collect();
        Setup {
            surface: Surface::new(mesh.clone()),
            fields: poles.iter().map(|&p| field(&mesh, p)).collect(),
            refs: refs.iter().map(|&v| Source::Vertex(v)).collect(),
            poles,
            mesh,
        }
    }

    /// The descriptor of the fields, with their references.
    fn describe(&self, o: &DescriptorOptions) -> Result<Descriptor, BipolarError> {
        describe_fields(&self.surface, &self.fields, Some(&self.refs), o)
    }
}

/// Plane grid on [-1.5, 1.5]^2 with `n` cells a side, references at the vertices nearest to
/// (-0.5, 0) and (0.5, 0) (no jitter there), exact Euclidean fields.
fn plane_setup(n: usize, jitter: f64) -> Setup {
    let h = 3.0 / n as f64;
    let mesh = grid_plane(n, h, -1.5, jitter, 5, |_| false);
    let refs = [
        nearest_vertex(&mesh, DVec3::new(-0.5, 0.0, 0.0)),
        nearest_vertex(&mesh, DVec3::new(0.5, 0.0, 0.0)),
    ];
    Setup::new(mesh, &refs, euclidean)
}

/// Great-circle fields on the unit sphere `mesh` from the vertices `refs`.
fn sphere_setup(mesh: TriMesh, refs: &[u32]) -> Setup {
    Setup::new(mesh, refs, |m, c| sphere_geodesic(m, c, 1.0))
}

fn law_of_cosines(p: DVec3, r: DVec3, q: DVec3) -> f64 {
    let (a, b, d) = ((p - r).length(), (p - q).length(), (r - q).length());
    (a * a + b * b - d * d) / (2.0 * a * b)
}

#[test]
fn linear_fields_give_exact_angles_and_positions() {
    // PL interpolation of affine fields is exact: cos must match to rounding.
    let mesh = grid_plane(30, 0.1, -1.5, 0.3, 9, |_| false);
    let surface = Surface::new(mesh.clone());
    let e1 = DVec3::new(1.0, 0.0, 0.0);
    let e2 = DVec3::new(0.6, 0.8, 0.0);
    let fa: Vec<f64> = mesh.positions().iter().map(|p| p.dot(e1) + 2.0).collect();
    let fb: Vec<f64> = mesh.positions().iter().map(|p| p.dot(e2) + 2.5).collect();
    let o = all_gradient(LevelSpec::Step(0.25));
    let d = describe_fields(&surface, &[fa, fb], None, &o).unwrap();
    assert!(d.len() > 100);
    for p in &d.points {
        assert!((p.cos - e1.dot(e2)).abs() < 1e-12, "cos {}", p.cos);
        assert!((p.position.dot(e1) + 2.0 - p.key.i as f64 * 0.25).abs() < 1e-12);
        assert!((p.position.dot(e2) + 2.5 - p.key.j as f64 * 0.25).abs() < 1e-12);
        // <n, e1 x e2> = +0.8 > 0 everywhere.
        assert_eq!(p.key.side, 1);
        assert!(!p.ambiguous);
        let [a, b, c] = mesh.face_corners(p.face);
        let q = p.bary.x * a + p.bary.y * b + p.bary.z * c;
        assert!((q - p.position).length() < 1e-12);
    }
    // Every grid pair (i, j) inside the square appears exactly once.
    let mut keys: Vec<_> = d.points.iter().map(|p| (p.key.i, p.key.j)).collect();
    keys.dedup();
    assert_eq!(keys.len(), d.len());
}

#[test]
fn plane_euclidean_fields_follow_the_law_of_cosines() {
    let mut mean_err = Vec::new();
    for n in [30, 60, 120] {
        let plane = plane_setup(n, 0.3);
        let [r, q] = plane.poles[..] else {
            unreachable!()
        };
        let h = 3.0 / n as f64;
        let o = all_gradient(LevelSpec::Count(5));
        let d = plane.describe(&o).unwrap();
        let dist = (r - q).length();
        assert!((d.step - dist / 5.0).abs() < 1e-12);
        assert!((d.reference_distance - dist).abs() < 1e-12);
        let mut sum = 0.0;
        for p in &d.points {
            let a = (p.position - r).length();
            let b = (p.position - q).length();
            // Chord error of the PL interpolant of a distance field: O(h^2 / a).
            assert!((a - p.key.i as f64 * d.step).abs() < h * h / a, "a");
            assert!((b - p.key.j as f64 * d.step).abs() < h * h / b, "b");
            let err = (p.cos - law_of_cosines(p.position, r, q)).abs();
            // Gradient of the PL interpolant: O(h / distance).
            assert!(err < 1.5 * h / a.min(b), "n {n}: err {err} at a {a} b {b}");
            sum += err;
            // Side: sign of <+z, (P - r) x (P - q)> = sign(y).
            if p.position.y.abs() > 1e-9 {
                assert_eq!(p.key.side as f64, p.position.y.signum());
            }
        }
        mean_err.push(sum / d.len() as f64);
    }
    // First-order convergence of the gradient method.
    assert!(mean_err[1] < 0.7 * mean_err[0], "{mean_err:?}");
    assert!(mean_err[2] < 0.7 * mean_err[1], "{mean_err:?}");
}

#[test]
fn filter_rule_keeps_only_points_near_angle_levels() {
    let plane = plane_setup(60, 0.3);
    let all = plane.describe(&all_gradient(LevelSpec::Count(5))).unwrap();
    let tol = 0.95 / 32.0;
    let o = opts(
        SelectionRule::Filter { tolerance: tol },
        TangentMethod::Gradient,
        LevelSpec::Count(5),
    );
    let d = plane.describe(&o).unwrap();
    assert!(!d.is_empty() && d.len() < all.len());
    for p in &d.points {
        let c = p.cos.abs();
        let k = (c * 8.0 / 0.95).round();
        assert!(k <= 8.0 && (c - 0.95 * k / 8.0).abs() <= tol);
        // The same point, with the same ambiguity flag, is in the unfiltered set.
        assert!(all
            .points
            .iter()
            .any(|q| q.key == p.key && q.position == p.position && q.ambiguous == p.ambiguous));
    }
    // The dropped ones are exactly the points outside the band.
    let expected = all
        .points
        .iter()
        .filter(|p| {
            let c = p.cos.abs();
            let k = (c * 8.0 / 0.95).round();
            k <= 8.0 && (c - 0.95 * k / 8.0).abs() <= tol
        })
        .count();
    assert_eq!(expected, d.len());
}

#[test]
fn isoangle_points_sit_on_angle_levels() {
    let plane = plane_setup(90, 0.3);
    let [r, q] = plane.poles[..] else {
        unreachable!()
    };
    let h = 3.0 / 90.0;
    for tangent in [
        TangentMethod::Gradient,
        TangentMethod::Spline,
        TangentMethod::Strip,
    ] {
        let o = DescriptorOptions {
            max_level: Some(5),
            ..opts(SelectionRule::IsoAngle, tangent, LevelSpec::Count(5))
        };
        let d = plane.describe(&o).unwrap();
        assert!(d.len() > 40, "{tangent:?}: {}", d.len());
        let mut errs = Vec::new();
        for p in &d.points {
            assert_eq!(p.cos, p.key.sign as f64 * 0.95 * p.key.j as f64 / 8.0);
            let a = (p.position - r).length();
            let b = (p.position - q).length();
            assert!((a - p.key.i as f64 * d.step).abs() < h * h / a);
            assert!(b <= 5.0 * d.step + h);
            errs.push((law_of_cosines(p.position, r, q) - p.cos).abs());
        }
        errs.sort_by(f64::total_cmp);
        let median = errs[errs.len() / 2];
        assert!(median < 0.05, "{tangent:?}: median angle error {median}");
    }
}

#[test]
fn sphere_matches_the_spherical_law_of_cosines() {
    let mesh = icosphere(4);
    // Two orthogonal poles, at vertices of the icosphere: (0, 1, t) and (0, -1, t) are not
    // orthogonal, so use the directions of two vertices and exact great-circle fields.
    let vr = 0u32;
    let r = mesh.position(vr);
    let vq = (0..mesh.n_vertices() as u32)
        .min_by(|&a, &b| {
            mesh.position(a)
                .dot(r)
                .abs()
                .total_cmp(&mesh.position(b).dot(r).abs())
        })
        .unwrap();
    let sphere = sphere_setup(mesh, &[vr, vq]);
    let q = sphere.poles[1];
    let dd = r.dot(q).clamp(-1.0, 1.0).acos();
    let oracle = |p: DVec3| {
        let p = p.normalize();
        let a = p.dot(r).clamp(-1.0, 1.0).acos();
        let b = p.dot(q).clamp(-1.0, 1.0).acos();
        (dd.cos() - a.cos() * b.cos()) / (a.sin() * b.sin())
    };
    for (tangent, tol) in [
        (TangentMethod::Gradient, 0.05),
        (TangentMethod::Strip, 0.15),
        (TangentMethod::Spline, 0.05),
    ] {
        let o = DescriptorOptions {
            max_level: Some(8),
            ..opts(SelectionRule::All, tangent, LevelSpec::Count(6))
        };
        let d = sphere.describe(&o).unwrap();
        assert!(d.len() > 50);
        let mut errs: Vec<f64> = d
            .points
            .iter()
            .map(|p| (p.cos - oracle(p.position)).abs())
            .collect();
        errs.sort_by(f64::total_cmp);
        let median = errs[errs.len() / 2];
        assert!(median < tol, "{tangent:?}: median error {median}");
        // Points lie on the level circles (chord error of the icosphere ~ h^2).
        for p in &d.points {
            let a = p.position.normalize().dot(r).clamp(-1.0, 1.0).acos();
            assert!((a - p.key.i as f64 * d.step).abs() < 0.02);
        }
    }
}

fn random_motion(seed: u64) -> DAffine3 {
    let f = |k: u64| ((seed.wrapping_mul(2654435761).wrapping_add(k * 97)) % 1000) as f64 / 1000.0;
    let axis = DVec3::new(f(1) - 0.5, f(2) - 0.5, f(3) + 0.1).normalize();
    DAffine3::from_rotation_translation(
        DQuat::from_axis_angle(axis, 6.0 * f(4)),
        DVec3::new(10.0 * f(5) - 5.0, 3.0 * f(6), -7.0 * f(7)),
    )
}

fn assert_same_up_to(d1: &Descriptor, d2: &Descriptor, t: &DAffine3, tol: f64, cos_tol: f64) {
    if d1.len() != d2.len() {
        let k1: std::collections::BTreeSet<_> =
            d1.points.iter().map(|p| (p.key, p.ambiguous)).collect();
        let k2: std::collections::BTreeSet<_> =
            d2.points.iter().map(|p| (p.key, p.ambiguous)).collect();
        eprintln!("only in 1: {:?}", k1.difference(&k2).collect::<Vec<_>>());
        eprintln!("only in 2: {:?}", k2.difference(&k1).collect::<Vec<_>>());
    }
    for (p, q) in d1.points.iter().zip(&d2.points) {
        if p.key != q.key
            || (t.transform_point3(p.position) - q.position).length() >= tol
            || (p.cos - q.cos).abs() >= cos_tol
        {
            eprintln!(
                "first mismatch: {p:?}\n vs {q:?}\n dist {}",
                (t.transform_point3(p.position) - q.position).length()
            );
            break;
        }
    }
    assert_eq!(d1.len(), d2.len());
    for (p, q) in d1.points.iter().zip(&d2.points) {
        assert_eq!(p.key, q.key);
        assert_eq!(p.ambiguous, q.ambiguous);
        assert!((t.transform_point3(p.position) - q.position).length() < tol);
        assert!((p.cos - q.cos).abs() < cos_tol);
    }
}

/// Matches points by key and position (the sort by position differs after a motion).
fn sorted_by_key_then_mapped(d: &Descriptor, t: &DAffine3) -> Descriptor {
    let mut out = d.clone();
    for p in &mut out.points {
        p.position = t.transform_point3(p.position);
    }
    out.points.sort_by(|p, q| {
        p.key
            .cmp(&q.key)
            .then(p.position.x.total_cmp(&q.position.x))
            .then(p.position.y.total_cmp(&q.position.y))
            .then(p.position.z.total_cmp(&q.position.z))
    });
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn rigid_motion_invariance(seed in 0u64..10_000, iso in prop::bool::ANY) {
        let mesh = icosphere(3);
        let surface = Surface::new(mesh.clone());
        let r = mesh.position(3);
        let q = mesh.position(40);
        let fields = vec![sphere_geodesic(&mesh, r, 1.0), sphere_geodesic(&mesh, q, 1.0)];
        let rule = if iso { SelectionRule::IsoAngle } else { SelectionRule::Filter { tolerance: 0.95 / 32.0 } };
        let o = opts(rule, TangentMethod::Gradient, LevelSpec::Count(6));
        let t = random_motion(seed);
        let moved = mesh.transformed(&t);
        let d1 = describe_fields(&surface, &fields, None, &o).unwrap();
        let d2 = describe_fields(&Surface::new(moved.clone()), &fields, None, &o).unwrap();
        let m1 = sorted_by_key_then_mapped(&d1, &t);
        assert_same_up_to(&m1, &d2, &DAffine3::IDENTITY, 1e-9, 1e-9);
    }
}

#[test]
fn rigid_motion_invariance_of_strip_and_spline() {
    let mesh = icosphere(3);
    let surface = Surface::new(mesh.clone());
    let fields = vec![
        sphere_geodesic(&mesh, mesh.position(3), 1.0),
        sphere_geodesic(&mesh, mesh.position(40), 1.0),
    ];
    let t = random_motion(77);
    let moved = mesh.transformed(&t);
    let moved_surface = Surface::new(moved.clone());
    for tangent in [TangentMethod::Strip, TangentMethod::Spline] {
        let o = opts(SelectionRule::All, tangent, LevelSpec::Count(6));
        let d1 = describe_fields(&surface, &fields, None, &o).unwrap();
        let d2 = describe_fields(&moved_surface, &fields, None, &o).unwrap();
        let m1 = sorted_by_key_then_mapped(&d1, &t);
        assert_same_up_to(&m1, &d2, &DAffine3::IDENTITY, 1e-9, 1e-7);
    }
}

#[test]
fn vertex_renumbering_does_not_change_the_descriptor() {
    let plane = plane_setup(40, 0.3);
    let n = plane.mesh.n_vertices();
    // A deterministic permutation and a rotation of each face's corner order, faces reversed.
    let (m2, perm) = testsupport::renumbered(&plane.mesh);
    let t2 = Surface::new(m2.clone());
    let mut f2 = vec![vec![0.0; n]; 2];
    for (f2k, fk) in f2.iter_mut().zip(&plane.fields) {
        for v in 0..n {
            f2k[perm[v] as usize] = fk[v];
        }
    }
    let refs2: Vec<Source> = plane
        .refs
        .iter()
        .map(|r| match r {
            Source::Vertex(v) => Source::Vertex(perm[*v as usize]),
            o => *o,
        })
        .collect();
    for rule in [SelectionRule::IsoAngle, SelectionRule::All] {
        let o = opts(rule, TangentMethod::Gradient, LevelSpec::Count(5));
        let d1 = plane.describe(&o).unwrap();
        let d2 = describe_fields(&t2, &f2, Some(&refs2), &o).unwrap();
        assert_same_up_to(&d1, &d2, &DAffine3::IDENTITY, 1e-12, 1e-9);
    }
}

#[test]
fn holes_split_curves_and_hold_no_points() {
    let hole = DVec3::new(0.0, 0.6, 0.0);
    let mesh = grid_plane(60, 0.05, -1.5, 0.3, 3, |c| (c - hole).length() < 0.3);
    let surface = Surface::new(mesh.clone());
    assert_eq!(surface.topology().boundary_loops().len(), 2);
    let r = DVec3::new(-0.5, 0.0, 0.0);
    let q = DVec3::new(0.5, 0.0, 0.0);
    // Euclidean fields (a stand-in: on a holed plane true geodesics bend around the hole).
    let fields = vec![euclidean(&mesh, r), euclidean(&mesh, q)];
    for rule in [SelectionRule::IsoAngle, SelectionRule::All] {
        for tangent in [
            TangentMethod::Gradient,
            TangentMethod::Spline,
            TangentMethod::Strip,
        ] {
            let o = opts(rule, tangent, LevelSpec::Step(0.2));
            let d = describe_fields(&surface, &fields, None, &o).unwrap();
            assert!(!d.is_empty());
            for p in &d.points {
                assert!(
                    (p.position - hole).length() > 0.3 - 0.05,
                    "point in the hole"
                );
                assert!(p.cos.is_finite());
            }
        }
    }
}

#[test]
fn vertex_mask_limits_the_region() {
    let plane = plane_setup(40, 0.2);
    let mask: Vec<bool> = plane
        .mesh
        .positions()
        .iter()
        .map(|p| p.y >= -0.05)
        .collect();
    let o = DescriptorOptions {
        vertex_mask: Some(mask),
        ..all_gradient(LevelSpec::Count(5))
    };
    let d = plane.describe(&o).unwrap();
    assert!(d
        .points
        .iter()
        .all(|p| p.position.y >= -0.05 && p.key.side == 1 || p.position.y.abs() < 0.1));
    let full = plane.describe(&all_gradient(LevelSpec::Count(5))).unwrap();
    assert!(d.len() < full.len() * 6 / 10);
}

#[test]
fn more_than_two_references_give_every_pair() {
    let sphere = sphere_setup(icosphere(3), &[0, 5, 100]);
    let d = sphere.describe(&DescriptorOptions::default()).unwrap();
    let mut pairs: Vec<(u8, u8)> = d.points.iter().map(|p| (p.key.a, p.key.b)).collect();
    pairs.dedup();
    assert_eq!(pairs, vec![(0, 1), (0, 2), (1, 2)]);
    assert_eq!(d.references.len(), 3);
}

#[test]
fn describe_with_a_solver() {
    let mesh = grid_plane(30, 0.1, -1.5, 0.0, 0, |_| false);
    let solver = geodesic::new_solver(&mesh, geodesic::Method::Dijkstra).unwrap();
    let refs = [Source::Vertex(15 * 31 + 10), Source::Vertex(15 * 31 + 20)];
    let o = all_gradient(LevelSpec::Count(5));
    let d = describe_solved(&Surface::new(mesh.clone()), solver.as_ref(), &refs, &o).unwrap();
    assert!((d.reference_distance - 1.0).abs() < 1e-9);
    assert!(d.len() > 20);
    // Surface-point references work too.
    let sp = meshcore::FaceLocator::new(&mesh)
        .nearest(DVec3::new(-0.47, 0.03, 0.0))
        .unwrap()
        .0;
    let refs = [Source::Point(sp), Source::Vertex(15 * 31 + 20)];
    let d = describe_solved(&Surface::new(mesh.clone()), solver.as_ref(), &refs, &o).unwrap();
    assert!((d.references[0] - DVec3::new(-0.47, 0.03, 0.0)).length() < 1e-12);
}

#[test]
fn bad_input_gives_clear_errors() {
    let plane = plane_setup(20, 0.0);
    let o = DescriptorOptions::default();
    // Coincident references.
    let r = describe_fields(
        &plane.surface,
        &[plane.fields[0].clone(), plane.fields[0].clone()],
        Some(&[plane.refs[0], plane.refs[0]]),
        &o,
    );
    assert!(
        matches!(
            r,
            Err(BipolarError::CoincidentReferences { a: 0, b: 1, .. })
        ),
        "{r:?}"
    );
    // NaN field.
    let mut bad = plane.fields.clone();
    bad[1][7] = f64::NAN;
    let r = describe_fields(&plane.surface, &bad, None, &o);
    assert!(matches!(
        r,
        Err(BipolarError::NonFiniteField {
            field: 1,
            vertex: 7,
            ..
        })
    ));
    // Wrong length.
    let r = describe_fields(
        &plane.surface,
        &[plane.fields[0].clone(), vec![0.0; 3]],
        None,
        &o,
    );
    assert!(matches!(r, Err(BipolarError::FieldLength { field: 1, .. })));
    // One field.
    assert!(matches!(
        describe_fields(&plane.surface, &plane.fields[..1], None, &o),
        Err(BipolarError::ReferenceCount(1))
    ));
    // Step too large: no level fits.
    let big = all_gradient(LevelSpec::Step(100.0));
    assert!(matches!(
        describe_fields(&plane.surface, &plane.fields, None, &big),
        Err(BipolarError::NoIntersections(_))
    ));
    // Invalid alpha.
    let a = DescriptorOptions {
        alpha: 1.5,
        ..DescriptorOptions::default()
    };
    assert!(matches!(
        describe_fields(&plane.surface, &plane.fields, None, &a),
        Err(BipolarError::InvalidOption(_))
    ));
    // Different components: two disjoint grids.
    let m1 = grid_plane(4, 0.25, 0.0, 0.0, 0, |_| false);
    let (mut p, mut t) = m1.clone().into_parts();
    let off = p.len() as u32;
    p.extend(
        m1.positions()
            .iter()
            .map(|x| *x + DVec3::new(5.0, 0.0, 0.0)),
    );
    t.extend(m1.triangles().iter().map(|tr| tr.map(|v| v + off)));
    let two = TriMesh::new(p, t).unwrap();
    let solver = geodesic::new_solver(&two, geodesic::Method::Dijkstra).unwrap();
    let r = describe_solved(
        &Surface::new(two.clone()),
        solver.as_ref(),
        &[Source::Vertex(0), Source::Vertex(off + 3)],
        &o,
    );
    assert!(
        matches!(r, Err(BipolarError::DifferentComponents { a: 0, b: 1 })),
        "{r:?}"
    );
    // Reference out of range.
    let r = describe_solved(
        &Surface::new(two.clone()),
        solver.as_ref(),
        &[Source::Vertex(0), Source::Vertex(10_000)],
        &o,
    );
    assert!(r.is_err());
}

#[test]
fn files_round_trip() {
    let plane = plane_setup(30, 0.3);
    let d = plane.describe(&DescriptorOptions::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("bipolar-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("d.json");
    bipolar::io::write_json(&json, &d).unwrap();
    let back = bipolar::io::read_json(&json).unwrap();
    assert_eq!(back, d);
    let csv = dir.join("d.csv");
    bipolar::io::write_csv(&csv, &d).unwrap();
    let back = bipolar::io::read_csv(&csv).unwrap();
    assert_eq!(back.len(), d.len());
    for (p, q) in d.points.iter().zip(&back.points) {
        assert_eq!(p.position, q.position);
        assert_eq!(p.key, q.key);
        assert_eq!(p.cos, q.cos);
        assert_eq!(p.ambiguous, q.ambiguous);
    }
    assert_eq!(back.packed_keys(), d.packed_keys());
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("x,y,z,a,b,i,j,side,sign,cos,ambiguous\n"));
    // A broken line is reported with its number.
    let broken = text.replacen('\n', "\n1,2,oops,0,1,1,1,1,0,0.5,0\n", 1);
    let err = bipolar::io::parse_csv(&broken, std::path::Path::new("x.csv")).unwrap_err();
    assert!(err.to_string().contains("line 2"), "{err}");
    let ply = dir.join("d.ply");
    bipolar::io::write_ply(&ply, &d).unwrap();
    let t = std::fs::read_to_string(&ply).unwrap();
    assert!(t.contains(&format!("element vertex {}", d.len())));
    assert_eq!(t.lines().count(), d.len() + 16);
    std::fs::remove_dir_all(&dir).ok();
}

/// Wraps a solver and records the cut-off of every call.
#[derive(Debug)]
struct Recording<'a> {
    inner: &'a dyn geodesic::GeodesicSolver,
    cuts: std::sync::Mutex<Vec<Option<f64>>>,
}

impl geodesic::GeodesicSolver for Recording<'_> {
    fn method(&self) -> geodesic::Method {
        self.inner.method()
    }
    fn n_vertices(&self) -> usize {
        self.inner.n_vertices()
    }
    fn distances(
        &self,
        sources: &[Source],
        opts: &geodesic::SolveOptions,
    ) -> Result<Vec<f64>, geodesic::GeodesicError> {
        self.cuts.lock().unwrap().push(opts.max_distance);
        self.inner.distances(sources, opts)
    }
}

#[test]
fn a_region_limit_cuts_the_fields_off_without_changing_the_descriptor() {
    let sphere = icosphere(4);
    let plane = grid_plane(40, 0.075, -1.5, 0.3, 11, |_| false);
    for (mesh, a, b, c, far, step) in [
        // Nearly antipodal references: the straight-line guess of d(r, q) is far too short and
        // the first field has to be solved again.
        (
            &sphere,
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.2, 0.0, -0.98),
            DVec3::new(1.0, 0.0, 0.0),
            true,
            0.4,
        ),
        (
            &plane,
            DVec3::new(-0.4, 0.0, 0.0),
            DVec3::new(0.4, 0.1, 0.0),
            DVec3::new(0.0, 0.5, 0.0),
            false,
            0.12,
        ),
    ] {
        let surface = Surface::new(mesh.clone());
        let sp = meshcore::FaceLocator::new(mesh).nearest(c).unwrap().0;
        let refs = [
            Source::Vertex(nearest_vertex(mesh, a)),
            Source::Vertex(nearest_vertex(mesh, b)),
            Source::Point(sp),
        ];
        for method in [geodesic::Method::Exact, geodesic::Method::Dijkstra] {
            let inner = geodesic::new_solver(mesh, method).unwrap();
            let full: Vec<Vec<f64>> = refs
                .iter()
                .map(|r| {
                    inner
                        .distances(&[*r], &geodesic::SolveOptions::default())
                        .unwrap()
                })
                .collect();
            for (levels, max_level) in [(LevelSpec::Count(6), 4), (LevelSpec::Step(step), 5)] {
                let mut o = all_gradient(levels);
                o.max_level = Some(max_level);
                let rec = Recording {
                    inner: inner.as_ref(),
                    cuts: std::sync::Mutex::new(Vec::new()),
                };
                let got = describe_solved(&surface, &rec, &refs, &o).unwrap();
                let want = describe_fields(&surface, &full, Some(&refs), &o).unwrap();
                let cuts = rec.cuts.into_inner().unwrap();
                assert!(cuts.iter().all(|c| c.is_some()), "{cuts:?}");
                assert!(cuts.len() >= 3);
                if far && matches!(levels, LevelSpec::Count(_)) {
                    assert!(cuts.len() > 3, "expected a second solve: {cuts:?}");
                }
                assert_eq!(got.len(), want.len(), "{method:?} {levels:?}");
                assert!(!got.is_empty());
                assert_eq!(got.reference_distance, want.reference_distance);
                for (p, q) in got.points.iter().zip(&want.points) {
                    assert_eq!(p.key, q.key);
                    assert_eq!(p.position, q.position);
                    assert_eq!(p.cos, q.cos);
                }
            }
        }
    }
}

#[test]
fn option_names_round_trip_and_bad_names_list_the_choices() {
    use bipolar::{BipolarError, SelectionKind, SelectionRule, TangentMethod};
    meshcore::choice::check_choice::<TangentMethod>("normal").unwrap();
    meshcore::choice::check_choice::<SelectionKind>("band").unwrap();
    meshcore::choice::check_choice::<bipolar::IsoRepeats>("first").unwrap();
    meshcore::choice::check_choice::<bipolar::IsoCrossings>("some").unwrap();
    let k: SelectionKind = "iso-angle".parse().unwrap();
    assert_eq!(k.rule(0.1), SelectionRule::IsoAngle);
    assert_eq!(
        SelectionKind::Filter.rule(0.1).kind(),
        SelectionKind::Filter
    );
    match "band".parse::<SelectionKind>() {
        Err(BipolarError::UnknownChoice(e)) => {
            assert_eq!(e.expected, ["filter", "isoangle", "all"]);
        }
        other => panic!("{other:?}"),
    }
}
