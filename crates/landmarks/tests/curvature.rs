//! Curvature against analytic values on spheres, cylinders and saddles.

use landmarks::curvature::{taubin_smooth, vertex_curvatures, CurvatureOptions};
use landmarks::{curvedness, shape_index};
use meshcore::{DAffine3, DVec3, TriMesh};
use testsupport::shapes;

/// UV sphere of radius `r` (the shared generator, scaled).
fn sphere(r: f64, n_lat: usize, n_lon: usize) -> TriMesh {
    shapes::uv_sphere(n_lat, n_lon).transformed(&DAffine3::from_scale(DVec3::splat(r)))
}

/// Open cylinder of radius `r` around z from `z = -len / 2` to `len / 2`, outward normals.
fn cylinder(r: f64, len: f64, n_a: usize, n_z: usize) -> TriMesh {
    shapes::cylinder(r, len, n_a, n_z).transformed(&DAffine3::from_translation(DVec3::new(
        0.0,
        0.0,
        -0.5 * len,
    )))
}

/// Height field `z = f(x, y)` on a jittered-free grid over `[-1, 1]^2`, normals up.
fn height_field(n: usize, f: impl Fn(f64, f64) -> f64) -> TriMesh {
    testsupport::height_field(n, 1.0, f)
}

fn flipped(m: &TriMesh) -> TriMesh {
    TriMesh::new(
        m.positions().to_vec(),
        m.triangles().iter().map(|t| [t[0], t[2], t[1]]).collect(),
    )
    .unwrap()
}

#[test]
fn sphere_has_positive_umbilic_curvature_and_cap_shape_index() {
    for r in [0.5, 2.0, 30.0] {
        let m = sphere(r, 40, 80);
        let c = vertex_curvatures(&m, &CurvatureOptions::with_radius(0.25 * r));
        let mut worst: f64 = 0.0;
        for (v, k) in c.iter().enumerate() {
            // Skip the poles (fan vertices with skewed neighbourhoods are still fine, but keep
            // the test about the regular part).
            if v == 0 || v == c.len() - 1 {
                continue;
            }
            worst = worst
                .max((k.k1 * r - 1.0).abs())
                .max((k.k2 * r - 1.0).abs());
            assert!(k.shape_index() > 0.95, "S = {}", k.shape_index());
            assert!((k.curvedness() * r - 1.0).abs() < 0.02);
        }
        assert!(worst < 0.02, "radius {r}: worst relative error {worst}");
        // Reversed orientation (normals inwards): a cup.
        let c = vertex_curvatures(&flipped(&m), &CurvatureOptions::with_radius(0.25 * r));
        for k in &c[1..c.len() - 1] {
            assert!((k.k1 * r + 1.0).abs() < 0.02 && (k.k2 * r + 1.0).abs() < 0.02);
            assert!(k.shape_index() < -0.95);
        }
    }
}

#[test]
fn cylinder_principal_values_and_directions() {
    let r = 1.5;
    let m = cylinder(r, 6.0, 96, 60);
    let c = vertex_curvatures(&m, &CurvatureOptions::with_radius(0.4));
    let mut checked = 0;
    for (v, k) in c.iter().enumerate() {
        let p = m.position(v as u32);
        if p.z.abs() > 2.0 {
            continue; // Away from the open ends.
        }
        assert!((k.k1 * r - 1.0).abs() < 0.02, "k1 = {}", k.k1);
        assert!(k.k2.abs() < 0.02, "k2 = {}", k.k2);
        // d1 is circumferential, d2 axial.
        assert!(k.d1.z.abs() < 0.02, "d1 = {}", k.d1);
        assert!(k.d2.z.abs() > 0.999, "d2 = {}", k.d2);
        assert!((k.shape_index() - 0.5).abs() < 0.02);
        checked += 1;
    }
    assert!(checked > 1000);
}

#[test]
fn saddle_and_bowl_at_center() {
    // z = (x^2 - y^2)/2 with upward normals: curvatures -1 along x (surface bends towards the
    // normal) and +1 along y at the origin; shape index 0.
    let m = height_field(60, |x, y| 0.5 * (x * x - y * y));
    let c = vertex_curvatures(&m, &CurvatureOptions::with_radius(0.12));
    let center = 30 * 61 + 30;
    let k = c[center];
    assert!(
        (k.k1 - 1.0).abs() < 0.03 && (k.k2 + 1.0).abs() < 0.03,
        "{k:?}"
    );
    assert!(k.shape_index().abs() < 0.02);
    assert!(k.d1.y.abs() > 0.99, "d1 along y: {}", k.d1);
    // Bowl z = (x^2 + y^2)/2 seen from above (normals up): a cup, S = -1, like an eye corner.
    let m = height_field(60, |x, y| 0.5 * (x * x + y * y));
    let c = vertex_curvatures(&m, &CurvatureOptions::with_radius(0.12));
    let k = c[center];
    assert!(
        (k.k1 + 1.0).abs() < 0.03 && (k.k2 + 1.0).abs() < 0.03,
        "{k:?}"
    );
    assert!(k.shape_index() < -0.97);
}

#[test]
fn noisy_sphere_is_robust_at_a_larger_scale_and_with_smoothing() {
    use rand::{Rng, SeedableRng};
    let r = 5.0;
    let m = sphere(r, 50, 100);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let h = m.mean_edge_length();
    let noisy = TriMesh::new(
        m.positions()
            .iter()
            .map(|p| *p * (1.0 + 0.05 * h / r * (rng.random::<f64>() - 0.5) * 2.0))
            .collect(),
        m.triangles().to_vec(),
    )
    .unwrap();
    let smooth = taubin_smooth(&noisy, 5, 0.5, -0.53);
    for mesh in [&noisy, &smooth] {
        let c = vertex_curvatures(mesh, &CurvatureOptions::with_radius(0.3 * r));
        let mean_err: f64 = c[1..c.len() - 1]
            .iter()
            .map(|k| (k.mean() * r - 1.0).abs())
            .sum::<f64>()
            / (c.len() - 2) as f64;
        assert!(mean_err < 0.03, "mean relative error {mean_err}");
    }
}

#[test]
fn shape_index_convention() {
    assert_eq!(shape_index(1.0, 1.0), 1.0);
    assert_eq!(shape_index(-1.0, -1.0), -1.0);
    assert_eq!(shape_index(0.0, 0.0), 0.0);
    assert!((shape_index(1.0, 0.0) - 0.5).abs() < 1e-12);
    assert!((shape_index(0.0, -1.0) + 0.5).abs() < 1e-12);
    assert!(shape_index(1.0, -1.0).abs() < 1e-12);
    assert_eq!(shape_index(0.3, 0.7), shape_index(0.7, 0.3));
    assert!((curvedness(3.0, 4.0) - (12.5f64).sqrt()).abs() < 1e-12);
}

#[test]
fn curvature_does_not_depend_on_the_thread_count() {
    // The per-vertex fits run in parallel; every value must equal the one-thread result bit
    // for bit (a jittered height field, so that the fits differ from vertex to vertex).
    let m = height_field(40, |x, y| {
        0.3 * (3.0 * x).sin() * (2.0 * y).cos() + 0.01 * (37.0 * x * y).sin()
    });
    let opts = CurvatureOptions::with_radius(0.12);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| vertex_curvatures(&m, &opts))
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.len(), m.n_vertices());
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a.k1.to_bits(), b.k1.to_bits());
        assert_eq!(a.k2.to_bits(), b.k2.to_bits());
        assert_eq!(
            a.d1.to_array().map(f64::to_bits),
            b.d1.to_array().map(f64::to_bits)
        );
        assert_eq!(
            a.normal.to_array().map(f64::to_bits),
            b.normal.to_array().map(f64::to_bits)
        );
    }
    // And the field is not trivial (the comparison is not between two flat results).
    assert!(one.iter().any(|c| c.k1.abs() > 0.1));
}

#[test]
fn curvature_at_chosen_vertices_equals_the_whole_mesh_computation() {
    let mesh = height_field(30, |x, y| 0.3 * x * x - 0.2 * x * y + 0.1 * y * y * y);
    let normals = mesh.vertex_normals();
    let adj = landmarks::curvature::VertexAdjacency::new(&mesh);
    let opts = CurvatureOptions::with_radius(0.25);
    let all = landmarks::curvature::vertex_curvatures_with(&mesh, &normals, &adj, &opts);
    let at = [517u32, 3, 250, 899, 3];
    let some = landmarks::curvature::curvatures_at(&mesh, &normals, &adj, &opts, &at);
    assert_eq!(some.len(), at.len());
    for (v, c) in at.iter().zip(&some) {
        assert_eq!(*c, all[*v as usize], "vertex {v}");
    }
    // An id out of range gets zero curvatures instead of a panic.
    let out = landmarks::curvature::curvatures_at(&mesh, &normals, &adj, &opts, &[u32::MAX]);
    assert_eq!((out[0].k1, out[0].k2), (0.0, 0.0));
}

#[test]
fn cube_thinning_keeps_the_first_vertex_of_each_cube() {
    let mesh = testsupport::jittered_unit_plane(25, 0.3, 7);
    let pos = mesh.positions();
    let spacing = 0.13;
    let thin = landmarks::curvature::CubeThinning::new(pos, spacing);
    let cube = |v: u32| (pos[v as usize] / spacing).floor();
    assert!(thin.kept().windows(2).all(|w| w[0] < w[1]));
    assert!(thin.kept().len() > 20 && thin.kept().len() < pos.len() / 4);
    for (v, &c) in thin.cube_of().iter().enumerate() {
        let k = thin.kept()[c as usize];
        assert_eq!(cube(k), cube(v as u32), "vertex {v}");
        assert!(k <= v as u32, "vertex {v} precedes its cube's vertex {k}");
    }
    for (i, &k) in thin.kept().iter().enumerate() {
        assert_eq!(thin.cube_of()[k as usize], i as u32);
    }
}

#[test]
fn thinned_fits_of_a_dense_sphere_find_its_curvature() {
    let r = 30.0;
    // About 0.8 mesh units between neighbours; fits at 7.5 over cubes of 1.25.
    let m = sphere(r, 120, 240);
    let normals = m.vertex_normals();
    let adj = landmarks::curvature::VertexAdjacency::new(&m);
    let opts = CurvatureOptions::with_radius(0.25 * r);
    // Vertices away from the poles.
    let at: Vec<u32> = (0..m.n_vertices() as u32)
        .filter(|&v| m.positions()[v as usize].z.abs() < 0.8 * r)
        .step_by(97)
        .collect();
    assert!(at.len() > 100);
    let thin = landmarks::curvature::CubeThinning::new(m.positions(), r / 24.0);
    let c = landmarks::curvature::curvatures_at_thinned(&m, &normals, &adj, &opts, &at, &thin);
    for (v, k) in at.iter().zip(&c) {
        assert!(
            (k.k1 * r - 1.0).abs() < 0.03 && (k.k2 * r - 1.0).abs() < 0.03,
            "vertex {v}: k1 r = {}, k2 r = {}",
            k.k1 * r,
            k.k2 * r
        );
    }
}

#[test]
fn thinned_fits_follow_the_edges_not_the_space_between_sheets() {
    // A flat sheet and, 0.1 above it, a bowl that is not connected to it: within a ball of 0.25
    // around the flat sheet's centre, but reached through no edge.
    let flat = height_field(80, |_, _| 0.0);
    let bowl = height_field(80, |x, y| 0.1 + 2.0 * (x * x + y * y));
    let n = flat.n_vertices() as u32;
    let mut pos = flat.positions().to_vec();
    pos.extend_from_slice(bowl.positions());
    let mut tris = flat.triangles().to_vec();
    tris.extend(bowl.triangles().iter().map(|t| t.map(|i| i + n)));
    let m = TriMesh::new(pos, tris).unwrap();
    let normals = m.vertex_normals();
    let adj = landmarks::curvature::VertexAdjacency::new(&m);
    let opts = CurvatureOptions::with_radius(0.25);
    let centre = testsupport::nearest_vertex(&flat, DVec3::ZERO);
    let bowl_centre = centre + n;
    let at = [centre, bowl_centre];
    let cubes = landmarks::curvature::CubeThinning::new(m.positions(), 0.05);
    let thin = landmarks::curvature::curvatures_at_thinned(&m, &normals, &adj, &opts, &at, &cubes);
    let full = landmarks::curvature::curvatures_at(&m, &normals, &adj, &opts, &at);
    for c in [&thin[0], &full[0]] {
        assert!(c.k1.abs() < 1e-6 && c.k2.abs() < 1e-6, "flat: {c:?}");
    }
    // The bowl's own curvature (4 at its bottom, outward normals up: a cup) is found.
    for c in [&thin[1], &full[1]] {
        assert!(
            (c.k1 + 4.0).abs() < 0.4 && (c.k2 + 4.0).abs() < 0.4,
            "bowl: {c:?}"
        );
    }
}
