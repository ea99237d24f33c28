//! Every reader on the small hand-written samples in `fixtures/`.

use mesh_io::{read_lm2, read_lm3, read_mesh, LoadedMesh};
use meshcore::{DVec3, Topology};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(name)
}

fn load(name: &str) -> LoadedMesh {
    read_mesh(fixture(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Closed, consistently oriented, outward (positive signed volume) surface.
fn check_closed_outward(m: &LoadedMesh, volume: f64) {
    let t = Topology::new(&m.mesh);
    assert!(t.boundary_loops().is_empty());
    assert_eq!(t.n_components(), 1);
    assert!(t.inconsistent_edges().is_empty());
    assert!(t.non_manifold_edges().is_empty());
    let vol: f64 = (0..m.mesh.n_faces() as u32)
        .map(|f| {
            let [a, b, c] = m.mesh.face_corners(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!((vol - volume).abs() < 1e-12, "volume {vol}");
}

/// The fixture `name`, checked to have `nv` vertices and `nf` faces and to be a closed outward
/// surface enclosing `volume`.
fn load_closed(name: &str, nv: usize, nf: usize, volume: f64) -> LoadedMesh {
    let m = load(name);
    assert_eq!(m.mesh.n_vertices(), nv, "{name}");
    assert_eq!(m.mesh.n_faces(), nf, "{name}");
    check_closed_outward(&m, volume);
    m
}

fn tetra_positions() -> Vec<DVec3> {
    vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z]
}

#[test]
fn obj_cube_with_quads_groups_and_negative_indices() {
    let m = load_closed("cube.obj", 8, 12, 1.0);
    assert!(
        m.warnings.iter().any(|w| w.contains("6 polygon")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn obj_agrees_with_tobj() {
    for name in ["cube.obj", "tetra.obj"] {
        let ours = load(name);
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(fixture(name), &opts).unwrap();
        let n_tris: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
        assert_eq!(ours.mesh.n_faces(), n_tris, "{name}");
        // Same triangles as sets of corner positions.
        let mut a: Vec<[i64; 9]> = Vec::new();
        for m in &models {
            for t in m.mesh.indices.chunks(3) {
                let mut k = [0i64; 9];
                for (c, &i) in t.iter().enumerate() {
                    for d in 0..3 {
                        k[3 * c + d] =
                            (m.mesh.positions[3 * i as usize + d] as f64 * 1e6).round() as i64;
                    }
                }
                a.push(k);
            }
        }
        let mut b: Vec<[i64; 9]> = ours
            .mesh
            .triangles()
            .iter()
            .map(|t| {
                let mut k = [0i64; 9];
                for (c, &i) in t.iter().enumerate() {
                    let p = ours.mesh.position(i);
                    for (d, v) in [p.x, p.y, p.z].into_iter().enumerate() {
                        k[3 * c + d] = (v * 1e6).round() as i64;
                    }
                }
                k
            })
            .collect();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "{name}");
    }
}

#[test]
fn ply_ascii_cube_with_colours() {
    let m = load_closed("cube_ascii.ply", 8, 12, 1.0);
    let c = m.colors.as_ref().expect("colours");
    assert_eq!(c[3], [90, 165, 7, 255]);
    assert!(m.scalars.is_empty());
}

#[test]
fn ply_binary_both_endians_with_extra_properties() {
    for name in ["tetra_be.ply", "tetra_le.ply"] {
        let m = load(name);
        assert_eq!(m.mesh.positions(), &tetra_positions()[..], "{name}");
        assert_eq!(
            m.mesh.triangles(),
            &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            "{name}"
        );
        check_closed_outward(&m, 1.0 / 6.0);
        let names: Vec<&str> = m.scalars.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["flags", "quality"]);
        assert_eq!(m.scalars[0].values, [0.0, -1.0, -2.0, -3.0]);
        assert_eq!(m.scalars[1].values, [0.0, 0.5, 1.0, 1.5]);
        assert_eq!(m.scalars[1].ty, mesh_io::ScalarType::F32);
        assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    }
}

#[test]
fn stl_ascii_and_binary_welded() {
    for name in ["tetra_ascii.stl", "tetra_binary.stl"] {
        let m = load_closed(name, 4, 4, 1.0 / 6.0);
        assert!(m.warnings.is_empty(), "{name}: {:?}", m.warnings);
    }
}

#[test]
fn off_cube() {
    load_closed("cube.off", 8, 12, 1.0);
}

#[test]
fn gltf_node_transforms_applied() {
    // tetra.gltf: translation (10,0,0) on the parent, scale 2 on the child holding the mesh.
    let m = load("tetra.gltf");
    let expect: Vec<DVec3> = tetra_positions()
        .iter()
        .map(|p| *p * 2.0 + DVec3::new(10.0, 0.0, 0.0))
        .collect();
    assert_eq!(m.mesh.positions(), &expect[..]);
    // Signed volume is translation invariant for a closed surface; scale 2 gives 8x.
    check_closed_outward(&m, 8.0 / 6.0);
    // tetra.glb: matrix = rotation by +90 degrees about z.
    let g = load("tetra.glb");
    let expect: Vec<DVec3> = tetra_positions()
        .iter()
        .map(|p| DVec3::new(-p.y, p.x, p.z))
        .collect();
    for (a, b) in g.mesh.positions().iter().zip(&expect) {
        assert!((*a - *b).length() < 1e-6, "{a} vs {b}");
    }
    check_closed_outward(&g, 1.0 / 6.0);
}

#[test]
fn landmark_files() {
    let lm = read_lm3(fixture("sample.lm3")).unwrap();
    assert_eq!(
        lm.labels,
        [
            "Outer left eye corner",
            "Nose tip",
            "Outer right eye corner"
        ]
    );
    assert_eq!(lm.get("Nose tip"), Some(DVec3::new(0.5, -10.0, 60.125)));
    assert_eq!(lm.points[2], DVec3::new(44.0, 31.0, -21.5));
    let l2 = read_lm2(fixture("sample.lm2")).unwrap();
    assert_eq!(l2.labels, ["Nose tip", "Chin middle"]);
    assert_eq!(l2.points, [[120.5, 200.0], [118.0, 330.25]]);
}

#[test]
fn unknown_extension_and_missing_file_are_errors() {
    let e = read_mesh(fixture("cube.xyz")).unwrap_err().to_string();
    assert!(e.contains("unknown mesh format"), "{e}");
    let e = read_mesh(fixture("does_not_exist.obj"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("does_not_exist.obj"), "{e}");
}
