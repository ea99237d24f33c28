//! The iso-angle rule on noisy surfaces (scan-like meshes): the monotone crossing rule gives one
//! point per key where the raw opening wiggles around an angle level, stays on the analytic
//! angles (plane: law of cosines; sphere: spherical law of cosines), and is invariant under
//! rigid motions and vertex renumbering.

use bipolar::synthetic::{grid_plane, icosphere};
use bipolar::{
    describe, Descriptor, DescriptorOptions, Fields, IsoAngleOptions, IsoCrossings, LevelSpec,
    Source,
};
use glam::{DAffine3, DQuat, DVec3};
use meshcore::{Surface, TriMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use testsupport::nearest_vertex;

mod common;

/// Plane grid on [-1.5, 1.5]^2, `n` cells a side, jittered in the plane, with uniform height
/// noise of amplitude `noise` (as a fraction of the cell size); references at the vertices
/// nearest to (-0.5, 0) and (0.5, 0).
fn noisy_plane(n: usize, noise: f64, seed: u64) -> (TriMesh, [u32; 2]) {
    let h = 3.0 / n as f64;
    let m = grid_plane(n, h, -1.5, 0.3, seed, |_| false);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pos: Vec<DVec3> = m
        .positions()
        .iter()
        .map(|p| *p + DVec3::Z * noise * h * rng.random_range(-1.0..1.0))
        .collect();
    let mesh = TriMesh::new(pos, m.triangles().to_vec()).unwrap();
    let near = |p: DVec3| nearest_vertex(&mesh, p);
    let refs = [
        near(DVec3::new(-0.5, 0.0, 0.0)),
        near(DVec3::new(0.5, 0.0, 0.0)),
    ];
    (mesh, refs)
}

/// Icosphere of radius 1 with radial noise of amplitude `noise` (fraction of the mean edge);
/// references: vertex 0 and the vertex nearest to the great circle orthogonal to it.
fn noisy_sphere(level: u32, noise: f64, seed: u64) -> (TriMesh, [u32; 2]) {
    let m = icosphere(level);
    let h = m.mean_edge_length();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pos: Vec<DVec3> = m
        .positions()
        .iter()
        .map(|p| p.normalize() * (1.0 + noise * h * rng.random_range(-1.0..1.0)))
        .collect();
    let mesh = TriMesh::new(pos, m.triangles().to_vec()).unwrap();
    let r = mesh.position(0).normalize();
    let vq = (1..mesh.n_vertices() as u32)
        .min_by(|&a, &b| {
            mesh.position(a)
                .normalize()
                .dot(r)
                .abs()
                .total_cmp(&mesh.position(b).normalize().dot(r).abs())
        })
        .unwrap();
    (mesh, [0, vq])
}

/// The iso-angle rule with `crossings` on `levels` levels.
fn iso(crossings: IsoCrossings, levels: u32) -> DescriptorOptions {
    let isoangle = IsoAngleOptions {
        crossings,
        ..IsoAngleOptions::default()
    };
    common::iso_angle(LevelSpec::Count(levels), levels, isoangle)
}

/// Exact geodesic fields from the two reference vertices.
fn exact_fields(mesh: &TriMesh, refs: [u32; 2]) -> Vec<Vec<f64>> {
    let solver = geodesic::new_solver(mesh, geodesic::Method::Exact).unwrap();
    refs.iter()
        .map(|&v| {
            solver
                .distances(&[Source::Vertex(v)], &geodesic::SolveOptions::default())
                .unwrap()
        })
        .collect()
}

fn describe_with(
    mesh: &TriMesh,
    fields: &[Vec<f64>],
    refs: [u32; 2],
    o: &DescriptorOptions,
) -> Descriptor {
    let refs = refs.map(Source::Vertex);
    describe(
        &Surface::new(mesh.clone()),
        Fields::Precomputed {
            fields,
            references: Some(&refs),
        },
        o,
    )
    .unwrap()
}

fn ambiguous_fraction(d: &Descriptor) -> f64 {
    d.points.iter().filter(|p| p.ambiguous).count() as f64 / d.len() as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn noisy_plane_keeps_one_point_per_key_on_the_law_of_cosines() {
    let (mesh, refs) = noisy_plane(90, 0.3, 3);
    let fields = exact_fields(&mesh, refs);
    let every = describe_with(&mesh, &fields, refs, &iso(IsoCrossings::Every, 5));
    let mono = describe_with(&mesh, &fields, refs, &iso(IsoCrossings::Monotone, 5));
    let (fe, fm) = (ambiguous_fraction(&every), ambiguous_fraction(&mono));
    // The noise makes the raw opening cross the levels several times (the test must be able
    // to fail): most keys of the every-crossing rule are ambiguous; the monotone rule keeps
    // one point per key.
    assert!(
        fe > 0.3,
        "every crossing: only {fe} ambiguous; the noise is too weak"
    );
    assert!(
        fm < 0.02,
        "monotone: {fm} of {} points ambiguous",
        mono.len()
    );
    assert!(mono.len() > 60, "{}", mono.len());
    // Positions: on the level circle of r and on the angle level (law of cosines, the plane's
    // geometry; the mesh is within 0.3 cells of it).
    let (r, q) = (mesh.position(refs[0]), mesh.position(refs[1]));
    let flat = |p: DVec3| DVec3::new(p.x, p.y, 0.0);
    let mut errs = Vec::new();
    for p in &mono.points {
        let (x, rr, qq) = (flat(p.position), flat(r), flat(q));
        let (a, b, d) = ((x - rr).length(), (x - qq).length(), (rr - qq).length());
        assert!(
            (a - p.key.i as f64 * mono.step).abs() < 0.05,
            "{:?} at {a}",
            p.key
        );
        errs.push(((a * a + b * b - d * d) / (2.0 * a * b) - p.cos).abs());
    }
    let m = median(errs);
    assert!(m < 0.05, "median cosine error {m}");
}

#[test]
fn noisy_sphere_keeps_one_point_per_key_on_the_spherical_law_of_cosines() {
    let (mesh, refs) = noisy_sphere(5, 0.3, 11);
    let fields = exact_fields(&mesh, refs);
    let o = |c| DescriptorOptions {
        levels: LevelSpec::Step(0.15),
        max_level: Some(10),
        ..iso(c, 10)
    };
    let every = describe_with(&mesh, &fields, refs, &o(IsoCrossings::Every));
    let mono = describe_with(&mesh, &fields, refs, &o(IsoCrossings::Monotone));
    let (fe, fm) = (ambiguous_fraction(&every), ambiguous_fraction(&mono));
    assert!(fe > 0.3, "every crossing: only {fe} ambiguous");
    assert!(
        fm < 0.02,
        "monotone: {fm} of {} points ambiguous",
        mono.len()
    );
    let (r, q) = (
        mesh.position(refs[0]).normalize(),
        mesh.position(refs[1]).normalize(),
    );
    let dd = r.dot(q).clamp(-1.0, 1.0).acos();
    let mut errs = Vec::new();
    for p in &mono.points {
        let x = p.position.normalize();
        let a = x.dot(r).clamp(-1.0, 1.0).acos();
        let b = x.dot(q).clamp(-1.0, 1.0).acos();
        let c = (dd.cos() - a.cos() * b.cos()) / (a.sin() * b.sin());
        errs.push((c - p.cos).abs());
    }
    let m = median(errs);
    assert!(m < 0.05, "median cosine error {m}");
}

#[test]
fn monotone_equals_every_crossing_where_the_opening_is_monotone() {
    // Exact Euclidean fields on an unjittered flat grid: the opening along each level arc is
    // monotone (law of cosines), so both rules give the same keys at nearly the same places.
    let m = grid_plane(60, 0.05, -1.5, 0.0, 1, |_| false);
    let near = |p: DVec3| nearest_vertex(&m, p);
    let refs = [
        near(DVec3::new(-0.5, 0.0, 0.0)),
        near(DVec3::new(0.5, 0.0, 0.0)),
    ];
    let fields: Vec<Vec<f64>> = refs
        .iter()
        .map(|&v| testsupport::fields::euclidean(&m, m.position(v)))
        .collect();
    let every = describe_with(&m, &fields, refs, &iso(IsoCrossings::Every, 5));
    let mono = describe_with(&m, &fields, refs, &iso(IsoCrossings::Monotone, 5));
    assert_eq!(ambiguous_fraction(&every), 0.0);
    assert_eq!(ambiguous_fraction(&mono), 0.0);
    assert_eq!(every.packed_keys(), mono.packed_keys());
    for (a, b) in every.points.iter().zip(&mono.points) {
        assert!(
            (a.position - b.position).length() < 0.05,
            "{:?}: {} vs {}",
            a.key,
            a.position,
            b.position
        );
    }
}

fn assert_same(a: &Descriptor, b: &Descriptor, t: &DAffine3, tol: f64) {
    assert_eq!(a.packed_keys(), b.packed_keys());
    for (p, q) in a.points.iter().zip(&b.points) {
        assert!(
            (t.transform_point3(p.position) - q.position).length() < tol,
            "{:?}",
            p.key
        );
        assert_eq!(p.ambiguous, q.ambiguous);
        assert_eq!(p.cos, q.cos);
    }
}

#[test]
fn monotone_rule_is_invariant_under_renumbering_and_rigid_motion_on_a_noisy_plane() {
    let (mesh, refs) = noisy_plane(50, 0.3, 5);
    let fields = exact_fields(&mesh, refs);
    let o = iso(IsoCrossings::Monotone, 5);
    let smoothed = DescriptorOptions {
        isoangle: IsoAngleOptions {
            crossings: IsoCrossings::Monotone,
            smoothing: 2.0,
            ..IsoAngleOptions::default()
        },
        ..o.clone()
    };
    for o in [o, smoothed] {
        let d1 = describe_with(&mesh, &fields, refs, &o);
        // Renumbered.
        let (m2, perm) = testsupport::renumbered(&mesh);
        let mut f2 = vec![vec![0.0; mesh.n_vertices()]; 2];
        for k in 0..2 {
            for v in 0..mesh.n_vertices() {
                f2[k][perm[v] as usize] = fields[k][v];
            }
        }
        let r2 = refs.map(|v| perm[v as usize]);
        let d2 = describe_with(&m2, &f2, r2, &o);
        assert_same(&d1, &d2, &DAffine3::IDENTITY, 1e-12);
        // Moved.
        let t = DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), 1.1),
            DVec3::new(4.0, -2.0, 7.0),
        );
        let m3 = mesh.transformed(&t);
        let d3 = describe_with(&m3, &fields, refs, &o);
        assert_same(&d1, &d3, &t, 1e-9);
    }
}

#[test]
fn bad_smoothing_is_refused() {
    let (mesh, refs) = noisy_plane(10, 0.0, 1);
    let fields = exact_fields(&mesh, refs);
    let refs = refs.map(Source::Vertex);
    for s in [-1.0, f64::NAN, f64::INFINITY] {
        let o = DescriptorOptions {
            isoangle: IsoAngleOptions {
                crossings: IsoCrossings::Monotone,
                smoothing: s,
                ..IsoAngleOptions::default()
            },
            ..DescriptorOptions::default()
        };
        let e = describe(
            &Surface::new(mesh.clone()),
            Fields::Precomputed {
                fields: &fields,
                references: Some(&refs),
            },
            &o,
        )
        .unwrap_err();
        assert!(e.to_string().contains("smoothing"), "{e}");
    }
}
