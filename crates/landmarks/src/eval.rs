//! Evaluation of detected landmarks against known positions (a detector's accuracy on annotated
//! meshes): per-landmark errors of a detection ([`score`]), the errors of a set of detections
//! ([`scored_errors`]), the errors of the fitted pose alone ([`pose_only_errors`]), the error
//! vectors in the model's canonical frame ([`canonical_errors`]), the weakest local template
//! agreement of a detection ([`weakest_agreement`]) and the share of each landmark's template
//! that finds the input surface ([`landmark_coverage`]).
//!
//! Distances are in the units of the positions given (the mesh's units).

use crate::{
    DetectOptions, GenericModel, Landmark, LandmarkError, LandmarkName, Landmarks, Unseen,
    VisibleLandmarks,
};
use meshcore::{DAffine3, DVec3, TriMesh};

/// A landmark the detector reported unseen ([`VisibleLandmarks::predicted`]), against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PredictedUnseen {
    /// The landmark.
    pub name: LandmarkName,
    /// Distance from its predicted position to the true position.
    pub distance: f64,
    /// Whether the true position is on the surface (then reporting it unseen missed it).
    pub truth_on_surface: bool,
}

/// A detection scored against the truth ([`score`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    /// Per landmark in [`LandmarkName::ALL`] order: the distance from the detected to the true
    /// position (infinite when the landmark was not placed or the face not found), or, when the
    /// true position is not on the surface, why (the landmark is then not scored).
    pub errors: [Result<f64, String>; 5],
    /// Per landmark: why the detector reported it unseen (`None`: placed, or no face found).
    pub unseen: [Option<Unseen>; 5],
    /// The landmarks reported unseen, in [`LandmarkName::ALL`] order.
    pub predicted_unseen: Vec<PredictedUnseen>,
}

/// Scores the detection `detected` (or the detector's error) against `truth`: per landmark in
/// [`LandmarkName::ALL`] order, the true position and, when it is not on the surface (hidden,
/// outside the scan), why.
pub fn score<E>(
    truth: &[(DVec3, Option<String>); 5],
    detected: Result<&VisibleLandmarks, E>,
) -> Scored {
    let errors = LandmarkName::ALL.map(|n| match (&truth[n as usize], &detected) {
        ((_, Some(why)), _) => Err(why.clone()),
        ((t, None), Ok(d)) => Ok(d
            .get(n)
            .map_or(f64::INFINITY, |l| (l.position - *t).length())),
        (_, Err(_)) => Ok(f64::INFINITY),
    });
    let d = detected.ok();
    let unseen = LandmarkName::ALL.map(|n| d.and_then(|d| d.get(n).err()));
    let predicted_unseen = d.map_or_else(Vec::new, |d| {
        LandmarkName::ALL
            .iter()
            .filter(|&&n| d.get(n).is_err())
            .map(|&n| {
                let (t, why) = &truth[n as usize];
                PredictedUnseen {
                    name: n,
                    distance: (d.predicted[n as usize] - *t).length(),
                    truth_on_surface: why.is_none(),
                }
            })
            .collect()
    });
    Scored {
        errors,
        unseen,
        predicted_unseen,
    }
}

/// The errors of landmark `n` over the detections `scored`, leaving out those whose truth is
/// not on the surface (infinite: not placed).
pub fn scored_errors(scored: &[&Scored], n: LandmarkName) -> Vec<f64> {
    scored
        .iter()
        .filter_map(|o| o.errors[n as usize].as_ref().ok().copied())
        .collect()
}

/// Per landmark, the distance from where the fitted pose alone puts the model's landmark
/// (before the local refinement) to the true position `truth`.
pub fn pose_only_errors(
    detected: &Landmarks,
    truth: &[DVec3; 5],
    generic: &GenericModel,
) -> [f64; 5] {
    LandmarkName::ALL.map(|n| {
        let pred = detected.model_to_mesh.transform_point3(generic.landmark(n));
        (pred - truth[n as usize]).length()
    })
}

/// Per landmark, the error vector (detected minus true position) in the model's canonical
/// frame (x: from the right to the left eye, y: up, z: out of the face).
pub fn canonical_errors(detected: &Landmarks, truth: &[DVec3; 5]) -> [DVec3; 5] {
    let inv = detected.model_to_mesh.inverse();
    LandmarkName::ALL.map(|n| inv.transform_vector3(detected.get(n).position - truth[n as usize]))
}

/// The weakest local template agreement of the landmarks `placed` of a detection with fit
/// confidence `confidence` (a landmark's confidence is the fit confidence times its agreement);
/// 1 when none is placed.
pub fn weakest_agreement<'a>(
    confidence: f64,
    placed: impl IntoIterator<Item = &'a Landmark>,
) -> f64 {
    placed
        .into_iter()
        .map(|l| l.confidence / confidence.max(1e-12))
        .fold(1.0, f64::min)
}

/// Per landmark in [`LandmarkName::ALL`] order, the share of its local template (the mean
/// surface around it, turned by the fitted pose and placed at the reported point) that finds
/// the input surface within the model's inlier distance, as the detector's check that a
/// landmark is on the surface measures it ([`DetectOptions::min_landmark_coverage`]); `None`
/// for a landmark not placed. The graded pass's guard ([`DetectOptions::graded_coverage`])
/// measures the same share at the template search's point, before the learned regression
/// moves the eye corners, so its value can differ. `mesh`, `model` and `options.mesh_units_per_model_unit`
/// are those of the detection `found`.
pub fn landmark_coverage(
    mesh: &TriMesh,
    model: &GenericModel,
    found: &VisibleLandmarks,
    options: &DetectOptions,
) -> Result<[Option<f64>; 5], LandmarkError> {
    model.validate()?;
    let s = options.mesh_units_per_model_unit;
    let mesh_m = crate::detect::in_model_units(mesh, s)?;
    let idx = crate::detect::surface_index(&mesh_m);
    let pose = DAffine3::from_mat3_translation(
        found.model_to_mesh.matrix3,
        found.model_to_mesh.translation / s,
    );
    let tau = model.params.inlier_distance;
    Ok(LandmarkName::ALL.map(|n| {
        found.get(n).ok().map(|l| {
            let tpl = &model.patches[n as usize];
            crate::detect::coverage(&idx, tpl, &pose, l.position / s, tau)
        })
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::{DAffine3, DQuat};

    fn landmark(x: f64, confidence: f64) -> Landmark {
        Landmark {
            vertex: 0,
            position: DVec3::new(x, 0.0, 0.0),
            confidence,
        }
    }

    /// Landmark `k` at `(k, 0, 0)` with confidence 0.8 times agreement `0.9 - 0.1 k`.
    fn detection() -> Landmarks {
        let l = |k: usize| landmark(k as f64, 0.8 * (0.9 - 0.1 * k as f64));
        Landmarks {
            outer_eye_right: l(0),
            inner_eye_right: l(1),
            inner_eye_left: l(2),
            outer_eye_left: l(3),
            nose_tip: l(4),
            confidence: 0.8,
            fit_rms: 0.1,
            inlier_fraction: 0.9,
            symmetry: 0.9,
            model_to_mesh: DAffine3::IDENTITY,
        }
    }

    #[test]
    fn a_detection_is_scored_per_landmark() {
        let mut v = VisibleLandmarks::from(detection());
        v.landmarks[3] = Err(Unseen::Bare { coverage: 0.2 });
        v.predicted[3] = DVec3::new(3.0, 4.0, 0.0);
        let mut truth: [(DVec3, Option<String>); 5] =
            std::array::from_fn(|k| (DVec3::new(k as f64, 1.0, 0.0), None));
        truth[1].1 = Some("hidden".into());
        let s = score::<()>(&truth, Ok(&v));
        assert_eq!(s.errors[0], Ok(1.0));
        assert_eq!(s.errors[1], Err("hidden".into()));
        assert_eq!(s.errors[3], Ok(f64::INFINITY));
        assert_eq!(s.unseen[3], Some(Unseen::Bare { coverage: 0.2 }));
        assert_eq!(s.unseen[0], None);
        assert_eq!(
            s.predicted_unseen,
            vec![PredictedUnseen {
                name: LandmarkName::OuterEyeLeft,
                distance: 3.0,
                truth_on_surface: true,
            }]
        );
        // No face found: every landmark whose truth is on the surface is infinitely wrong.
        let s = score(&truth, Err("not found"));
        assert_eq!(s.errors[0], Ok(f64::INFINITY));
        assert_eq!(s.errors[1], Err("hidden".into()));
        assert!(s.unseen.iter().all(Option::is_none) && s.predicted_unseen.is_empty());
    }

    #[test]
    fn scored_errors_leave_out_the_truths_off_the_surface() {
        let truth: [(DVec3, Option<String>); 5] =
            std::array::from_fn(|k| (DVec3::new(k as f64, 2.0, 0.0), None));
        let mut hidden = truth.clone();
        hidden[4].1 = Some("outside the scan".into());
        let v = VisibleLandmarks::from(detection());
        let a = score::<()>(&truth, Ok(&v));
        let b = score::<()>(&hidden, Ok(&v));
        let c = score(&truth, Err(()));
        let nose = scored_errors(&[&a, &b, &c], LandmarkName::NoseTip);
        assert_eq!(nose, vec![2.0, f64::INFINITY]);
    }

    #[test]
    fn pose_errors_and_canonical_vectors_follow_the_pose() {
        let generic = GenericModel::default_model().unwrap();
        let mut d = detection();
        d.model_to_mesh =
            DAffine3::from_rotation_translation(DQuat::from_rotation_z(0.5), DVec3::X);
        // The truth where the pose puts the model's landmarks, shifted by 0.5 along the model's y.
        let shift = d.model_to_mesh.transform_vector3(DVec3::Y * 0.5);
        let truth = LandmarkName::ALL
            .map(|n| d.model_to_mesh.transform_point3(generic.landmark(n)) + shift);
        for e in pose_only_errors(&d, &truth, &generic) {
            assert!((e - 0.5).abs() < 1e-12, "{e}");
        }
        // The detected landmarks at (k, 0, 0), the truth 0.5 below them along the model's y.
        let truth = d.positions().map(|p| p - shift);
        for v in canonical_errors(&d, &truth) {
            assert!((v - DVec3::Y * 0.5).length() < 1e-12, "{v}");
        }
    }

    #[test]
    fn the_weakest_agreement_is_the_least_confidence_over_the_fit() {
        let d = detection();
        let w = weakest_agreement(d.confidence, LandmarkName::ALL.map(|n| d.get(n)));
        assert!((w - 0.5).abs() < 1e-12, "{w}");
        assert_eq!(weakest_agreement(0.8, []), 1.0);
    }
}
