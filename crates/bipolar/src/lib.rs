//! The bipolar invariant descriptor of a surface (the paper's sections 2 and 3).
//!
//! Two reference points `r`, `q` on a mesh give two geodesic distance fields `U_r`, `U_q`.
//! Their level curves at a constant geodesic step intersect; at each intersection the two
//! level curves open an angle whose cosine is invariant under rigid motions. The descriptor is
//! the set of points whose opening falls on the levels `alpha k / K`, each with a [`Key`] that
//! puts descriptors of different surfaces in correspondence.
//!
//! * [`describe`] builds a [`Descriptor`] of a [`Surface`] (a mesh with its topology) from
//!   [`Fields`]: a geodesic solver and reference points ([`Fields::Solve`]) or precomputed
//!   fields ([`Fields::Precomputed`]).
//! * [`DescriptorOptions`]: step ([`LevelSpec`]), region (`max_level`, `vertex_mask`), `K`,
//!   `alpha`, the selection rule ([`SelectionRule::Filter`], [`SelectionRule::IsoAngle`],
//!   [`SelectionRule::All`]) and the tangent method ([`TangentMethod::Gradient`] = M0 exact
//!   per-face gradient, [`TangentMethod::Strip`] = the paper's method 1,
//!   [`TangentMethod::Spline`] = the paper's method 2).
//! * More than two reference points: every pair `a < b` contributes, keys carry the pair.
//! * [`polar`]: the single-pole descriptor (geodesic polar coordinates around one point,
//!   [`describe_polar`]), keyed by `(level, sector)`.
//! * [`reference_candidates`]: placements of a reference point around a given one, for a
//!   search that keeps the least distance over them (detected references are millimetres off).
//! * [`io`]: CSV / JSON / PLY files. [`synthetic`]: test meshes.
//!
//! Determinism: points are sorted by key, then position. Errors: [`BipolarError`]; an empty
//! result is an error ([`BipolarError::NoIntersections`]) carrying the reason.

// Index loops over 3x3 matrices and reference pairs read better than iterator chains.
#![allow(clippy::needless_range_loop)]

mod build;
mod error;
pub mod io;
mod key;
pub mod polar;
mod search;
pub mod synthetic;
mod types;

pub use build::{boundary_band, boundary_band_with, describe, solve_fields, Fields};
pub use error::BipolarError;
pub use geodesic::Source;
pub use key::Key;
pub use meshcore::Surface;
pub use polar::{describe_polar, PolarDescriptor, PolarKey, PolarOptions, PolarPoint};
pub use search::{
    describe_searched, least_searched_distance, moved_pairs, reference_candidates, MovedPair,
    SearchedPole,
};
pub use types::{
    Descriptor, DescriptorOptions, DescriptorPoint, DescriptorStats, IsoAngleOptions, IsoCrossings,
    IsoRepeats, LevelSpec, SelectionKind, SelectionRule, SplineOptions, StripOptions,
    TangentMethod,
};
