//! How a face is acquired: the fixed list of scan settings, the scan (`rangescan`, cleaned by
//! `scanprep`) or the face mesh itself in mm, and the ground-truth landmarks snapped to it.

use anyhow::{bail, Result};
use facemodel::Face;
use meshcore::{DVec3, FaceLocator, SurfacePoint, TriMesh};
use rangescan::ScanSettings;
use scanprep::{CleanOptions, Crop, Input};

/// One way of acquiring a face.
#[derive(Debug, Clone)]
pub(super) struct Setting {
    pub(super) name: &'static str,
    /// The scanner settings and the scan's seed; `None`: the face mesh itself, scaled to mm (no
    /// scanner).
    pub(super) scan: Option<(ScanSettings, u64)>,
}

/// The fixed list of settings: seven scans with the structured-light artifacts (name, pitch
/// mm, noise mm, quantisation mm, yaw and pitch degrees; seeds 1-7) and the face mesh itself,
/// last.
pub(super) fn settings() -> Vec<Setting> {
    const SCANS: [(&str, f64, f64, f64, f64, f64); 7] = [
        ("p0.75 n0.1", 0.75, 0.1, 0.0, 0.0, 0.0),
        ("p0.5 n0.1", 0.5, 0.1, 0.0, 0.0, 0.0),
        ("p1.0 n0.1", 1.0, 0.1, 0.0, 0.0, 0.0),
        ("p0.75 n0.2", 0.75, 0.2, 0.0, 0.0, 0.0),
        ("p0.75 yaw20", 0.75, 0.1, 0.0, 20.0, 0.0),
        ("p0.75 pitch10", 0.75, 0.1, 0.0, 0.0, 10.0),
        ("p0.75 q2mm", 0.75, 0.1, 2.0, 0.0, 0.0),
    ];
    let scans = SCANS.iter().zip(1..).map(|(s, seed)| {
        let &(name, pitch_mm, noise_mm, quantisation_mm, yaw_deg, pitch_deg) = s;
        let settings = ScanSettings {
            pitch_mm,
            noise_mm,
            quantisation_mm,
            yaw_deg,
            pitch_deg,
            ..ScanSettings::default()
        };
        Setting {
            name,
            scan: Some((settings, seed)),
        }
    });
    let mesh = Setting {
        name: "mesh (mm)",
        scan: None,
    };
    scans.chain([mesh]).collect()
}

/// Millimetres per unit of the paper-set meshes (cm).
const MM_PER_CM: f64 = 10.0;

/// The acquired mesh (mm) and the three ground-truth landmarks (r, q, nose) in its frame.
/// Also returns the landmarks the scanner did not see (label and why).
pub(super) fn acquire(
    face: &Face,
    setting: &Setting,
    smooth: usize,
) -> Result<(TriMesh, [DVec3; 3], Vec<String>)> {
    let lm = face.landmarks;
    let truth = [lm.right_eye_outer, lm.left_eye_outer, lm.nose_tip].map(|v| face.mesh.position(v));
    let Some((settings, seed)) = setting.scan else {
        let mesh = face
            .mesh
            .transformed(&meshcore::DAffine3::from_scale(DVec3::splat(MM_PER_CM)));
        return Ok((mesh, truth.map(|p| p * MM_PER_CM), Vec::new()));
    };
    let opts = settings.options(MM_PER_CM, seed);
    let names = ["right_eye_outer", "left_eye_outer", "nose_tip"];
    let marks: Vec<(String, DVec3)> = names
        .iter()
        .zip(truth)
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    let scan = rangescan::scan_with_landmarks(&face.mesh, &marks, &opts)?;
    // A landmark the scanner hides behind other surface is unusable; one in a small hole or a
    // grazing dropout may lie on the cleaned (filled) surface, which `snap` decides.
    for m in &scan.landmarks {
        if matches!(
            m.visibility,
            rangescan::Visibility::Occluded { .. } | rangescan::Visibility::OutsideGrid
        ) {
            bail!("landmark {} {}", m.label, m.visibility);
        }
    }
    let hidden: Vec<String> = scan
        .landmarks
        .iter()
        .filter(|m| !m.visibility.is_visible())
        .map(|m| format!("{} {}", m.label, m.visibility))
        .collect();
    let pos = [0, 1, 2].map(|k| scan.landmarks[k].position);
    let cleaned = scanprep::clean(
        Input::Grid(&scan.grid),
        &CleanOptions {
            units: Some(meshcore::units::Units::Millimetre),
            crop: Some(Crop::around(pos[2])),
            smoothing_iterations: smooth,
            ..CleanOptions::default()
        },
    )?;
    Ok((cleaned.mesh, pos, hidden))
}

/// Snaps the landmarks onto the mesh; an offset above `tol_mm` is an error naming it.
pub(super) fn snap(
    loc: &FaceLocator<'_>,
    lms: &[DVec3; 3],
    tol_mm: f64,
) -> Result<([SurfacePoint; 3], [f64; 3])> {
    let mut sp = [SurfacePoint::new(0, DVec3::X); 3];
    let mut off = [0.0; 3];
    for k in 0..3 {
        let (p, d) = loc.nearest(lms[k])?;
        if d > tol_mm {
            bail!(
                "landmark {} is {d:.2} mm from the cleaned surface (tolerance {tol_mm} mm)",
                ["right_eye_outer", "left_eye_outer", "nose_tip"][k]
            );
        }
        sp[k] = p;
        off[k] = d;
    }
    Ok((sp, off))
}
