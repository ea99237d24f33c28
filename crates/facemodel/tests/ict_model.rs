//! The crate on the real ICT model and paper set of the shared data folder (skipped when it
//! is absent): the sampled faces are pinned bit for bit, the ground-truth landmark vertices
//! agree with `model.json` and `landmarks.json`, and the face frame of the paper faces is
//! orthonormal with a plausible static area.

use facemodel::{
    face_frame, load_face_set, random_rigid_motion, static_mask, FaceModel, LEFT_EYE_OUTER,
    NOSE_TIP, RIGHT_EYE_OUTER,
};
use meshcore::TriMesh;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// FNV-1a (64 bit) over the little-endian bytes of the `f64` bits of every vertex coordinate
/// (x, y, z), in vertex order.
fn digest(mesh: &TriMesh) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in mesh.positions() {
        for c in p.to_array() {
            for b in c.to_bits().to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    h
}

/// (seed, digest) of the sampled faces.
const PINNED: [(u64, u64); 3] = [
    (1, 0xc6c4_0fbc_7305_1b7b),
    (2, 0x17f1_0dfd_dc75_13db),
    (3, 0x3ace_7802_7c93_f4bb),
];

/// Faces sampled as `cargo xtask landmarks-eval` samples them, pinned to the digests the
/// sampler gave in xtask before it moved here (`xtask/src/facemodel.rs` at commit 6de58c2).
/// Recipe per seed: `ChaCha8Rng::seed_from_u64(seed)`, then `random_identity`,
/// `random_expression`, `random_rigid_motion(rng, 10.0)`, `sample(id, ex)` moved by the
/// motion; the digest is [`digest`] of that mesh.
#[test]
fn sampled_faces_are_bit_identical_to_the_pinned_digests() {
    let dir = testsupport::require_shared!(testsupport::MODEL);
    let model = FaceModel::load(&dir).unwrap();
    assert_eq!(
        (
            model.n_vertices(),
            model.n_identities(),
            model.n_expressions()
        ),
        (6706, 100, 27)
    );
    assert_eq!(model.units(), "cm");
    for (seed, want) in PINNED {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let id = model.random_identity(&mut rng);
        let ex = model.random_expression(&mut rng);
        let pose = random_rigid_motion(&mut rng, 10.0);
        let face = model.sample(&id, &ex).unwrap().transformed(&pose);
        assert_eq!(digest(&face), want, "seed {seed}: {:#018x}", digest(&face));
    }
    assert_eq!(digest(&model.neutral().unwrap()), 0xd6b5_da21_6777_0c29);
}

#[test]
fn model_landmarks_are_the_ground_truth_vertices() {
    let dir = testsupport::require_shared!(testsupport::MODEL);
    let model = FaceModel::load(&dir).unwrap();
    assert_eq!(
        model.landmark_id("right_eye_outer").unwrap(),
        RIGHT_EYE_OUTER
    );
    assert_eq!(model.landmark_id("left_eye_outer").unwrap(), LEFT_EYE_OUTER);
    assert_eq!(model.landmark_id("nose_tip").unwrap(), NOSE_TIP);
    assert_eq!(model.landmark_ids().len(), 5);
    let neutral = model.neutral().unwrap();
    let lm = model.landmark_positions(&neutral).unwrap();
    // Order of LANDMARK_NAMES: right outer, right inner, left inner, left outer, nose tip;
    // "right" is the subject's right, at negative x.
    assert!(lm[0].x < lm[1].x && lm[1].x < 0.0 && 0.0 < lm[2].x && lm[2].x < lm[3].x);
    assert_eq!(lm[4], neutral.position(NOSE_TIP));
    assert!(model.recipe_names().any(|r| r == "happiness"));
}

#[test]
fn paper_set_loads_in_order_with_an_orthonormal_frame_and_a_static_area() {
    let dir = testsupport::require_shared!(testsupport::PAPER_SET);
    let faces = load_face_set(&dir).unwrap();
    assert_eq!(faces.len(), 12);
    let names: Vec<&str> = faces.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "id1_neutral",
            "id1_anger",
            "id1_disgust",
            "id1_happiness",
            "id1_mouth_open",
            "id1_sadness",
            "id1_surprise",
            "id2_neutral",
            "id3_neutral",
            "id4_neutral",
            "id5_neutral",
            "id6_neutral"
        ]
    );
    for f in &faces {
        assert_eq!(f.mesh.n_vertices(), 6706, "{}", f.name);
        let lm = f.landmarks;
        let (r, q, nose) = (
            f.mesh.position(lm.right_eye_outer),
            f.mesh.position(lm.left_eye_outer),
            f.mesh.position(lm.nose_tip),
        );
        let fr = face_frame(&f.mesh, r, q, nose);
        for (a, b) in [(fr.x, fr.up), (fr.x, fr.forward), (fr.up, fr.forward)] {
            assert!(a.dot(b).abs() < 1e-12, "{}: {fr:?}", f.name);
        }
        for v in [fr.x, fr.up, fr.forward] {
            assert!((v.length() - 1.0).abs() < 1e-12, "{}: {fr:?}", f.name);
        }
        // The faces look along +z with +y up (cm).
        assert!(fr.forward.z > 0.9 && fr.up.y > 0.9, "{}: {fr:?}", f.name);
        // With Euclidean distances (a lower bound of the geodesic ones) the static area is a
        // minority of the face that holds both eye corners' surroundings.
        let d = (q - r).length();
        let dist = |c: meshcore::DVec3| -> Vec<f64> {
            f.mesh
                .positions()
                .iter()
                .map(|p| (*p - c).length())
                .collect()
        };
        let mask = static_mask(&f.mesh, &dist(r), &dist(q), d, &fr, nose);
        let n = mask.iter().filter(|m| **m).count();
        assert!(n > 500 && n < 6706 / 2, "{}: {n}", f.name);
        assert!(mask[lm.right_eye_outer as usize] && mask[lm.left_eye_outer as usize]);
    }
}
