//! The ICT FaceKit face model and face geometry helpers used by the experiments, the landmark
//! evaluation and the tests.
//!
//! * [`shared`]: the one lookup of the shared data folder ([`shared_dir`]; rule in the module
//!   documentation) and the locations of the paper set and the model inside it.
//! * [`model`]: [`FaceModel`] loads `neutral.obj`, the float32 `.npy` identity and expression
//!   offsets and `model.json`, and samples faces (identities `N(0, 1)`, random expressions,
//!   deterministic under a seeded generator); [`random_rigid_motion`] draws a rigid motion as a
//!   [`meshcore::DAffine3`]; landmark vertex ids and positions.
//! * [`faceset`]: [`load_face_set`] reads a folder of faces in the ICT topology (the paper set)
//!   in a stable order and checks them against `landmarks.json` (read by
//!   `mesh_io::read_ict_landmarks`); the ground-truth vertex ids
//!   [`RIGHT_EYE_OUTER`], [`LEFT_EYE_OUTER`], [`NOSE_TIP`].
//! * [`frame`]: the landmark-derived [`FaceFrame`] and the static-area vertex mask
//!   [`static_mask`].
//! * [`variation`]: faces beyond the model's span, for tests: [`FaceModel::strong_expression`]
//!   (expressions past full strength or mixed) and [`random_warp`] (smooth non-rigid warps of
//!   2-6 mm).
//!
//! Every fallible function returns [`FaceModelError`]. Meshes, `.npy` arrays and the landmark
//! file are read with `mesh-io`.

mod error;
pub mod faceset;
pub mod frame;
pub mod model;
pub mod shared;
pub mod variation;

pub use error::FaceModelError;
pub use faceset::{load_face_set, Face, FaceLandmarks, LEFT_EYE_OUTER, NOSE_TIP, RIGHT_EYE_OUTER};
pub use frame::{face_frame, static_mask, FaceFrame};
pub use model::{random_rigid_motion, standard_normal, FaceModel, LANDMARK_NAMES};
pub use shared::{
    default_model_dir, default_paper_set, shared_dir, workspace_root_from, MODEL, PAPER_SET,
    SHARED_ENV,
};
pub use variation::{random_warp, Warp};
