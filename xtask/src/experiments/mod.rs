//! Shared pieces of `cargo xtask robustness` and `cargo xtask recognition`:
//! straightest-geodesic perturbation of reference points, the single-pole descriptor and its
//! point set, the pipeline glue around `bipolar` and `shapedist`, and report writing. Face-set
//! loading, the face frame and the static-area mask are in the `facemodel` crate.

pub mod keyed;
pub mod pipeline;
pub mod polar;
pub mod report;
pub mod walk;
