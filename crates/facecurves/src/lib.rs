//! The two curve representations the paper compares the bipolar one with (section 6), as
//! descriptors with a distance each:
//!
//! * [`iso`]: **iso-curvature curves** (Bannour and Ghorbel, section 6.1): the level sets of
//!   the two principal curvature fields `k1 >= k2` (estimated by
//!   [`landmarks::curvature::vertex_curvatures`]) at chosen levels, extracted by
//!   [`levelcurves`]. Two networks are compared by the normalised RMS closest-point distance
//!   after a global ICP alignment ([`shapedist::icp_distance_points`]): the curves carry no
//!   correspondence across surfaces.
//! * [`facial`]: **facial curves** (Samir et al., Srivastava et al., section 6.2): the level
//!   curves of the geodesic distance from the nose tip at radii `i * step`; two faces are
//!   compared curve by curve with the elastic distance and the per-curve distances are summed
//!   ([`Aggregate`]).
//! * [`elastic`]: the elastic distance between two 3D curves by their square-root velocity
//!   functions (SRVF): invariant to translation, rotation (Kabsch,
//!   [`meshcore::linalg::kabsch_rotation`]), reparametrisation (dynamic programming over a grid
//!   of piecewise-linear reparametrisations, start-point search for closed curves) and,
//!   optionally, scale.
//!
//! * [`io`]: JSON files of either representation.
//! * [`nose`]: both representations of a face around its nose tip from the nose's geodesic
//!   field (facial curves at `D / N` steps, the iso-curvature network in the disc `U_n <= D` at
//!   levels shared by a face set) and their distances, as the experiments use them.
//!
//! `docs/section6.md` describes what was implemented from the cited papers and where it
//! departs from them. Nothing here panics on user input: errors are [`FaceCurvesError`].

pub mod elastic;
mod error;
pub mod facial;
pub mod io;
pub mod iso;
pub mod nose;

pub use elastic::{elastic_distance, ElasticMatch, ElasticOptions, Resampling};
pub use error::FaceCurvesError;
pub use facial::{
    describe_facial_curves, describe_facial_curves_from, facial_curves_distance, Aggregate,
    FacialCurve, FacialCurvesDescriptor, FacialCurvesOptions, FacialDistance,
};
pub use iso::{
    describe_iso_curvature, iso_curvature_distance, principal_curvature_fields,
    IsoCurvatureDescriptor, IsoCurvatureOptions, IsoCurve, IsoLevels, PrincipalField,
};
