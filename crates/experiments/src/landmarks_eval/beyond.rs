//! Test faces the ICT model cannot make, and things that are not faces: the faces of
//! `landmarks-eval --beyond`. Every face is made from the ICT model (read at run time) by a
//! seeded, regenerable recipe; errors are measured against the model's landmark vertices,
//! carried through the recipe.
//!
//! * [`Kind::StrongExpression`]: expressions at 1.5-2 times full strength, or two recipes mixed
//!   ([`FaceModel::strong_expression`]).
//! * [`Kind::Warp`]: a smooth random non-rigid warp of 2-6 mm (eyes wider or narrower, brows
//!   higher, nose longer, one side only), on top of a random expression
//!   ([`facemodel::random_warp`]).
//! * [`Kind::Remesh`]: the face subdivided and decimated to 1-5 mm edges (another topology,
//!   [`scanprep::remesh`]).
//! * [`Kind::DepthCamera`]: a consumer-depth-camera-like range scan (2-5 mm pitch, depth
//!   quantised to 1-4 mm, 1 mm noise: [`Artifacts::depth_camera`]; flying pixels at the
//!   silhouette: [`rangescan::add_flying_pixels`]), cleaned by `scanprep`.
//! * [`non_faces`]: a sphere, a noisy plane, the back of a head (an ellipsoid cap) and a face
//!   seen from behind (normals inverted), by [`facemodel::variation::non_faces`].

use anyhow::Result;
use facemodel::FaceModel;
use meshcore::{DAffine3, DVec3, TriMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangescan::{Artifacts, FlyingPixels, HeadPose, ScanOptions};

/// A kind of face outside the ICT model's span.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Expressions at 1.5-2x full strength, or two recipes mixed.
    StrongExpression,
    /// A smooth random non-rigid warp of 2-6 mm.
    Warp,
    /// Another topology: subdivided and decimated to 1-5 mm edges.
    Remesh,
    /// A consumer depth camera's scan.
    DepthCamera,
}

impl Kind {
    /// Every kind, in table order.
    pub const ALL: [Kind; 4] = [
        Kind::StrongExpression,
        Kind::Warp,
        Kind::Remesh,
        Kind::DepthCamera,
    ];

    /// Its name in tables and file names.
    pub fn name(self) -> &'static str {
        match self {
            Kind::StrongExpression => "strong-expression",
            Kind::Warp => "warp",
            Kind::Remesh => "remesh",
            Kind::DepthCamera => "depth-camera",
        }
    }
}

/// A generated test face, in mm.
#[derive(Debug, Clone)]
pub struct BeyondFace {
    /// The face's name, `KIND-NNN` (kind, then a three-digit number).
    pub name: String,
    /// The face (mm).
    pub mesh: TriMesh,
    /// Per landmark (`LandmarkName::ALL` order) the true position and, when it is not on the
    /// surface (a scan that did not see it), why.
    pub truth: [(DVec3, Option<String>); 5],
    /// The direction toward the scanner for a scan.
    pub toward_viewer: Option<DVec3>,
    /// What the recipe did (expression, warp size, edge length, scanner settings).
    pub label: String,
}

/// Millimetres per unit of the units label `units` (of `what`; refused when it names none).
pub(super) fn mm_per(units: &str, what: &str) -> Result<f64> {
    let u: meshcore::units::Units = units
        .trim()
        .parse()
        .map_err(|e| anyhow::anyhow!("{what}'s units {units:?}: {e}"))?;
    Ok(u.factor_to(meshcore::units::Units::Millimetre))
}

/// Millimetres per ICT model unit, from the model's units label.
fn mm_per_unit(ict: &FaceModel) -> Result<f64> {
    mm_per(ict.units(), "the ICT model")
}

/// Seed of face `index` of `kind` in the stream of `seed`.
fn face_seed(seed: u64, kind: Kind, index: usize) -> u64 {
    let k = Kind::ALL.iter().position(|&x| x == kind).unwrap_or(0) as u64;
    (seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x6265_796f_6e64_0000)
        .wrapping_add(k << 40)
        .wrapping_add(index as u64)
}

/// Face `index` of `kind` in the stream of `seed` (the same face for the same arguments).
pub fn make(ict: &FaceModel, kind: Kind, index: usize, seed: u64) -> Result<BeyondFace> {
    let mut rng = ChaCha8Rng::seed_from_u64(face_seed(seed, kind, index));
    let s = mm_per_unit(ict)?;
    let name = format!("{}-{index:03}", kind.name());
    let id = ict.random_identity(&mut rng);
    let (ex, ex_label) = match kind {
        Kind::StrongExpression => ict.strong_expression(&mut rng)?,
        _ => (
            ict.random_expression(&mut rng),
            String::from("random expression"),
        ),
    };
    let face = ict.sample(&id, &ex)?;
    let truth = ict.landmark_positions(&face)?;
    let face = face.transformed(&DAffine3::from_scale(DVec3::splat(s)));
    let truth = truth.map(|p| p * s);
    let motion = facemodel::random_rigid_motion(&mut rng, 100.0);
    let (mesh, truth, label) = match kind {
        Kind::StrongExpression => (face, truth, ex_label),
        Kind::Warp => {
            let w = facemodel::random_warp(&face, &truth, &mut rng)?;
            let moved = ict.landmark_positions(&w.mesh)?;
            let label = format!("warp {:.1} mm: {}", w.size_mm, w.parts.join(", "));
            (w.mesh, moved, label)
        }
        Kind::Remesh => {
            let edge = rng.random_range(1.0..5.0);
            let mesh = scanprep::remesh(&face, edge)?;
            let label = format!(
                "edges {edge:.2} mm asked, mean {:.2} mm, {} vertices",
                mesh.mean_edge_length(),
                mesh.n_vertices()
            );
            (mesh, truth, label)
        }
        Kind::DepthCamera => return depth_camera(name, &face, &truth, &mut rng),
    };
    Ok(BeyondFace {
        name,
        mesh: mesh.transformed(&motion),
        truth: truth.map(|p| (motion.transform_point3(p), None)),
        toward_viewer: None,
        label,
    })
}

/// A consumer depth camera's scan of `face` (mm): head yaw up to 20 degrees, 2-5 mm pitch,
/// depth quantised to 1-4 mm, 1 mm noise, dropouts at grazing angles, a few holes, flying
/// pixels at the silhouette; cleaned by `scanprep` (crop around the nose tip). The truth is
/// the scanner's projection of the landmarks, on the cleaned scan within
/// [`crate::scans::MAX_SNAP_MM`] or not on it.
fn depth_camera(
    name: String,
    face: &TriMesh,
    truth: &[DVec3; 5],
    rng: &mut ChaCha8Rng,
) -> Result<BeyondFace> {
    let pitch = rng.random_range(2.0..5.0);
    let step = rng.random_range(1.0..4.0);
    let yaw = rng.random_range(-20.0..20.0);
    let marks: Vec<(String, DVec3)> = landmarks::LandmarkName::ALL
        .iter()
        .zip(truth)
        .map(|(n, p)| (n.lm3_label().to_string(), *p))
        .collect();
    let mut scan = rangescan::scan_with_landmarks(
        face,
        &marks,
        &ScanOptions {
            input_mm_per_unit: 1.0,
            pitch_mm: pitch,
            pose: HeadPose {
                yaw_deg: yaw,
                pitch_deg: 0.0,
            },
            artifacts: Artifacts::depth_camera(step),
            seed: rng.random(),
            ..ScanOptions::default()
        },
    )?;
    let flying = rangescan::add_flying_pixels(&mut scan.grid, &FlyingPixels::default(), rng)?;
    let nose = scan.landmarks[landmarks::LandmarkName::NoseTip as usize].position;
    let cleaned = scanprep::clean(
        scanprep::Input::Grid(&scan.grid),
        &scanprep::CleanOptions {
            crop: Some(scanprep::Crop::around(nose)),
            ..scanprep::CleanOptions::default()
        },
    )?;
    let mesh = cleaned.mesh;
    // On the cleaned scan when its surface (not its nearest vertex: the samples are up to 5 mm
    // apart) passes within [`crate::scans::MAX_SNAP_MM`].
    let surface = meshcore::FaceLocator::new(&mesh);
    let truth = std::array::from_fn(|k| {
        let l = &scan.landmarks[k];
        let why = match surface.nearest(l.position) {
            Ok((_, d)) if d <= crate::scans::MAX_SNAP_MM => None,
            Ok((_, d)) => Some(format!(
                "{} and {d:.1} mm from the cleaned surface",
                l.visibility
            )),
            Err(e) => Some(format!("the cleaned scan: {e}")),
        };
        (l.position, why)
    });
    Ok(BeyondFace {
        name,
        label: format!(
            "pitch {pitch:.2} mm, quantisation {step:.2} mm, noise 1 mm, yaw {yaw:.1}, {flying} flying pixels, {} vertices",
            mesh.n_vertices()
        ),
        mesh,
        truth,
        toward_viewer: Some(crate::scans::SCANNER_SIDE),
    })
}

/// Things that are not faces, in mm, with a name ([`facemodel::variation::non_faces`]): a
/// sphere, a noisy plane, the back of a head and a face seen from behind (the ICT face of
/// `seed`'s stream with its normals inverted), each under a random rotation.
pub fn non_faces(ict: &FaceModel, seed: u64) -> Result<Vec<(String, TriMesh)>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6e6f_6e66_6163_6500);
    let s = mm_per_unit(ict)?;
    let face = |rng: &mut ChaCha8Rng| {
        let id = ict.random_identity(rng);
        Ok(ict
            .sample(&id, &[])?
            .transformed(&DAffine3::from_scale(DVec3::splat(s))))
    };
    Ok(facemodel::variation::non_faces(&mut rng, face)?)
}
