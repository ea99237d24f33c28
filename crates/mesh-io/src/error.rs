use meshcore::MeshError;
use std::fmt;
use std::path::Path;
use thiserror::Error;

/// Where in a file a problem was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number of a text file.
    Line(usize),
    /// 0-based byte offset in a binary file.
    Byte(usize),
    /// The problem concerns the whole file (e.g. it is empty).
    File,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}: "),
            Location::Byte(b) => write!(f, "byte {b}: "),
            Location::File => Ok(()),
        }
    }
}

/// Errors of the mesh readers and writers. Every variant names the file.
#[derive(Debug, Error)]
pub enum IoError {
    /// An operating-system failure on a file (the path and the OS error are kept).
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
    /// The file content is malformed: truncated, inconsistent counts, bad numbers, indices out
    /// of range, non-finite coordinates, ...
    #[error("{file}: {at}{problem}")]
    Malformed {
        /// The file.
        file: String,
        /// Line (text) or byte offset (binary) of the problem.
        at: Location,
        /// What is wrong.
        problem: String,
    },
    /// The file is valid in its format but uses a feature this crate does not read.
    #[error("{file}: {at}unsupported: {problem}")]
    Unsupported {
        /// The file.
        file: String,
        /// Line or byte offset.
        at: Location,
        /// The unsupported feature.
        problem: String,
    },
    /// The file extension does not name a known format.
    #[error("{file}: unknown mesh format (extension {ext:?}); expected one of obj, ply, stl, off, gltf, glb, bnt")]
    UnknownFormat {
        /// The file.
        file: String,
        /// The extension found (may be empty).
        ext: String,
    },
    /// The parsed data does not make a valid mesh (empty, non-finite, index out of range).
    #[error("{file}: {source}")]
    Mesh {
        /// The file.
        file: String,
        /// The mesh validation error.
        #[source]
        source: MeshError,
    },
    /// Data handed to a writer is inconsistent (e.g. colour count differs from vertex count).
    #[error("{file}: cannot write: {problem}")]
    InvalidInput {
        /// The file.
        file: String,
        /// What is wrong.
        problem: String,
    },
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
}

impl IoError {
    pub(crate) fn malformed(file: &str, at: Location, problem: impl Into<String>) -> Self {
        IoError::Malformed {
            file: file.to_string(),
            at,
            problem: problem.into(),
        }
    }

    pub(crate) fn line(file: &str, line: usize, problem: impl Into<String>) -> Self {
        Self::malformed(file, Location::Line(line), problem)
    }

    pub(crate) fn byte(file: &str, offset: usize, problem: impl Into<String>) -> Self {
        Self::malformed(file, Location::Byte(offset), problem)
    }

    pub(crate) fn whole(file: &str, problem: impl Into<String>) -> Self {
        Self::malformed(file, Location::File, problem)
    }

    pub(crate) fn io(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        IoError::Io(meshcore::FileError::new(action, path, source))
    }

    pub(crate) fn mesh(file: &str, source: MeshError) -> Self {
        IoError::Mesh {
            file: file.to_string(),
            source,
        }
    }

    pub(crate) fn invalid(file: &str, problem: impl Into<String>) -> Self {
        IoError::InvalidInput {
            file: file.to_string(),
            problem: problem.into(),
        }
    }
}
