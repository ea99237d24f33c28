//! Normalised shape distances between bipolar descriptors (or any 3D point sets), exact where
//! the points correspond and robust where they do not.
//!
//! The paper defines the distance of two descriptors as `inf_{h in SO(3)} ||S1 - h S2||`,
//! computed with ICP. This crate offers:
//!
//! * [`keyed_distance`]: points paired by their keys (`u64`, e.g. `bipolar::Key::pack`),
//!   centred, rotation in closed form ([`RotationMethod::Kabsch`] with the reflection guard,
//!   or [`RotationMethod::Horn`]); optional IRLS weights ([`RobustLoss`]) and a residual gate.
//!   Distance `d_L2 = min_R ||A - R B||_F / sqrt(||A||_F^2 + ||B||_F^2)` in [0, 1].
//! * [`icp()`] and [`global_icp`] on [`PreparedSet`]s: point-to-point (the paper's definition)
//!   and point-to-plane ICP with an exact k-d tree ([`nn::PointTree`]: tight boxes, grouped
//!   warm-started queries, the same answers as brute force) behind a certified walk on the
//!   target's neighbour graph ([`nn::NeighbourGraph`]: most correspondences near convergence
//!   without a tree query, still exact), trimmed pairs, convergence test, and a
//!   multi-start global strategy (principal axes + the 24 cube rotations on a subsample, then
//!   refinement on all points). [`icp_distance`] returns the normalised symmetric Hausdorff,
//!   mean and RMS closest-point distances after alignment ([`ClosestPointStats`]).
//! * [`icp_to_target`]: the one ICP loop, generic over an [`IcpTarget`] (a [`PreparedSet`],
//!   a mesh surface through [`meshcore::FaceLocator`], the landmark detector's surface index),
//!   with point-to-point or point-to-plane steps, distance and normal gates, trimming,
//!   damping and the stopping rule as options ([`IcpLoopOptions`]); [`icp()`] and
//!   [`global_icp`] run it. Rigid motions are [`glam::DAffine3`].
//! * [`compare()`]: one comparison in a chosen [`Mode`] (keyed, ICP mean or Hausdorff) from flat
//!   settings ([`CompareOptions`]), with its details as JSON: what the command line and the
//!   Python bindings call.
//! * [`pairwise_matrix`] and [`write_matrix_csv`]: parallel symmetric distance matrices;
//!   [`Separation`]: how such a matrix separates groups.
//! * [`landmark_icp_rms`]: points onto a mesh surface by a trimmed ICP started from
//!   corresponding landmarks, scored by their RMS distance to the surface (the benchmarks' ICP
//!   score on raw meshes).
//!
//! The normalisations and their proofs of lying in [0, 1] are in `docs/shape-distance.md`.
//! Nothing panics on user input: errors are [`ShapeDistError`].

pub mod compare;
mod error;
pub mod icp;
pub mod keyed;
mod matrix;
pub mod nn;
pub mod points;
mod surface_icp;
pub mod target;

use glam::{DAffine3, DVec3};
use serde::Serialize;

pub use compare::{compare, CompareOptions, ComparedSet, Comparison, Mode, RobustWeights};
pub use error::{ShapeDistError, Which};
pub use glam;
pub use icp::{
    closest_point_stats, global_icp, icp, ClosestPointStats, GlobalOptions, GlobalResult,
    IcpOptions, IcpResult, IcpVariant, PrepareOptions, PreparedSet,
};
pub use keyed::{
    align_pairs, keyed_distance, pair_by_keys, Alignment, KeyedDistance, KeyedOptions, Pairing,
    RobustLoss, RotationMethod,
};
pub use matrix::{pairwise_matrix, write_matrix_csv, PairError, Separation};
pub use surface_icp::{landmark_icp_rms, rms_to_surface, strided_points, trimmed_icp};
pub use target::{
    icp_to_target, Convergence, Damping, IcpLoopOptions, IcpTarget, Match, PointTarget,
    TrimRounding,
};

/// Result of [`icp_distance`]: the global alignment and the closest-point distances after it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IcpDistance {
    /// Closest-point distances (raw and normalised) at the final pose.
    pub stats: ClosestPointStats,
    /// Rigid motion mapping centred B onto centred A (translation zero unless estimated).
    pub motion: DAffine3,
    /// Iterations of the final refinement.
    pub iterations: usize,
    /// RMS of the kept pairs at the final pose (ICP's own objective).
    pub rmse: f64,
    /// Whether the final refinement met its convergence test.
    pub converged: bool,
    /// Starting rotations tried.
    pub starts: usize,
}

/// Aligns B onto A with [`global_icp`] and evaluates the closest-point distances.
pub fn icp_distance(
    a: &PreparedSet,
    b: &PreparedSet,
    opts: &GlobalOptions,
) -> Result<IcpDistance, ShapeDistError> {
    let g = global_icp(a, b, opts)?;
    let stats = closest_point_stats(a, b, &g.icp.motion);
    Ok(IcpDistance {
        stats,
        motion: g.icp.motion,
        iterations: g.icp.iterations,
        rmse: g.icp.rmse,
        converged: g.icp.converged,
        starts: g.starts,
    })
}

/// [`icp_distance`] on raw point slices (prepares both sets with default options).
pub fn icp_distance_points(
    a: &[DVec3],
    b: &[DVec3],
    opts: &GlobalOptions,
) -> Result<IcpDistance, ShapeDistError> {
    let po = PrepareOptions::default();
    let pa = PreparedSet::new(a, &po, Which::A)?;
    let pb = PreparedSet::new(b, &po, Which::B)?;
    icp_distance(&pa, &pb, opts)
}
