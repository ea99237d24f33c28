//! Shared pieces of `cargo xtask robustness` and `cargo xtask recognition`: face-set loading,
//! straightest-geodesic perturbation of reference points, the static-area segmentation, the
//! keyed descriptors (bipolar grid and single pole) with their distance, and report writing.

pub mod data;
pub mod descriptor;
pub mod pipeline;
pub mod polar;
pub mod report;
pub mod segment;
pub mod walk;
