//! Errors of the curve representations.

use thiserror::Error;

/// Everything that can go wrong when building or comparing the curve representations.
#[derive(Debug, Error)]
pub enum FaceCurvesError {
    /// The mesh is invalid.
    #[error(transparent)]
    Mesh(#[from] meshcore::MeshError),
    /// The geodesic solver failed.
    #[error("geodesic solver: {0}")]
    Geodesic(#[from] geodesic::GeodesicError),
    /// Isoline extraction failed.
    #[error("level curves: {0}")]
    LevelCurves(#[from] levelcurves::LevelCurveError),
    /// The closest-point distance of two curve networks failed.
    #[error("shape distance: {0}")]
    ShapeDist(#[from] shapedist::ShapeDistError),
    /// An option is out of its range; the message names it and the value.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// An option name is none of the valid ones.
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
    /// A per-vertex input (field or mask) has the wrong length.
    #[error("{what} has {got} values but the mesh has {expected} vertices")]
    VertexCount {
        /// What was given (`"field"`, `"mask"`).
        what: &'static str,
        /// Number of vertices.
        expected: usize,
        /// Number of values given.
        got: usize,
    },
    /// A distance field value is NaN or negative infinity (`+inf`, unreachable, is allowed).
    #[error("distance field has a non-finite value {value} at vertex {vertex}")]
    NonFiniteField {
        /// The vertex.
        vertex: usize,
        /// Its value.
        value: f64,
    },
    /// A curve has too few points for its kind.
    #[error("{which} curve has {got} points; a {kind} curve needs at least {needed}")]
    TooFewPoints {
        /// Which curve (`"first"`, `"second"`).
        which: &'static str,
        /// `"closed"` or `"open"`.
        kind: &'static str,
        /// Points needed.
        needed: usize,
        /// Points given.
        got: usize,
    },
    /// A curve point is NaN or infinite.
    #[error("{which} curve has a non-finite point at index {index}")]
    NonFinitePoint {
        /// Which curve (`"first"`, `"second"`).
        which: &'static str,
        /// Index of the point.
        index: usize,
    },
    /// A curve has zero length (all its points coincide).
    #[error("{which} curve has zero length")]
    ZeroLength {
        /// Which curve (`"first"`, `"second"`).
        which: &'static str,
    },
    /// No curve could be extracted; the message says why.
    #[error("no curves: {0}")]
    NoCurves(String),
    /// An operating-system failure on a file (the path and the OS error are kept).
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
    /// A curve file is malformed; the message says how.
    #[error("{}: {message}", path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Two facial-curve descriptors have no level in common.
    #[error(
        "the two descriptors share no curve level (first has {first} curves, second {second})"
    )]
    NoSharedCurves {
        /// Curves of the first descriptor.
        first: usize,
        /// Curves of the second descriptor.
        second: usize,
    },
}
