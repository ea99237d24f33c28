//! Faces outside the ICT model's span, one test per kind of `landmarks-eval
//! --beyond`, made from the shared paper set by the library generators: an expression past full
//! strength, a smooth non-rigid warp (`facemodel::random_warp`), another topology
//! (`scanprep::remesh`), a depth-camera-class scan with flying pixels
//! (`rangescan::add_flying_pixels`); and things that are not faces. Each test skips (or, with
//! `BIPOLAR_REQUIRE_SHARED` set, fails) when the paper set is absent.

use landmarks::{
    detect_visible, io, mesh_units_per_model_unit, DetectOptions, GenericModel, LandmarkName,
    VisibleLandmarks,
};
use meshcore::{DAffine3, DQuat, DVec3, TriMesh};
use rand::SeedableRng;
use rangescan::{Artifacts, DepthNoise, FlyingPixels, HeadPose, Quantisation, ScanOptions};

/// The paper-set face `name` in mm and its five true landmarks (mm); `None` without the data.
fn face_mm(name: &str) -> Option<(TriMesh, [DVec3; 5])> {
    let json = testsupport::paper_face("landmarks.json")?;
    let obj = testsupport::paper_face(&format!("{name}.obj"))?;
    let truth = io::select_five(&mesh_io::read_ict_landmarks(&json).unwrap()[name], name).unwrap();
    let mm = DAffine3::from_scale(DVec3::splat(10.0));
    let mesh = testsupport::read_mesh(obj).transformed(&mm);
    Some((mesh, truth.map(|p| p * 10.0)))
}

/// Detects with the default model and options (units from the face's size), toward `view`.
fn detect(mesh: &TriMesh, view: Option<DVec3>) -> VisibleLandmarks {
    let model = GenericModel::default_model().unwrap();
    let options = DetectOptions {
        mesh_units_per_model_unit: mesh_units_per_model_unit(mesh, &model).unwrap(),
        toward_viewer: view,
        ..DetectOptions::default()
    };
    detect_visible(mesh, &model, &options).unwrap_or_else(|e| panic!("not found: {e}"))
}

/// Asserts that every landmark is placed within `tol` mm of the truth.
fn assert_within(found: &VisibleLandmarks, truth: &[DVec3; 5], tol: f64) {
    for n in LandmarkName::ALL {
        let l = found.get(n).unwrap_or_else(|u| panic!("{n} unseen: {u}"));
        let e = (l.position - truth[n as usize]).length();
        assert!(e < tol, "{n} is {e} mm off (at most {tol})");
    }
}

/// A rigid motion of the whole face (detection must not depend on the pose).
fn motion() -> DAffine3 {
    DAffine3::from_rotation_translation(
        DQuat::from_axis_angle(DVec3::new(0.4, 1.0, -0.3).normalize(), 0.9),
        DVec3::new(40.0, -25.0, 300.0),
    )
}

#[test]
fn an_expression_at_1_7_times_full_strength_is_found() {
    let (Some((neutral, tn)), Some((surprise, ts))) =
        (face_mm("id1_neutral"), face_mm("id1_surprise"))
    else {
        return;
    };
    // neutral + 1.7 (surprise - neutral): the same topology, the expression past its span.
    let k = 1.7;
    let pos: Vec<DVec3> = neutral
        .positions()
        .iter()
        .zip(surprise.positions())
        .map(|(n, s)| *n + (*s - *n) * k)
        .collect();
    let strong = TriMesh::new(pos, neutral.triangles().to_vec()).unwrap();
    let truth: [DVec3; 5] = std::array::from_fn(|i| tn[i] + (ts[i] - tn[i]) * k);
    let t = motion();
    let found = detect(&strong.transformed(&t), None);
    assert_within(&found, &truth.map(|p| t.transform_point3(p)), 4.0);
}

#[test]
fn a_face_warped_by_a_few_millimetres_is_found() {
    let Some((face, truth)) = face_mm("id2_neutral") else {
        return;
    };
    let ids = face_landmark_vertices(&face, &truth);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let w = facemodel::random_warp(&face, &truth, &mut rng).unwrap();
    assert!(w.size_mm >= 2.0, "{}", w.size_mm);
    let moved = ids.map(|v| w.mesh.position(v));
    let t = motion();
    let found = detect(&w.mesh.transformed(&t), None);
    assert_within(&found, &moved.map(|p| t.transform_point3(p)), 4.0);
}

/// The vertices at the true landmarks of a paper-set face.
fn face_landmark_vertices(face: &TriMesh, truth: &[DVec3; 5]) -> [u32; 5] {
    truth.map(|p| {
        let (v, d) = face
            .positions()
            .iter()
            .enumerate()
            .map(|(i, q)| (i as u32, (*q - p).length()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        assert!(d < 1e-6, "a landmark of the paper set is a vertex");
        v
    })
}

#[test]
fn a_face_of_another_topology_is_found() {
    let Some((face, truth)) = face_mm("id3_neutral") else {
        return;
    };
    // 3 mm edges on vertices that are not the model's.
    let m = scanprep::remesh(&face, 3.0).unwrap();
    assert_ne!(m.n_vertices(), face.n_vertices());
    let t = motion();
    let found = detect(&m.transformed(&t), None);
    assert_within(&found, &truth.map(|p| t.transform_point3(p)), 4.0);
}

#[test]
fn a_depth_camera_scan_with_flying_pixels_is_found() {
    let Some((face, truth)) = face_mm("id4_neutral") else {
        return;
    };
    let marks: Vec<(String, DVec3)> = LandmarkName::ALL
        .iter()
        .zip(truth)
        .map(|(n, p)| (n.lm3_label().to_string(), p))
        .collect();
    // 3 mm pitch, depth in steps of 2 mm, 1 mm noise, turned by 10 degrees.
    let mut scan = rangescan::scan_with_landmarks(
        &face,
        &marks,
        &ScanOptions {
            input_mm_per_unit: 1.0,
            pitch_mm: 3.0,
            pose: HeadPose {
                yaw_deg: 10.0,
                pitch_deg: 0.0,
            },
            artifacts: Artifacts {
                noise: Some(DepthNoise { sigma_mm: 1.0 }),
                quantisation: Some(Quantisation { step_mm: 2.0 }),
                ..Artifacts::none()
            },
            seed: 3,
            ..ScanOptions::default()
        },
    )
    .unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let flying =
        rangescan::add_flying_pixels(&mut scan.grid, &FlyingPixels::default(), &mut rng).unwrap();
    assert!(flying > 20, "{flying}");
    let nose = scan.landmarks[LandmarkName::NoseTip as usize].position;
    let cleaned = scanprep::clean(
        scanprep::Input::Grid(&scan.grid),
        &scanprep::CleanOptions {
            crop: Some(scanprep::Crop::around(nose)),
            ..scanprep::CleanOptions::default()
        },
    )
    .unwrap();
    let truth: [DVec3; 5] = std::array::from_fn(|k| scan.landmarks[k].position);
    let found = detect(&cleaned.mesh, Some(DVec3::Z));
    // The depth-camera target of issue 31 is 4 mm median for the outer corners; every
    // landmark within 6 mm on this face.
    assert_within(&found, &truth, 6.0);
}

#[test]
fn non_faces_in_millimetres_are_refused() {
    let model = GenericModel::default_model().unwrap();
    let mm: meshcore::units::Units = model.units.parse().unwrap();
    let options = DetectOptions {
        mesh_units_per_model_unit: mm.factor_to(meshcore::units::Units::Millimetre),
        ..DetectOptions::default()
    };
    // The back of a head: an ellipsoid cap 150 x 190 x 60 mm.
    let back = meshcore::shapes::grid(60, 60, meshcore::shapes::Diagonals::Alternating, |i, j| {
        let (u, v) = (i as f64 / 60.0 * 2.0 - 1.0, j as f64 / 60.0 * 2.0 - 1.0);
        let r2 = (u * u + v * v).min(1.0);
        DVec3::new(75.0 * u, 95.0 * v, 60.0 * (1.0 - r2).sqrt())
    })
    .unwrap();
    // A plane of 2 mm cells with 1 mm noise.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let plane = meshcore::shapes::grid(80, 80, meshcore::shapes::Diagonals::Alternating, |i, j| {
        DVec3::new(
            2.0 * i as f64,
            2.0 * j as f64,
            facemodel::standard_normal(&mut rng),
        )
    })
    .unwrap();
    for (name, m) in [("back of a head", back), ("noisy plane", plane)] {
        let r = detect_visible(&m.transformed(&motion()), &model, &options);
        assert!(r.is_err(), "{name} was let through: {r:?}");
    }
}
