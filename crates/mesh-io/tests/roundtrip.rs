//! Round trips through every writer and reader, on random meshes (proptest).

use mesh_io::{
    read_mesh_from_bytes, write_glb_to_bytes, write_mesh_to_bytes, write_ply_to_bytes, Format,
    GltfScene, LoadedMesh, PlyEncoding, PlyWriteOptions, ScalarField, ScalarType,
};
use meshcore::{DVec3, TriMesh};
use proptest::prelude::*;

fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3f64..1e3,
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
        Just(0.0),
        Just(-0.0),
    ]
}

/// `mesh` with every coordinate clamped to `[-1e30, 1e30]` (finite in f32).
fn clamped(mesh: &TriMesh) -> TriMesh {
    let p = mesh
        .positions()
        .iter()
        .map(|p| p.clamp(DVec3::splat(-1e30), DVec3::splat(1e30)))
        .collect();
    TriMesh::new(p, mesh.triangles().to_vec()).unwrap()
}

prop_compose! {
    fn random_mesh()(n in 3usize..30)
        (pos in prop::collection::vec((coord(), coord(), coord()), n),
         tris in prop::collection::vec((0..n as u32, 0..n as u32, 0..n as u32), 1..40),
         colors in prop::collection::vec(any::<[u8; 4]>(), n),
         s64 in prop::collection::vec(coord(), n),
         s32 in prop::collection::vec(-1e6f64..1e6, n))
        -> (TriMesh, Vec<[u8; 4]>, Vec<ScalarField>)
    {
        let p = pos.into_iter().map(|(x, y, z)| DVec3::new(x, y, z)).collect();
        let t = tris.into_iter().map(|(a, b, c)| [a, b, c]).collect();
        let scalars = vec![
            ScalarField { name: "distance".into(), values: s64, ty: ScalarType::F64 },
            ScalarField { name: "quality".into(), values: s32, ty: ScalarType::F32 },
        ];
        (TriMesh::new(p, t).unwrap(), colors, scalars)
    }
}

fn same_bits(a: &[DVec3], b: &[DVec3]) -> bool {
    // Exact equality, with -0.0 == 0.0.
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| p == q)
}

fn as_f32(p: DVec3) -> DVec3 {
    DVec3::new(p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn ply_all_encodings_exact((mesh, colors, scalars) in random_mesh()) {
        for enc in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian] {
            let opts = PlyWriteOptions { encoding: enc, colors: Some(&colors), scalars: &scalars };
            let bytes = write_ply_to_bytes(&mesh, &opts).unwrap();
            let back = read_mesh_from_bytes(&bytes, Format::Ply).unwrap();
            prop_assert!(same_bits(back.mesh.positions(), mesh.positions()), "{:?}", enc);
            prop_assert_eq!(back.mesh.triangles(), mesh.triangles());
            prop_assert_eq!(back.colors.as_ref(), Some(&colors));
            prop_assert_eq!(back.scalars.len(), 2);
            prop_assert_eq!(&back.scalars[0], &scalars[0]);
            let want32: Vec<f64> = scalars[1].values.iter().map(|v| *v as f32 as f64).collect();
            prop_assert_eq!(&back.scalars[1].values, &want32);
        }
    }

    #[test]
    fn text_formats_exact((mesh, _c, _s) in random_mesh()) {
        for f in [Format::Obj, Format::Off] {
            let bytes = write_mesh_to_bytes(&LoadedMesh::new(mesh.clone()), f).unwrap();
            let back = read_mesh_from_bytes(&bytes, f).unwrap();
            prop_assert!(same_bits(back.mesh.positions(), mesh.positions()), "{:?}", f);
            prop_assert_eq!(back.mesh.triangles(), mesh.triangles());
        }
    }

    #[test]
    fn stl_corners_within_f32((mesh, _c, _s) in random_mesh()) {
        let small = clamped(&mesh);
        let bytes = write_mesh_to_bytes(&LoadedMesh::new(small.clone()), Format::Stl).unwrap();
        let back = read_mesh_from_bytes(&bytes, Format::Stl).unwrap();
        prop_assert_eq!(back.mesh.n_faces(), small.n_faces());
        for f in 0..small.n_faces() as u32 {
            let a = small.face_corners(f).map(as_f32);
            let b = back.mesh.face_corners(f);
            prop_assert_eq!(a, b);
        }
        // Exact welding: no two vertices share a position.
        prop_assert_eq!(mesh_io::count_duplicate_vertices(&back.mesh), 0);
    }

    #[test]
    fn glb_within_f32_with_colours((mesh, colors, _s) in random_mesh()) {
        let small = clamped(&mesh);
        let mut scene = GltfScene::default();
        scene.add_mesh("m", &small, Some(colors.clone()));
        scene.add_points("pts", &small.positions()[..2], [255, 0, 0, 255]);
        let bytes = write_glb_to_bytes(&scene).unwrap();
        let back = read_mesh_from_bytes(&bytes, Format::Glb).unwrap();
        let want: Vec<DVec3> = small.positions().iter().map(|p| as_f32(*p)).collect();
        prop_assert_eq!(back.mesh.positions(), &want[..]);
        prop_assert_eq!(back.mesh.triangles(), small.triangles());
        prop_assert_eq!(back.colors.as_ref(), Some(&colors));
        prop_assert!(back.warnings.iter().any(|w| w.contains("1 point/line primitive")));
    }
}

#[test]
fn glb_points_and_polylines_are_valid_gltf() {
    let mesh = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).unwrap();
    let mut scene = GltfScene::default();
    scene.add_mesh("face", &mesh, None);
    scene.add_points(
        "descriptor points",
        &[DVec3::X, DVec3::Y, DVec3::Z],
        [255, 0, 0, 255],
    );
    let ring: Vec<DVec3> = (0..10)
        .map(|i| DVec3::new((i as f64).cos(), (i as f64).sin(), 0.0))
        .collect();
    scene.add_polyline(
        "level curve",
        &ring,
        mesh_io::LineMode::Loop,
        [0, 0, 255, 255],
    );
    scene.add_polyline(
        "segments",
        &ring,
        mesh_io::LineMode::Segments,
        [0, 255, 0, 255],
    );
    scene.add_polyline(
        "strip",
        &ring[..3],
        mesh_io::LineMode::Strip,
        [9, 9, 9, 255],
    );
    let bytes = write_glb_to_bytes(&scene).unwrap();
    // Independent check with the gltf crate (full validation).
    let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
    let modes: Vec<(String, gltf::mesh::Mode, usize)> = doc
        .meshes()
        .map(|m| {
            let p = m.primitives().next().unwrap();
            let r = p.reader(|b| Some(&buffers[b.index()]));
            (
                m.name().unwrap().to_string(),
                p.mode(),
                r.read_positions().unwrap().count(),
            )
        })
        .collect();
    use gltf::mesh::Mode::*;
    assert_eq!(
        modes,
        vec![
            ("face".to_string(), Triangles, 3),
            ("descriptor points".to_string(), Points, 3),
            ("level curve".to_string(), LineLoop, 10),
            ("segments".to_string(), Lines, 10),
            ("strip".to_string(), LineStrip, 3),
        ]
    );
    let pts = doc.meshes().nth(1).unwrap().primitives().next().unwrap();
    let r = pts.reader(|b| Some(&buffers[b.index()]));
    let cols: Vec<[u8; 4]> = r.read_colors(0).unwrap().into_rgba_u8().collect();
    assert_eq!(cols, vec![[255, 0, 0, 255]; 3]);
    // Odd number of points for LINES is refused.
    let mut bad = GltfScene::default();
    bad.add_polyline(
        "odd",
        &ring[..3],
        mesh_io::LineMode::Segments,
        [0, 0, 0, 255],
    );
    assert!(write_glb_to_bytes(&bad).is_err());
}

#[test]
fn lm3_round_trip() {
    let lm = mesh_io::Landmarks3d {
        labels: vec!["Nose tip".into(), "Outer left eye corner".into()],
        points: vec![
            DVec3::new(0.1, -2.5e-7, 1e10),
            DVec3::new(-45.25, 30.0, 0.0),
        ],
        ..Default::default()
    };
    let dir = std::env::temp_dir().join(format!("mesh-io-lm3-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("x.lm3");
    mesh_io::write_lm3(&p, &lm).unwrap();
    assert_eq!(mesh_io::read_lm3(&p).unwrap(), lm);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn repairs_keep_extras_aligned() {
    // Two triangles as a soup sharing an edge, plus a degenerate face.
    let soup = testsupport::shapes::triangle_soup();
    let orig = soup.positions().to_vec();
    let mut m = LoadedMesh::new(soup);
    assert_eq!(m.warnings.len(), 2, "{:?}", m.warnings);
    m.colors = Some((0..6).map(|i| [i, 0, 0, 255]).collect());
    m.grid_index = Some((10..16).collect());
    let s = m.drop_degenerate(0.0);
    assert_eq!(s.removed_faces, 1);
    let s = m.weld(0.0);
    assert_eq!(s.welded_vertices, 2);
    assert_eq!(m.mesh.n_vertices(), 4);
    assert_eq!(m.mesh.n_faces(), 2);
    assert_eq!(
        m.colors
            .as_ref()
            .unwrap()
            .iter()
            .map(|c| c[0])
            .collect::<Vec<_>>(),
        [0, 1, 2, 4]
    );
    assert_eq!(m.grid_index.as_ref().unwrap(), &[10, 11, 12, 14]);
    for (v, p) in m.mesh.positions().iter().enumerate() {
        assert_eq!(*p, orig[m.grid_index.as_ref().unwrap()[v] as usize - 10]);
    }
    assert!(m.warnings.is_empty());
}

#[test]
fn lm3_notes_round_trip_and_readers_skip_them() {
    let lm = mesh_io::Landmarks3d {
        labels: vec!["Nose tip".into()],
        points: vec![DVec3::new(1.0, 2.0, 3.0)],
        ..Default::default()
    };
    let dir = std::env::temp_dir().join(format!("mesh-io-lm3n-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("x.lm3");
    let notes = vec![
        "not visible: Outer left eye corner: occluded".to_string(),
        "scanner: seed 3".to_string(),
    ];
    mesh_io::write_lm3_with_notes(&p, &lm, &notes).unwrap();
    assert_eq!(mesh_io::read_lm3(&p).unwrap(), lm);
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(mesh_io::parse_lm3_notes(&bytes), notes);
    // A plain file has no notes.
    mesh_io::write_lm3(&p, &lm).unwrap();
    assert!(mesh_io::parse_lm3_notes(&std::fs::read(&p).unwrap()).is_empty());
    // Notes that would break the layout are refused.
    for bad in ["", "two\nlines", "3 landmarks:"] {
        assert!(mesh_io::write_lm3_with_notes(&p, &lm, &[bad.to_string()]).is_err());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn landmark_json_round_trips_and_every_layout_reads() {
    let dir = std::env::temp_dir().join(format!("mesh-io-lmjson-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut lm = mesh_io::Landmarks3d::default();
    lm.push("nose_tip", DVec3::new(0.1, -2.5e-7, 12.0), Some(7));
    lm.push("outer_eye_left", DVec3::new(4.0, 3.0, 8.0), Some(9));
    lm.confidences = vec![Some(0.9), None];
    lm.attributes = vec![("confidence".into(), 0.75), ("fit_rms".into(), 0.01)];
    let p = dir.join("lm.json");
    mesh_io::write_landmarks_json(&p, &lm).unwrap();
    let back = mesh_io::read_landmark_file(&p, None).unwrap();
    assert_eq!(back, lm);
    // A flat object: positions only.
    let flat =
        mesh_io::parse_landmarks_json(br#"{"a": [1, 2, 3], "note": "x"}"#, "f.json").unwrap();
    assert_eq!(flat.labels, ["a"]);
    assert!(flat.vertices.is_empty() && flat.confidences.is_empty());
    let e = mesh_io::parse_landmarks_json(br#"{"a": [1, 2]}"#, "g.json").unwrap_err();
    assert!(
        e.to_string().contains("g.json: a: expected [x, y, z]"),
        "{e}"
    );
    // ICT layout: the face named like the mesh, with vertex ids.
    let ict = dir.join("landmarks.json");
    std::fs::write(
        &ict,
        r#"{"vertex_ids": {"nose_tip": 5}, "faces": {"f1": {"nose_tip": [0, 0, 12], "right_eye_outer": [-4, 3, 8]}}}"#,
    )
    .unwrap();
    let f1 = mesh_io::read_landmark_file(&ict, Some("f1")).unwrap();
    assert_eq!(f1.get("nose_tip"), Some(DVec3::new(0.0, 0.0, 12.0)));
    assert_eq!(f1.vertex(f1.index("nose_tip").unwrap()), Some(5));
    assert_eq!(f1.vertex(f1.index("right_eye_outer").unwrap()), None);
    let e = mesh_io::read_landmark_file(&ict, Some("f2")).unwrap_err();
    assert!(e.to_string().contains("it has: f1"), "{e}");
    assert_eq!(mesh_io::read_ict_landmarks(&ict).unwrap()["f1"], f1);
    let e = mesh_io::read_landmark_file(dir.join("missing.lm3"), None).unwrap_err();
    assert!(matches!(
        e,
        mesh_io::IoError::Io(meshcore::FileError { action: "read", .. })
    ));
    assert!(std::error::Error::source(&e).is_some());
    std::fs::remove_dir_all(&dir).ok();
}
