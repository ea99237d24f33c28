//! Bad input gives an error naming the file, the line or byte offset and the problem.

use mesh_io::{read_mesh_from_bytes, Format, IoError, Location};

fn err(bytes: &[u8], f: Format) -> IoError {
    match read_mesh_from_bytes(bytes, f) {
        Ok(m) => panic!("accepted bad input: {} vertices", m.mesh.n_vertices()),
        Err(e) => e,
    }
}

fn at(e: &IoError) -> Option<Location> {
    match e {
        IoError::Malformed { at, .. } | IoError::Unsupported { at, .. } => Some(*at),
        _ => None,
    }
}

/// Each case: the format, bad input, where the error must point (`None`: not checked) and what
/// its message must contain (`""`: nothing in particular). A failure names the input.
fn check(cases: &[(Format, &[u8], Option<Location>, &str)]) {
    for &(f, bytes, loc, msg) in cases {
        let e = err(bytes, f);
        let input = String::from_utf8_lossy(bytes);
        if loc.is_some() {
            assert_eq!(at(&e), loc, "{input:?}: {e}");
        }
        assert!(e.to_string().contains(msg), "{input:?}: {e}");
    }
}

#[test]
fn obj_and_off_errors_name_the_line() {
    use Format::{Obj, Off};
    use Location::Line;
    check(&[
        (
            Obj,
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            Some(Line(4)),
            "<memory>: line 4: face refers to vertex 4",
        ),
        (
            Obj,
            b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
            Some(Line(2)),
            "not finite",
        ),
        (
            Obj,
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
            None,
            "line 4: face has 2 corner",
        ),
        (
            Obj,
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n",
            Some(Line(4)),
            "",
        ),
        (Obj, b"v 0 0 0\nv 1 0\n", Some(Line(2)), ""),
        (Obj, b"v 0 0 0\nv 1 0 0\n", None, "no faces"),
        (Obj, b"", None, "no faces"),
        (Obj, b"v 0 0 0\nf -2 1 1\n", Some(Line(2)), ""),
        (
            Off,
            b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
            Some(Line(6)),
            "",
        ),
        (
            Off,
            b"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
            None,
            "line 2: file ends after 0 of 1 faces",
        ),
        (Off, b"OFF\n99999999 1 0\n0 0 0\n", Some(Line(2)), ""),
        (
            Off,
            b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n1 2 3\n",
            None,
            "after the 3 vertices and 1 faces",
        ),
    ]);
}

fn ply_header(fmt: &str, nv: usize, nf: usize) -> String {
    format!("ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
}

fn binary_tri(nv_claim: usize, nf_claim: usize, idx: [i32; 3]) -> Vec<u8> {
    let mut b = ply_header("binary_little_endian", nv_claim, nf_claim).into_bytes();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for v in p {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b.push(3);
    for i in idx {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

#[test]
fn ply_errors() {
    let hdr = ply_header("binary_little_endian", 3, 1).len();
    // Valid file first (so the errors below are about the defects).
    assert!(read_mesh_from_bytes(&binary_tri(3, 1, [0, 1, 2]), Format::Ply).is_ok());
    // Index out of range: byte offset of the face record.
    let e = err(&binary_tri(3, 1, [0, 1, 7]), Format::Ply);
    assert_eq!(at(&e), Some(Location::Byte(hdr + 36)), "{e}");
    assert!(e.to_string().contains("vertex 7"), "{e}");
    // Header claims far more than the file holds: no allocation, error at the body start.
    let e = err(&binary_tri(3_000_000_000, 1, [0, 1, 2]), Format::Ply);
    assert!(e.to_string().contains("3000000000 records"), "{e}");
    // File far larger than the header claims.
    let mut b = binary_tri(3, 1, [0, 1, 2]);
    b.extend_from_slice(&binary_tri(3, 1, [0, 1, 2])[hdr..]);
    let e = err(&b, Format::Ply);
    assert!(e.to_string().contains("fewer records"), "{e}");
    // Truncated.
    let b = binary_tri(3, 1, [0, 1, 2]);
    let e = err(&b[..b.len() - 3], Format::Ply);
    assert!(matches!(at(&e), Some(Location::Byte(_))), "{e}");
    // Negative index.
    let e = err(&binary_tri(3, 1, [0, -1, 2]), Format::Ply);
    assert!(e.to_string().contains("invalid vertex index -1"), "{e}");
    // ASCII: bad number on line 12, NaN, trailing data, counts too large.
    let ascii = |nv: usize, body: &str| ply_header("ascii", nv, 1) + body;
    let (bad, nan, trailing, huge) = (
        ascii(3, "0 0 0\n1 0 0\n0 x 0\n3 0 1 2\n"),
        ascii(3, "0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n"),
        ascii(3, "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n"),
        ascii(1_000_000, "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
    );
    check(&[
        (Format::Ply, bad.as_bytes(), Some(Location::Line(12)), ""),
        (
            Format::Ply,
            nan.as_bytes(),
            None,
            "line 12: vertex 2 has a non-finite",
        ),
        (
            Format::Ply,
            trailing.as_bytes(),
            Some(Location::Line(14)),
            "",
        ),
        (Format::Ply, huge.as_bytes(), Some(Location::Line(3)), ""),
    ]);
    let e = err(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        Format::Ply,
    );
    assert!(e.to_string().contains("end_header"), "{e}");
    let e = err(b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n", Format::Ply);
    assert!(e.to_string().contains("empty mesh"), "{e}");
}

#[test]
fn stl_errors() {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&1000u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 50]);
    let e = err(&b, Format::Stl);
    assert!(e.to_string().contains("claims 1000 triangles"), "{e}");
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&1u32.to_le_bytes());
    for v in [0f32, 0., 0., 0., 0., 0., 1., 0., 0., f32::NAN, 1., 0.] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&[0, 0]);
    let e = err(&b, Format::Stl);
    assert_eq!(at(&e), Some(Location::Byte(84 + 36)), "{e}");
    let e = err(
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n",
        Format::Stl,
    );
    assert!(
        e.to_string().contains("line 6: facet has 2 vertices"),
        "{e}"
    );
    let e = err(
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
        Format::Stl,
    );
    assert!(
        e.to_string()
            .contains("file ends inside the facet opened on line 3"),
        "{e}"
    );
}

#[test]
fn gltf_errors() {
    let e = err(b"{not json", Format::Gltf);
    assert!(e.to_string().contains("invalid glTF"), "{e}");
    let e = err(b"glTF\x02\0\0\0\xff\0\0\0", Format::Glb);
    assert!(e.to_string().starts_with("<memory>:"), "{e}");
}

#[test]
fn bnt_errors() {
    let e = err(&[1, 0], Format::Bnt);
    assert!(
        e.to_string()
            .contains("byte 2: file ends while reading ncols"),
        "{e}"
    );
    let mut b = Vec::new();
    b.extend_from_slice(&100u16.to_le_bytes());
    b.extend_from_slice(&100u16.to_le_bytes());
    b.extend_from_slice(&(-1e9f64).to_le_bytes());
    b.extend_from_slice(&0u16.to_le_bytes());
    b.extend_from_slice(&50000u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 64]);
    let e = err(&b, Format::Bnt);
    assert!(
        e.to_string()
            .contains("byte 18: header claims 50000 doubles"),
        "{e}"
    );
}

#[test]
fn npy_errors() {
    let e =
        mesh_io::parse_npy_f32(b"\x93NUMPY\x01\x00\x10\x00{'descr': '<i4'}", "a.npy").unwrap_err();
    assert!(e.to_string().contains("unsupported"), "{e}");
    let e = mesh_io::parse_npy_f32(b"nope", "a.npy").unwrap_err();
    assert!(e.to_string().contains("a.npy: byte 0"), "{e}");
}

#[test]
fn npy_synthetic_f4_and_f8() {
    fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        while (10 + h.len() + 1) % 64 != 0 {
            h.push(' ');
        }
        h.push('\n');
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(h.len() as u16).to_le_bytes());
        b.extend_from_slice(h.as_bytes());
        b.extend_from_slice(data);
        b
    }
    let vals = [1.5f32, -2.0, 3.25, 0.0, 1e-3, 7.0];
    let d4: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
    let d8: Vec<u8> = vals
        .iter()
        .flat_map(|v| (*v as f64).to_le_bytes())
        .collect();
    let (s, v) = mesh_io::parse_npy_f32(&npy("<f4", "(2, 3)", &d4), "a.npy").unwrap();
    assert_eq!((s, v), (vec![2, 3], vals.to_vec()));
    let (s, v) = mesh_io::parse_npy_f32(&npy("<f8", "(6,)", &d8), "a.npy").unwrap();
    assert_eq!((s, v), (vec![6], vals.to_vec()));
    // Shape disagreeing with the data.
    let e = mesh_io::parse_npy_f32(&npy("<f4", "(2, 4)", &d4), "a.npy").unwrap_err();
    assert!(e.to_string().contains("does not match"), "{e}");
    let e = mesh_io::parse_npy_f32(
        &npy("<f4", "(1000000000, 1000000000, 1000000000)", &d4),
        "a.npy",
    )
    .unwrap_err();
    assert!(e.to_string().contains("does not match"), "{e}");
    let mut f = npy("<f4", "(2, 3)", &d4);
    let at = f.windows(5).position(|w| w == b"False").unwrap();
    f[at..at + 5].copy_from_slice(b"True ");
    let e = mesh_io::parse_npy_f32(&f, "a.npy").unwrap_err();
    assert!(e.to_string().contains("Fortran"), "{e}");
}

#[test]
fn ply_element_without_properties_and_huge_count_does_not_hang() {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement nothing 18446744073709551615\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    let m = read_mesh_from_bytes(&b, Format::Ply).unwrap();
    assert_eq!(m.mesh.n_faces(), 1);
}

#[test]
fn option_names_round_trip_and_bad_names_list_the_choices() {
    use mesh_io::{Format, IoError, LineMode, PlyEncoding, ScalarType};
    meshcore::choice::check_choice::<Format>("fbx").unwrap();
    meshcore::choice::check_choice::<PlyEncoding>("utf8").unwrap();
    meshcore::choice::check_choice::<ScalarType>("int").unwrap();
    meshcore::choice::check_choice::<LineMode>("fan").unwrap();
    match "utf8".parse::<PlyEncoding>() {
        Err(IoError::UnknownChoice(e)) => {
            assert_eq!(
                e.expected,
                ["ascii", "binary_little_endian", "binary_big_endian"]
            );
        }
        other => panic!("{other:?}"),
    }
}
