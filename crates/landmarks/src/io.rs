//! Landmarks and landmark files. The files themselves are read and written by `mesh-io`
//! ([`mesh_io::read_landmark_file`], [`mesh_io::write_lm3`], [`mesh_io::write_landmarks_json`],
//! [`mesh_io::read_ict_landmarks`]); this module converts between them and
//! [`crate::VisibleLandmarks`] (or [`crate::Landmarks`]).

use crate::{LandmarkError, LandmarkName, VisibleLandmarks};
use mesh_io::Landmarks3d;
use meshcore::DVec3;

/// The five landmarks of the crate among labelled points (`.lm3` labels, JSON keys, ICT keys:
/// any spelling [`LandmarkName::parse`] reads), in [`LandmarkName::ALL`] order; an error naming
/// the first missing one. `source` names the points in the error (a file name).
pub fn select_five(points: &Landmarks3d, source: &str) -> Result<[DVec3; 5], LandmarkError> {
    let mut out = [DVec3::ZERO; 5];
    for n in LandmarkName::ALL {
        out[n as usize] = points
            .labels
            .iter()
            .zip(&points.points)
            .find(|(l, _)| LandmarkName::parse(l) == Some(n))
            .map(|(_, p)| *p)
            .ok_or_else(|| LandmarkError::MissingLandmark {
                source_name: source.to_string(),
                label: n.lm3_label().to_string(),
            })?;
    }
    Ok(out)
}

/// Detected landmarks as the landmark JSON of `bipolar landmarks`: keys [`LandmarkName::key`],
/// with vertex and confidence per placed landmark (an unseen one is left out) and the fit's
/// `confidence`, `fit_rms`, `inlier_fraction` and `symmetry` (write with
/// [`mesh_io::write_landmarks_json`]). A [`crate::Landmarks`] converts with `.into()`.
pub fn to_json_file(lm: &VisibleLandmarks) -> Landmarks3d {
    let mut out = Landmarks3d::default();
    for n in LandmarkName::ALL {
        if let Ok(l) = lm.get(n) {
            out.push(n.key(), l.position, Some(l.vertex));
            out.confidences.push(Some(l.confidence));
        }
    }
    out.attributes = vec![
        ("confidence".into(), lm.confidence),
        ("fit_rms".into(), lm.fit_rms),
        ("inlier_fraction".into(), lm.inlier_fraction),
        ("symmetry".into(), lm.symmetry),
    ];
    out
}

/// Detected landmarks with their Bosphorus `.lm3` labels, and one note per unseen landmark
/// naming it and why (write with [`mesh_io::write_lm3_with_notes`]).
pub fn to_lm3_file(lm: &VisibleLandmarks) -> (Landmarks3d, Vec<String>) {
    let mut out = Landmarks3d::default();
    let mut notes = Vec::new();
    for n in LandmarkName::ALL {
        match lm.get(n) {
            Ok(l) => out.push(n.lm3_label(), l.position, None),
            Err(u) => notes.push(format!("{} not found: {u}", n.lm3_label())),
        }
    }
    (out, notes)
}
