use thiserror::Error;

/// Errors raised when building or querying a [`crate::TriMesh`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh has no vertices or no triangles.
    #[error("empty mesh: {vertices} vertices, {triangles} triangles")]
    Empty {
        /// Number of vertices given.
        vertices: usize,
        /// Number of triangles given.
        triangles: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteVertex {
        /// Index of the offending vertex.
        vertex: usize,
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
        /// z coordinate.
        z: f64,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Index of the offending triangle.
        triangle: usize,
        /// The out-of-range vertex index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// The mesh has more vertices than `u32` can index.
    #[error("too many vertices ({0}); at most u32::MAX are supported")]
    TooManyVertices(usize),
    /// A face index is out of range.
    #[error("face {face} does not exist (the mesh has {faces} faces)")]
    FaceOutOfRange {
        /// The face index asked for.
        face: u32,
        /// Number of faces.
        faces: usize,
    },
    /// A vertex index is out of range.
    #[error("vertex {vertex} does not exist (the mesh has {vertices} vertices)")]
    VertexOutOfRange {
        /// The vertex index asked for.
        vertex: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A per-vertex field whose length is not the mesh's vertex count.
    #[error("a per-vertex field has {values} values for a mesh of {vertices} vertices")]
    FieldLength {
        /// Number of values given.
        values: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// Barycentric coordinates that are not finite, negative beyond tolerance or do not sum to 1.
    #[error("invalid barycentric coordinates ({0}, {1}, {2}): must be finite, >= 0 and sum to 1")]
    InvalidBarycentric(f64, f64, f64),
    /// A query point is not finite.
    #[error("query point ({0}, {1}, {2}) is not finite")]
    NonFinitePoint(f64, f64, f64),
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] crate::UnknownChoice),
}
