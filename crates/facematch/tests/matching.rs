//! Enrolment and identification on virtual range scans of paper-set faces (needs the shared
//! data: skipped, and said so, without it).

use facematch::{enroll, prepare, Gallery, MatchOptions, ScanInput, Template};
use meshcore::{DAffine3, DQuat, DVec3, TriMesh};
use rangescan::{HeadPose, ScanOptions};

/// A frontal (or turned) scan of a paper-set face (cm) with the default artifacts.
fn scan(mesh: &TriMesh, yaw_deg: f64, seed: u64) -> mesh_io::BntGrid {
    rangescan::scan(
        mesh,
        &ScanOptions {
            input_mm_per_unit: 10.0,
            pose: HeadPose {
                yaw_deg,
                pitch_deg: 0.0,
            },
            seed,
            ..ScanOptions::default()
        },
    )
    .unwrap()
    .grid
}

#[test]
fn enrol_then_identify_ranks_the_same_person_first_and_templates_round_trip() {
    let Some([a, b, c, probe]) = testsupport::paper_meshes([
        "id1_neutral.obj",
        "id2_neutral.obj",
        "id3_neutral.obj",
        "id1_happiness.obj",
    ]) else {
        return;
    };
    let o = MatchOptions::default();
    let dir = tempfile::tempdir().unwrap();
    for (k, (m, id)) in [(&a, "id1"), (&b, "id2"), (&c, "id3")]
        .into_iter()
        .enumerate()
    {
        let g = scan(m, 0.0, 11 + k as u64);
        let t = enroll(ScanInput::Grid(&g), id, &format!("{id}.bnt"), &o).unwrap();
        assert_eq!(t.views.len(), 8);
        assert!(
            t.description.sets.iter().all(Result::is_ok),
            "{id}: {:?}",
            t.description.sets
        );
        // Bit-identical round trip, and under 200 kB.
        let bytes = t.to_bytes();
        assert!(bytes.len() < 200_000, "{id}: {} bytes", bytes.len());
        assert_eq!(Template::from_bytes(&bytes, id).unwrap(), t);
        t.write(&dir.path().join(format!("{id}.bpt"))).unwrap();
    }
    let gallery = Gallery::open(dir.path(), &o).unwrap();
    let p = scan(&probe, 20.0, 5);
    let d = prepare(ScanInput::Grid(&p), &o)
        .unwrap()
        .describe(&o, true)
        .unwrap();
    assert!(
        d.moved.iter().all(|m| !m.is_empty()),
        "the search moved every pair"
    );
    let ranking = gallery.identify(&d, &o);
    assert_eq!(ranking.len(), 3);
    assert_eq!(ranking[0].identity, "id1", "{ranking:#?}");
    assert!(ranking[0].score < ranking[1].score);
    // A probe turned by 20 degrees is compared with a view of each template.
    assert!(
        matches!(
            ranking[0].comparison.view,
            facematch::ViewUse::Matched { .. }
        ),
        "{:?}",
        ranking[0].comparison.view
    );
}

#[test]
fn a_probe_scores_alike_after_a_rigid_motion_and_in_other_units() {
    let Some([a, probe]) = testsupport::paper_meshes(["id2_neutral.obj", "id2_neutral.obj"]) else {
        return;
    };
    let o = MatchOptions::default();
    let g = scan(&a, 0.0, 3);
    let t = enroll(ScanInput::Grid(&g), "id2", "id2.bnt", &o).unwrap();
    // The probe: a second scan, cleaned into a mesh; then the same mesh moved rigidly, in cm.
    let p = scan(&probe, 0.0, 4);
    let mesh = mesh_io::bnt_grid_to_mesh(&p, &Default::default())
        .unwrap()
        .mesh;
    let motion = DAffine3::from_rotation_translation(
        DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.5, 0.2),
        DVec3::new(12.0, -40.0, 7.0),
    );
    let score = |m: &TriMesh, scanner: DVec3, units| {
        let s = prepare(
            ScanInput::Mesh {
                mesh: m,
                units,
                scanner: Some(scanner),
            },
            &o,
        )
        .unwrap();
        facematch::compare(&s.describe(&o, true).unwrap(), &t, &o).score
    };
    let s0 = score(&mesh, DVec3::Z, None);
    let moved_cm = TriMesh::new(
        mesh.positions()
            .iter()
            .map(|p| motion.transform_point3(*p) / 10.0)
            .collect(),
        mesh.triangles().to_vec(),
    )
    .unwrap();
    let (moved_cm, _) = testsupport::renumbered(&moved_cm);
    let s1 = score(&moved_cm, motion.matrix3 * DVec3::Z, None);
    assert!(s0.is_finite() && s0 < o.verify_threshold, "{s0}");
    // Cleaning decimates in vertex order, so a renumbered probe is not the same mesh after
    // cleaning: the score moves by the decimation's noise, far less than the threshold.
    assert!(
        s1.is_finite() && (s1 - s0).abs() <= 0.25 * o.verify_threshold,
        "{s0} vs {s1} after a rigid motion and a renumbering, in cm"
    );
}

#[test]
fn a_face_before_a_wall_is_found() {
    let Some([a]) = testsupport::paper_meshes(["id3_neutral.obj"]) else {
        return;
    };
    // A 25 x 25 cm wall 25 cm behind the nose tip (cm), wider than the head: the uncropped
    // scan is mostly wall.
    let nose = a.position(4857);
    let n = a.n_vertices() as u32;
    let c = nose - DVec3::new(0.0, 0.0, 25.0);
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| c + DVec3::new(12.5 * x, 12.5 * y, 0.0));
    let positions: Vec<DVec3> = a.positions().iter().copied().chain(corners).collect();
    let mut triangles = a.triangles().to_vec();
    triangles.extend([[n, n + 1, n + 2], [n, n + 2, n + 3]]);
    let scene = TriMesh::new(positions, triangles).unwrap();
    let o = MatchOptions::default();
    let sc = rangescan::scan(
        &scene,
        &ScanOptions {
            input_mm_per_unit: 10.0,
            seed: 21,
            ..ScanOptions::default()
        },
    )
    .unwrap();
    let s = prepare(ScanInput::Grid(&sc.grid), &o).unwrap();
    // The face is found, its nose tip (the ICT model's vertex 4857) within 5 mm; the crop
    // leaves the wall out.
    let truth = sc.scan_from_input.transform_point3(nose);
    let found = s
        .detected
        .get(landmarks::LandmarkName::NoseTip)
        .unwrap()
        .position;
    assert!(
        (found - truth).length() < 5.0,
        "nose tip at {found:?}, truth {truth:?}; notes {:?}",
        s.notes
    );
    // The crop: 100 mm around the found nose tip, within 5 mm of the truth; the wall is 250 mm
    // behind.
    assert!(
        s.mesh
            .positions()
            .iter()
            .all(|p| (*p - truth).length() < 105.0),
        "the prepared scan reaches beyond the crop: {:?}",
        s.mesh
            .positions()
            .iter()
            .map(|p| (*p - truth).length())
            .fold(0.0, f64::max)
    );
}

fn with_prepare(prepare: facematch::PrepareOptions) -> MatchOptions {
    MatchOptions {
        prepare,
        ..MatchOptions::default()
    }
}

#[test]
fn the_crop_around_the_detected_nose_tip() {
    let Some([a]) = testsupport::paper_meshes(["id2_neutral.obj"]) else {
        return;
    };
    let grid = scan(&a, 0.0, 31);
    let uncropped = with_prepare(facematch::PrepareOptions {
        crop_radius_mm: None,
        ..MatchOptions::default().prepare
    });
    let wide = with_prepare(facematch::PrepareOptions {
        crop_radius_mm: Some(400.0),
        ..MatchOptions::default().prepare
    });
    let first = prepare(ScanInput::Grid(&grid), &uncropped).unwrap();
    let kept = prepare(ScanInput::Grid(&grid), &wide).unwrap();
    // 400 mm around the nose tip holds the whole scan: the same mesh, the same landmarks,
    // and no second detection.
    assert_eq!(kept.mesh, first.mesh);
    assert_eq!(kept.detected, first.detected);
    assert_eq!(kept.times.crop_detect, std::time::Duration::ZERO);
    // The default crop (100 mm) cuts the scan, and detection runs again on what is left.
    let cut = prepare(ScanInput::Grid(&grid), &MatchOptions::default()).unwrap();
    assert!(cut.mesh.n_vertices() < first.mesh.n_vertices());
    assert!(cut.times.crop_detect > std::time::Duration::ZERO);
    // `crop_keeps_detection` crops the first cleaning instead and keeps its landmarks.
    let keep = with_prepare(facematch::PrepareOptions {
        crop_keeps_detection: true,
        ..MatchOptions::default().prepare
    });
    assert_ne!(
        keep.template_settings(),
        MatchOptions::default().template_settings()
    );
    let first = prepare(ScanInput::Grid(&grid), &uncropped).unwrap();
    let kept = prepare(ScanInput::Grid(&grid), &keep).unwrap();
    // The crop cuts the first cleaning: fewer vertices, each one of the first cleaning's.
    assert!(kept.mesh.n_vertices() < first.mesh.n_vertices());
    let nose = first.mesh.position(
        first.detected.landmarks[4]
            .as_ref()
            .expect("the nose tip is seen")
            .vertex,
    );
    for p in kept.mesh.positions() {
        assert!(first.mesh.positions().contains(p));
        assert!((*p - nose).length() <= 100.0 + 1e-9);
    }
    // The landmarks are the first detection's, at the same places, on the cut's vertices.
    assert_eq!(kept.times.crop_detect, std::time::Duration::ZERO);
    for (k, f) in kept
        .detected
        .landmarks
        .iter()
        .zip(&first.detected.landmarks)
    {
        match (k, f) {
            (Ok(k), Ok(f)) => {
                assert_eq!(k.position, f.position);
                assert_eq!(kept.mesh.position(k.vertex), f.position);
                assert_eq!(k.confidence, f.confidence);
            }
            (k, f) => assert_eq!(k.is_err(), f.is_err()),
        }
    }
}

#[test]
fn detect_landmarks_finds_what_prepare_found_on_its_scan() {
    let Some([face]) = testsupport::paper_meshes(["id2_neutral.obj"]) else {
        return;
    };
    let o = MatchOptions::default();
    let p = prepare(ScanInput::Grid(&scan(&face, 10.0, 3)), &o).unwrap();
    let generic = landmarks::GenericModel::default_model().unwrap();
    let options = landmarks::DetectOptions {
        toward_viewer: Some(p.scanner),
        ..o.prepare.detect
    };
    let found = facematch::detect_landmarks(&p.mesh, &generic, &options, 0).unwrap();
    assert_eq!(found, p.detected);
    // On a smoothed copy the landmarks stay on the scan's own vertices.
    let smoothed = facematch::detect_landmarks(&p.mesh, &generic, &options, 3).unwrap();
    for l in smoothed.landmarks.iter().flatten() {
        assert_eq!(l.position, p.mesh.position(l.vertex));
    }
    // A mesh with no face is no face, with the detector's reason.
    let flat = meshcore::shapes::icosphere(2);
    let e = facematch::detect_landmarks(&flat, &generic, &options, 0).unwrap_err();
    assert!(matches!(e, facematch::MatchError::NoFace(_)), "{e}");
}
