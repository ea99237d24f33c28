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
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
    /// The method is not available yet.
    #[error("geodesic method {0} is not implemented yet")]
    NotImplemented(&'static str),
    /// A numerical step failed (e.g. a sparse factorisation of a mesh with degenerate faces).
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A negative or NaN cut-off.
    #[error("invalid max_distance {0}: must be positive")]
    InvalidCutoff(f64),
}
