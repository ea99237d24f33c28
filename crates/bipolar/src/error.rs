//! Errors of the descriptor.

use thiserror::Error;

/// Everything that can go wrong when building or reading a descriptor.
///
/// "No intersections in range" is an **error** ([`BipolarError::NoIntersections`], with the
/// reason), never a silently empty descriptor.
#[derive(Debug, Error)]
pub enum BipolarError {
    /// The mesh is invalid.
    #[error(transparent)]
    Mesh(#[from] meshcore::MeshError),
    /// The geodesic solver failed.
    #[error("geodesic solver: {0}")]
    Geodesic(#[from] geodesic::GeodesicError),
    /// Isoline extraction failed.
    #[error("level curves: {0}")]
    LevelCurves(#[from] levelcurves::LevelCurveError),
    /// Fewer than two reference points (or fields), or more than 256.
    #[error("need between 2 and 256 reference points, got {0}")]
    ReferenceCount(usize),
    /// Two reference points lie on different connected components of the mesh.
    #[error("reference points {a} and {b} lie on different connected components (the geodesic distance between them is infinite)")]
    DifferentComponents {
        /// First reference.
        a: usize,
        /// Second reference.
        b: usize,
    },
    /// Two reference points coincide.
    #[error("reference points {a} and {b} coincide (distance {distance:e})")]
    CoincidentReferences {
        /// First reference.
        a: usize,
        /// Second reference.
        b: usize,
        /// Their (geodesic) distance.
        distance: f64,
    },
    /// A reference point lies on a degenerate (zero-area) face.
    #[error("reference point {reference} lies on degenerate face {face} (zero area)")]
    DegenerateFace {
        /// The reference.
        reference: usize,
        /// The face.
        face: u32,
    },
    /// A field has the wrong number of values.
    #[error("field {field} has {got} values but the mesh has {expected} vertices")]
    FieldLength {
        /// Field index.
        field: usize,
        /// Number of vertices.
        expected: usize,
        /// Number of values.
        got: usize,
    },
    /// A field value is NaN or negative infinity (`+inf` means unreachable and is allowed).
    #[error("field {field} has a non-finite value {value} at vertex {vertex}")]
    NonFiniteField {
        /// Field index.
        field: usize,
        /// Vertex.
        vertex: usize,
        /// The value.
        value: f64,
    },
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The descriptor would be empty; the message says why.
    #[error("no descriptor points: {0}")]
    NoIntersections(String),
    /// The spline tangent method failed in a way that has no fallback.
    #[error("B-spline tangents: {0}")]
    Spline(#[from] bspline::BSplineError),
    /// An operating-system failure on a file (the path and the OS error are kept).
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
    /// A descriptor file is malformed or cannot hold the descriptor.
    #[error("{}: {message}", path.display())]
    File {
        /// File.
        path: std::path::PathBuf,
        /// What is wrong (line number included where relevant).
        message: String,
    },
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
}
