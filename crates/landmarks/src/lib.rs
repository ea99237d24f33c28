//! Curvature and automatic face landmarks (nose tip, inner and outer eye corners).
//!
//! * [`curvature`]: per-vertex principal curvatures by quadric fitting at a chosen scale, shape
//!   index (nose-tip cap `+1` with outward normals), curvedness, Taubin smoothing.
//! * [`GenericModel`]: mean landmark configuration, mean face surface and per-landmark surface
//!   templates learned from training faces ([`GenericModel::train`]); JSON serialisable; a
//!   default model trained on ICT FaceKit faces (cm) ships with the crate
//!   ([`GenericModel::default_model`]).
//! * [`detect`]: rotation- and translation-invariant detection. Curvature gives nose-tip (convex
//!   cap) and inner-eye-corner (concave) candidates; their configurations give pose hypotheses;
//!   the generic face surface is fitted (point-to-plane ICP) to choose and refine the pose;
//!   each landmark is then refined by a local template search and, when the model has a
//!   [`LandmarkRegressor`] (the shipped one does), the eye corners are placed by its learned
//!   regression from the local depth maps. Inputs that do not fit a face (not a face, inverted
//!   normals) end with [`LandmarkError::NotFound`].
//! * [`io`]: conversions between [`Landmarks`] and the landmark files of `mesh-io` (which
//!   reads and writes every landmark file), and [`io::select_five`].

pub mod curvature;
mod detect;
pub mod eval;
pub mod geom;
pub mod io;
mod model;
mod regress;

pub use curvature::{curvedness, shape_index, Curvature, CurvatureOptions};
pub use detect::{
    detect, detect_seen_from, detect_visible, detect_with, mesh_units_per_model_unit,
    DetectOptions, GRADED_COVERAGE, GRAZING_RIM_DEG, MIN_PLACED, RIM_AGREEMENT,
};
pub use model::{DetectParams, GenericModel, Template, TrainOptions};
pub use regress::{LandmarkRegressor, RegressorOptions, RegressorPatch};

use meshcore::{DAffine3, DVec3, MeshError};

/// The five landmarks; "right" and "left" are the subject's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LandmarkName {
    /// Outer corner of the right eye (exocanthion).
    OuterEyeRight = 0,
    /// Inner corner of the right eye (endocanthion).
    InnerEyeRight = 1,
    /// Inner corner of the left eye.
    InnerEyeLeft = 2,
    /// Outer corner of the left eye.
    OuterEyeLeft = 3,
    /// Nose tip (pronasale).
    NoseTip = 4,
}

impl LandmarkName {
    /// All names in index order.
    pub const ALL: [LandmarkName; 5] = [
        LandmarkName::OuterEyeRight,
        LandmarkName::InnerEyeRight,
        LandmarkName::InnerEyeLeft,
        LandmarkName::OuterEyeLeft,
        LandmarkName::NoseTip,
    ];

    /// Snake-case key used in JSON files (`outer_eye_right`, ...).
    pub fn key(self) -> &'static str {
        match self {
            Self::OuterEyeRight => "outer_eye_right",
            Self::InnerEyeRight => "inner_eye_right",
            Self::InnerEyeLeft => "inner_eye_left",
            Self::OuterEyeLeft => "outer_eye_left",
            Self::NoseTip => "nose_tip",
        }
    }

    /// Key of the ICT FaceKit `landmarks.json` (`right_eye_outer`, ...).
    pub fn ict_key(self) -> &'static str {
        match self {
            Self::OuterEyeRight => "right_eye_outer",
            Self::InnerEyeRight => "right_eye_inner",
            Self::InnerEyeLeft => "left_eye_inner",
            Self::OuterEyeLeft => "left_eye_outer",
            Self::NoseTip => "nose_tip",
        }
    }

    /// Bosphorus `.lm3` label (`Outer right eye corner`, ...).
    pub fn lm3_label(self) -> &'static str {
        match self {
            Self::OuterEyeRight => "Outer right eye corner",
            Self::InnerEyeRight => "Inner right eye corner",
            Self::InnerEyeLeft => "Inner left eye corner",
            Self::OuterEyeLeft => "Outer left eye corner",
            Self::NoseTip => "Nose tip",
        }
    }

    /// Parses any of the spellings above, or the kebab-case CLI form (`outer-eye-right`).
    pub fn parse(s: &str) -> Option<Self> {
        let t = s.trim();
        Self::ALL.into_iter().find(|n| {
            t == n.key()
                || t == n.ict_key()
                || t.eq_ignore_ascii_case(n.lm3_label())
                || t == n.key().replace('_', "-")
        })
    }
}

impl std::fmt::Display for LandmarkName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}

/// One detected landmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landmark {
    /// Vertex of the input mesh.
    pub vertex: u32,
    /// Its position (input units).
    pub position: DVec3,
    /// Confidence in `[0, 1]` (face fit quality times local template agreement).
    pub confidence: f64,
}

/// The five detected landmarks and the quality of the face fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Landmarks {
    /// Subject's right outer eye corner.
    pub outer_eye_right: Landmark,
    /// Subject's left outer eye corner.
    pub outer_eye_left: Landmark,
    /// Subject's right inner eye corner.
    pub inner_eye_right: Landmark,
    /// Subject's left inner eye corner.
    pub inner_eye_left: Landmark,
    /// Nose tip.
    pub nose_tip: Landmark,
    /// Overall confidence in `[0, 1]` of the generic face fit.
    pub confidence: f64,
    /// RMS distance of the fitted generic face surface (inliers), input units.
    pub fit_rms: f64,
    /// Share of the generic face surface that found the input surface.
    pub inlier_fraction: f64,
    /// Mirror symmetry of the fit in `[0, 1]`: share of the matched input vertices that, mirrored
    /// across the fitted mid-sagittal plane, land on the input surface again.
    pub symmetry: f64,
    /// Rigid motion from the model's canonical frame to the input (model units scaled to input
    /// units only in the translation).
    pub model_to_mesh: DAffine3,
}

impl Landmarks {
    /// The landmark of a given name.
    pub fn get(&self, name: LandmarkName) -> &Landmark {
        match name {
            LandmarkName::OuterEyeRight => &self.outer_eye_right,
            LandmarkName::InnerEyeRight => &self.inner_eye_right,
            LandmarkName::InnerEyeLeft => &self.inner_eye_left,
            LandmarkName::OuterEyeLeft => &self.outer_eye_left,
            LandmarkName::NoseTip => &self.nose_tip,
        }
    }

    /// Positions in [`LandmarkName::ALL`] order.
    pub fn positions(&self) -> [DVec3; 5] {
        LandmarkName::ALL.map(|n| self.get(n).position)
    }
}

/// Why [`detect_visible`] did not place a landmark of a face it found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unseen {
    /// The landmark borders surface the scanner did not see (a rim of a dropout or of a part
    /// hidden behind nearer surface, [`DetectOptions::toward_viewer`]) and what was seen
    /// around it does not match its template well enough: local agreement `agreement`, below
    /// [`RIM_AGREEMENT`].
    Unobserved {
        /// The landmark's local template agreement.
        agreement: f64,
    },
    /// Only the share `coverage` of the surface expected around the landmark is on the input
    /// (a hole, a dropout, the border of the scan).
    Bare {
        /// Share of the landmark's template that found the input surface.
        coverage: f64,
    },
}

impl std::fmt::Display for Unseen {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unseen::Unobserved { agreement } => write!(
                f,
                "beside surface the scanner did not see, and what it saw does not match the landmark's template (agreement {agreement})"
            ),
            Unseen::Bare { coverage } => write!(
                f,
                "only {} % of the surface expected around it was found (in a hole or outside the scan)",
                100.0 * coverage
            ),
        }
    }
}

/// The landmarks of a face that the scanner may not have seen whole ([`detect_visible`]).
#[derive(Debug, Clone, PartialEq)]
pub struct VisibleLandmarks {
    /// Per landmark in [`LandmarkName::ALL`] order: placed, or why not.
    pub landmarks: [Result<Landmark, Unseen>; 5],
    /// Where each landmark is predicted (input units), seen or not: not a point of the input.
    /// A placed landmark's is where the fitted generic face puts it; an unseen one whose
    /// mirror partner (the other side's same corner) is placed is predicted from the partner
    /// mirrored across the input's own mid-sagittal plane (the fitted face's, refined by
    /// aligning the mirrored input with itself), else where the fitted face puts it.
    pub predicted: [DVec3; 5],
    /// Overall confidence in `[0, 1]` of the generic face fit.
    pub confidence: f64,
    /// RMS distance of the fitted generic face surface (inliers), input units.
    pub fit_rms: f64,
    /// Share of the generic face surface that found the input surface.
    pub inlier_fraction: f64,
    /// Mirror symmetry of the fit in `[0, 1]` (see [`Landmarks::symmetry`]).
    pub symmetry: f64,
    /// Rigid motion from the model's canonical frame to the input (see
    /// [`Landmarks::model_to_mesh`]).
    pub model_to_mesh: DAffine3,
}

/// Five placed landmarks, none unseen (`predicted` holds their positions).
impl From<Landmarks> for VisibleLandmarks {
    fn from(l: Landmarks) -> Self {
        VisibleLandmarks {
            landmarks: LandmarkName::ALL.map(|n| Ok(*l.get(n))),
            predicted: l.positions(),
            confidence: l.confidence,
            fit_rms: l.fit_rms,
            inlier_fraction: l.inlier_fraction,
            symmetry: l.symmetry,
            model_to_mesh: l.model_to_mesh,
        }
    }
}

impl VisibleLandmarks {
    /// The landmark of a given name, or why it was not placed.
    pub fn get(&self, name: LandmarkName) -> Result<&Landmark, Unseen> {
        self.landmarks[name as usize].as_ref().map_err(|u| *u)
    }

    /// All five landmarks, or [`LandmarkError::NotFound`] naming the first one not placed.
    pub fn complete(&self) -> Result<Landmarks, LandmarkError> {
        let get = |n: LandmarkName| {
            self.get(n).copied().map_err(|u| LandmarkError::NotFound {
                reason: format!("{n} is not on the surface: {u}"),
                best_score: self.confidence,
            })
        };
        Ok(Landmarks {
            outer_eye_right: get(LandmarkName::OuterEyeRight)?,
            inner_eye_right: get(LandmarkName::InnerEyeRight)?,
            inner_eye_left: get(LandmarkName::InnerEyeLeft)?,
            outer_eye_left: get(LandmarkName::OuterEyeLeft)?,
            nose_tip: get(LandmarkName::NoseTip)?,
            confidence: self.confidence,
            fit_rms: self.fit_rms,
            inlier_fraction: self.inlier_fraction,
            symmetry: self.symmetry,
            model_to_mesh: self.model_to_mesh,
        })
    }
}

/// Why the evidence behind a detection is weak ([`VisibleLandmarks::weak_evidence`]): the
/// landmarks are returned, with this reason, instead of being refused. Values are printed
/// unrounded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Weakness {
    /// The generic face fits the input less well than it fits typical faces: fit confidence
    /// `confidence` below `strong` ([`DetectOptions::strong_confidence`]).
    Fit {
        /// The fit confidence.
        confidence: f64,
        /// The confidence of a convincing fit.
        strong: f64,
    },
    /// The fitted face is less mirror-symmetric than faces usually are: `symmetry` below
    /// `strong` ([`DetectOptions::strong_symmetry`]).
    Asymmetric {
        /// The symmetry of the fit.
        symmetry: f64,
        /// The symmetry of a convincing fit.
        strong: f64,
    },
    /// The surface around a placed landmark matches its template weakly: local agreement
    /// `agreement` below `strong` ([`DetectOptions::min_local_agreement`]).
    Landmark {
        /// The landmark.
        name: LandmarkName,
        /// Its local template agreement.
        agreement: f64,
        /// The agreement of a convincing landmark.
        strong: f64,
    },
}

impl std::fmt::Display for Weakness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Weakness::Fit { confidence, strong } => write!(
                f,
                "the generic face fits weakly (fit confidence {confidence} < {strong})"
            ),
            Weakness::Asymmetric { symmetry, strong } => write!(
                f,
                "the fitted face is not very mirror-symmetric (symmetry {symmetry} < {strong})"
            ),
            Weakness::Landmark {
                name,
                agreement,
                strong,
            } => write!(
                f,
                "{name} matches its template weakly (agreement {agreement} < {strong})"
            ),
        }
    }
}

/// The weaknesses of a detection with fit confidence `confidence`, symmetry `symmetry` and the
/// placed landmarks `placed` (their confidences are the fit confidence times their local
/// agreement).
fn weaknesses<'a>(
    confidence: f64,
    symmetry: f64,
    placed: impl Iterator<Item = (LandmarkName, &'a Landmark)>,
    options: &DetectOptions,
) -> Vec<Weakness> {
    let mut out = Vec::new();
    if confidence < options.strong_confidence {
        out.push(Weakness::Fit {
            confidence,
            strong: options.strong_confidence,
        });
    }
    if symmetry < options.strong_symmetry {
        out.push(Weakness::Asymmetric {
            symmetry,
            strong: options.strong_symmetry,
        });
    }
    for (name, l) in placed {
        let agreement = if confidence > 0.0 {
            l.confidence / confidence
        } else {
            0.0
        };
        if agreement < options.min_local_agreement {
            out.push(Weakness::Landmark {
                name,
                agreement,
                strong: options.min_local_agreement,
            });
        }
    }
    out
}

impl Landmarks {
    /// Why the evidence behind these landmarks is weak under `options` (the options they were
    /// detected with); empty when every check is convincing.
    pub fn weak_evidence(&self, options: &DetectOptions) -> Vec<Weakness> {
        let placed = LandmarkName::ALL.into_iter().map(|n| (n, self.get(n)));
        weaknesses(self.confidence, self.symmetry, placed, options)
    }
}

impl VisibleLandmarks {
    /// Why the evidence behind the placed landmarks is weak under `options` (the options they
    /// were detected with); empty when every check is convincing. Unseen landmarks carry their
    /// own reason ([`Unseen`]).
    pub fn weak_evidence(&self, options: &DetectOptions) -> Vec<Weakness> {
        let placed = LandmarkName::ALL
            .into_iter()
            .filter_map(|n| self.get(n).ok().map(|l| (n, l)));
        weaknesses(self.confidence, self.symmetry, placed, options)
    }
}

/// Errors of the landmarks crate.
#[derive(Debug, thiserror::Error)]
pub enum LandmarkError {
    /// No face-like configuration was found.
    #[error("landmarks not found: {reason} (best candidate score {best_score}, needs a face with outward normals in the model's units)")]
    NotFound {
        /// What failed.
        reason: String,
        /// Confidence of the best candidate configuration in `[0, 1]`.
        best_score: f64,
    },
    /// The generic model is malformed.
    #[error("invalid generic model: {0}")]
    InvalidModel(String),
    /// Training data unusable.
    #[error("invalid training data: {0}")]
    InvalidTraining(String),
    /// Bad option value.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Mesh error.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// An operating-system failure on a file (the path and the OS error are kept).
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
    /// A landmark file could not be read or is malformed (`mesh-io` reads them).
    #[error(transparent)]
    File(#[from] mesh_io::IoError),
    /// A set of labelled points lacks one of the five landmarks.
    #[error("{source_name}: no landmark {label:?}")]
    MissingLandmark {
        /// Where the points came from (a file name).
        source_name: String,
        /// The Bosphorus label of the missing landmark.
        label: String,
    },
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
    /// The units of the mesh (or of the model) could not be told from its size or label.
    #[error("landmarks: {0}")]
    Units(#[from] meshcore::units::UnitsError),
}
