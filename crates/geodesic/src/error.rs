use thiserror::Error;

/// Errors of the geodesic solvers.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GeodesicError {
    /// The mesh itself is invalid.
    #[error(transparent)]
    Mesh(#[from] meshcore::MeshError),
    /// No source was given.
    #[error("no source given")]
    NoSource,
    /// A source vertex does not exist.
    #[error("source vertex {vertex} does not exist (the mesh has {vertices} vertices)")]
    SourceOutOfRange {
        /// The vertex asked for.
        vertex: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A method name was not recognised.
    #[error("unknown geodesic method {0:?} (expected exact, fmm, heat or dijkstra)")]
    UnknownMethod(String),
    /// The method is not available yet.
    #[error("geodesic method {0} is not implemented yet")]
    NotImplemented(&'static str),
    /// A numerical step failed (e.g. a sparse factorisation of a mesh with degenerate faces).
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A negative or NaN cut-off.
    #[error("invalid max_distance {0}: must be positive")]
    InvalidCutoff(f64),
    /// A straightest-geodesic direction is zero, not finite or normal to the surface.
    #[error("invalid walk direction: {0}")]
    InvalidDirection(String),
    /// A straightest-geodesic length is negative or not finite.
    #[error("invalid walk length {0}: must be finite and >= 0")]
    InvalidLength(f64),
    /// A straightest geodesic entered a zero-area face.
    #[error("the walk entered degenerate face {0}")]
    DegenerateFace(u32),
    /// A straightest geodesic could not continue (inconsistent adjacency, too many crossings).
    #[error("straightest geodesic: {0}")]
    WalkFailed(String),
}
