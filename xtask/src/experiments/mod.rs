//! Shared pieces of `cargo xtask robustness` and `cargo xtask recognition`:
//! straightest-geodesic perturbation of reference points, the keyed descriptors (bipolar grid
//! and single pole) with their distance, and report writing. Face-set loading, the face frame
//! and the static-area mask are in the `facemodel` crate.

pub mod descriptor;
pub mod pipeline;
pub mod polar;
pub mod report;
pub mod walk;
