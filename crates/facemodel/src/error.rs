//! The error type of the crate.

use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors of the face-model loader, the sampler, the face-set loader and the shared-folder
/// lookup. Every file error names the file.
#[derive(Debug, Error)]
pub enum FaceModelError {
    /// An operating-system failure on a file (the path and the OS error are kept).
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
    /// A mesh file is malformed or is not a valid mesh (the message of `mesh-io` names the
    /// file and the line or byte).
    #[error("{source}")]
    Mesh {
        /// The mesh file.
        path: PathBuf,
        /// What `mesh-io` found.
        #[source]
        source: mesh_io::IoError,
    },
    /// An `.npy` file is malformed: bad magic or header, unsupported dtype or order, data size
    /// not matching the shape (the message names the file and the byte).
    #[error("{source}")]
    Npy {
        /// The `.npy` file.
        path: PathBuf,
        /// What the `.npy` reader found.
        #[source]
        source: mesh_io::IoError,
    },
    /// The face set's `landmarks.json` is malformed (the message of `mesh-io` names the file
    /// and what is wrong).
    #[error("{source}")]
    Landmarks {
        /// The landmark file.
        path: PathBuf,
        /// What `mesh-io` found.
        #[source]
        source: mesh_io::IoError,
    },
    /// An `.npy` array is well formed but does not have the shape the model needs.
    #[error("{}: array of shape {shape:?}, expected {expected}", path.display())]
    NpyShape {
        /// The `.npy` file.
        path: PathBuf,
        /// The shape found.
        shape: Vec<usize>,
        /// The shape expected, e.g. `(k, 6706, 3)`.
        expected: String,
    },
    /// A JSON file is not valid JSON.
    #[error("{}: {source}", path.display())]
    Json {
        /// The JSON file.
        path: PathBuf,
        /// The parser's error (with line and column).
        #[source]
        source: serde_json::Error,
    },
    /// A JSON file is valid JSON but a key is missing or holds the wrong kind of value.
    #[error("{}: {problem}", path.display())]
    JsonContent {
        /// The JSON file.
        path: PathBuf,
        /// Which key and what is wrong with it.
        problem: String,
    },
    /// More weights than the model has components.
    #[error("{given} {kind} weights for a model of {available} {kind} components")]
    TooManyWeights {
        /// `identity` or `expression`.
        kind: &'static str,
        /// Number of weights given.
        given: usize,
        /// Number of components of the model.
        available: usize,
    },
    /// The model has no landmark of this name.
    #[error("the face model has no landmark named {name}")]
    UnknownLandmark {
        /// The name asked for.
        name: String,
    },
    /// The model has no expression recipe of this name.
    #[error("the face model has no expression recipe named {name}")]
    UnknownRecipe {
        /// The name asked for.
        name: String,
    },
    /// A face folder is missing or holds no `.obj` file.
    #[error("{}: {problem}", dir.display())]
    FaceSet {
        /// The folder.
        dir: PathBuf,
        /// What is wrong (`not found`, `no .obj file`).
        problem: String,
    },
    /// A face of the set lacks a ground-truth landmark vertex (it is not in the ICT topology).
    #[error("{face}: landmark vertex {vertex} missing ({n_vertices} vertices)")]
    MissingLandmarkVertex {
        /// Face name (file stem).
        face: String,
        /// The vertex id.
        vertex: u32,
        /// Vertex count of the face.
        n_vertices: usize,
    },
    /// `landmarks.json` places a landmark away from its ground-truth vertex.
    #[error("{face}: landmarks.json {landmark} is {distance} away from vertex {vertex}")]
    LandmarkMismatch {
        /// Face name (file stem).
        face: String,
        /// Landmark name.
        landmark: String,
        /// Ground-truth vertex id.
        vertex: u32,
        /// Distance between the file's position and the vertex.
        distance: f64,
    },
    /// Building a mesh or reading a vertex failed (e.g. a vertex id out of range).
    #[error(transparent)]
    Geometry(#[from] meshcore::MeshError),
    /// `$BIPOLAR_SHARED` is set but does not name a folder.
    #[error("BIPOLAR_SHARED={} is not a folder", path.display())]
    SharedEnvNotAFolder {
        /// The value of the variable.
        path: PathBuf,
    },
    /// No shared data folder was found (see [`crate::shared`] for the rule).
    #[error(
        "shared data folder not found (looked at {}); set BIPOLAR_SHARED",
        fmt_paths(searched)
    )]
    SharedNotFound {
        /// The candidate folders looked at (empty when no workspace root was found).
        searched: Vec<PathBuf>,
    },
}

fn fmt_paths(p: &[PathBuf]) -> String {
    if p.is_empty() {
        return "no workspace root above the current directory".into();
    }
    p.iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

impl FaceModelError {
    /// Wraps an error of `mesh_io::read_mesh` on `path`, keeping an OS error as [`Self::Io`].
    pub(crate) fn mesh(path: &Path, e: mesh_io::IoError) -> Self {
        Self::wrap(path, e, |path, source| Self::Mesh { path, source })
    }

    /// Wraps an error of `mesh_io::read_npy_f32` on `path`, keeping an OS error as [`Self::Io`].
    pub(crate) fn npy(path: &Path, e: mesh_io::IoError) -> Self {
        Self::wrap(path, e, |path, source| Self::Npy { path, source })
    }

    /// Wraps an error of `mesh_io::read_ict_landmarks` on `path`, keeping an OS error as
    /// [`Self::Io`].
    pub(crate) fn landmarks(path: &Path, e: mesh_io::IoError) -> Self {
        Self::wrap(path, e, |path, source| Self::Landmarks { path, source })
    }

    /// An OS error of `mesh-io` as [`Self::Io`], any other as `variant`.
    fn wrap(
        path: &Path,
        e: mesh_io::IoError,
        variant: impl FnOnce(PathBuf, mesh_io::IoError) -> Self,
    ) -> Self {
        match e {
            mesh_io::IoError::Io(e) => Self::Io(e),
            e => variant(path.to_path_buf(), e),
        }
    }

    /// An OS error on `path`.
    pub(crate) fn io(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        Self::Io(meshcore::FileError::new(action, path, source))
    }

    /// A content problem of the JSON file `path`.
    pub(crate) fn json(path: &Path, problem: impl Into<String>) -> Self {
        Self::JsonContent {
            path: path.to_path_buf(),
            problem: problem.into(),
        }
    }
}
