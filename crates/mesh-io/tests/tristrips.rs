//! PLY files whose triangles are stored as triangle strips (`element tristrips`, `-1` restarts),
//! as scanner software writes them.

use mesh_io::{read_mesh_from_bytes, Format};
use meshcore::{DVec3, Topology};

/// A 3 x 2 grid of quads (4 x 3 vertices, row-major) as two strips, one per row of quads,
/// separated by -1; the second strip ends with a repeated vertex (a degenerate triangle).
fn strips() -> Vec<i32> {
    vec![0, 4, 1, 5, 2, 6, 3, 7, -1, 4, 8, 5, 9, 6, 10, 7, 11, 11]
}

fn vertices() -> Vec<DVec3> {
    (0..12)
        .map(|i| DVec3::new((i % 4) as f64, -((i / 4) as f64), 0.0))
        .collect()
}

fn ascii() -> Vec<u8> {
    let v = vertices();
    let s = strips();
    let mut t = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n",
        v.len()
    );
    for p in &v {
        t.push_str(&format!("{} {} {}\n", p.x, p.y, p.z));
    }
    t.push_str(&s.len().to_string());
    for i in &s {
        t.push_str(&format!(" {i}"));
    }
    t.push('\n');
    t.into_bytes()
}

fn binary(big_endian: bool) -> Vec<u8> {
    let v = vertices();
    let s = strips();
    let enc = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!(
        "ply\nformat {enc} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n",
        v.len()
    )
    .into_bytes();
    let f32b = |x: f32| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i32b = |x: i32| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for p in &v {
        for c in [p.x, p.y, p.z] {
            b.extend_from_slice(&f32b(c as f32));
        }
    }
    b.extend_from_slice(&i32b(s.len() as i32));
    for &i in &s {
        b.extend_from_slice(&i32b(i));
    }
    b
}

#[test]
fn strips_are_decoded_with_alternating_winding_and_restarts() {
    for bytes in [ascii(), binary(false), binary(true)] {
        let m = read_mesh_from_bytes(&bytes, Format::Ply).unwrap();
        assert_eq!(m.mesh.n_vertices(), 12);
        // 6 quads = 12 triangles; the joint's repeated vertex gives one degenerate triangle.
        assert_eq!(m.mesh.n_faces(), 12);
        assert!(
            m.warnings
                .iter()
                .any(|w| w.contains("2 triangle strip(s)") && w.contains("1 degenerate")),
            "{:?}",
            m.warnings
        );
        // Every triangle faces the same way (+z), the grid is one oriented manifold patch.
        for f in 0..12 {
            assert!(m.mesh.face_normal(f).z > 0.99, "face {f}");
        }
        let t = Topology::new(&m.mesh);
        assert!(t.inconsistent_edges().is_empty() && t.non_manifold_edges().is_empty());
        assert_eq!(t.boundary_loops().len(), 1);
        assert!((m.mesh.area() - 6.0).abs() < 1e-12);
    }
}

#[test]
fn bad_strip_indices_are_errors() {
    let mut b = String::from_utf8(ascii()).unwrap();
    b = b.replace(" 11 11\n", " 12 11\n");
    let e = read_mesh_from_bytes(b.as_bytes(), Format::Ply)
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 12"), "{e}");
    let b = String::from_utf8(ascii()).unwrap().replace(" -1 ", " -2 ");
    let e = read_mesh_from_bytes(b.as_bytes(), Format::Ply)
        .unwrap_err()
        .to_string();
    assert!(e.contains("invalid vertex index -2"), "{e}");
}
