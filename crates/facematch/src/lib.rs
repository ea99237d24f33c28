//! Face matching with the bipolar descriptor: what `cargo xtask recognition --scans`, the CLI
//! (`bipolar enroll`, `identify`, `verify`) and Python share, one implementation.
//!
//! The path of a scan:
//!
//! 1. [`prepare`]: clean the scan ([`scanprep::clean`], units recognised, output in mm), detect
//!    the landmarks seen from the scanner ([`landmarks::detect_visible`]), clean it again with a
//!    crop around the *detected* nose tip and detect again (when the uncropped scan gives no
//!    face, the first detection is repeated on a crop around the point nearest the scanner,
//!    and the scan's notes say so). A scan in which no face is found is an error with the
//!    detector's reasons; an outer eye corner the detector reports unseen is a
//!    [`Lost`] corner (explicit), not a stand-in.
//! 2. [`describe`]: the geodesic fields of the outer eye corners and the nose tip (cut off at
//!    1.4 times the corners' distance), the bipolar descriptor of each of the three pole pairs
//!    ([`Pair`]) on the static area, without the band along holes and the border and without
//!    what the scanner saw at grazing incidence; for a probe also the reference-point search
//!    (each pole moved by 2 mm in 6 directions).
//! 3. [`Template`]: a gallery face's descriptors, also as seen from a set of turned scanner
//!    directions (view matching, [`ViewOptions`]), written to a versioned file
//!    ([`Template::write`], [`Gallery`]).
//! 4. [`compare`]: a probe against a template: the distance by each pair (the probe's search,
//!    the template's view nearest the probe's scanner direction), the score (the least over the
//!    pairs), and everything the comparison used or fell back on ([`Comparison`]).
//!
//! The options and their defaults (the benchmark's) are written once, in [`MatchOptions`]. The
//! figures a set of scores is judged by (rank-1, EER, ROC, McNemar, Wilson) are in [`metrics`].

mod area;
mod compare;
mod describe;
mod error;
mod evaluate;
mod fields;
pub mod fixture;
mod gallery;
mod keyed;
pub mod metrics;
mod options;
mod poles;
mod prepare;
mod template;
mod view;

pub use area::{grid_rule, Area, PoleRefs};
pub use compare::{compare, pair_score, Comparison, PairUse, ViewUse};
pub use describe::{describe, describe_with_fields, kept_vertices, Description, FaceFields};
pub use error::MatchError;
pub use evaluate::{evaluate, Evaluation, FallbackCount};
pub use fields::{description_fields, face_fields};
pub use gallery::{rank, Gallery, Ranked};
pub use keyed::KeyedSet;
pub use options::{
    MatchOptions, PrepareOptions, SearchOptions, ViewOptions, DEFAULT_EDGE_MM, VERIFY_THRESHOLD,
};
pub use poles::{Lost, Pair, Poles};
pub use prepare::{detect_landmarks, prepare, prepare_with, PreparedScan, ScanInput, StepTimes};
pub use template::{enroll, views_of, Template, TemplateView, FORMAT_VERSION};
pub use view::{
    cut_to_view, describe_view, nearest_vertex, probe_direction, seen_within, view_directions,
    ViewCut,
};

/// The direction toward the scanner in the frame of a range grid (`.bnt`): the scanner looks
/// down the z axis.
pub const GRID_SCANNER: meshcore::DVec3 = meshcore::DVec3::Z;
