//! Library errors as Python exceptions.
//!
//! The exception classes live in `bipolar/errors.py` (a hierarchy with multiple bases, e.g.
//! `InputError(BipolarError, ValueError)`, which `create_exception!` cannot express). Each
//! library error enum is mapped here, in one function per crate, to the class that fits; the
//! message is always the library's own `Display` text.

use pyo3::prelude::*;
use pyo3::types::PyType;

/// Which exception class of `bipolar.errors` an error becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `InputError` (a `ValueError`).
    Input,
    /// `InputTypeError` (a `ValueError` and a `TypeError`).
    Type,
    /// `IndexOutOfRangeError` (a `ValueError` and an `IndexError`).
    Index,
    /// `FileFormatError` (a `ValueError`).
    Format,
    /// `NoDescriptorPointsError` (a `ValueError`).
    NoPoints,
    /// `FileError` (an `OSError`).
    File,
    /// `LandmarksNotFoundError` (detection found no face).
    NotFound,
    /// `ComputationError` (a `RuntimeError`).
    Computation,
    /// `TemplateSettingsError` (a `ValueError`): a template made with other settings.
    Settings,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Input => "InputError",
            Kind::Type => "InputTypeError",
            Kind::Index => "IndexOutOfRangeError",
            Kind::Format => "FileFormatError",
            Kind::NoPoints => "NoDescriptorPointsError",
            Kind::File => "FileError",
            Kind::NotFound => "LandmarksNotFoundError",
            Kind::Computation => "ComputationError",
            Kind::Settings => "TemplateSettingsError",
        }
    }
}

/// A Python exception of the given kind with `message`.
pub fn err(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| {
        let class = py
            .import("bipolar.errors")
            .and_then(|m| m.getattr(kind.class_name()))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(c) => PyErr::from_type(c, message),
            // The package is always installed with its errors module; if it was not importable
            // the message still reaches the user.
            Err(_) => pyo3::exceptions::PyValueError::new_err(message),
        }
    })
}

/// `InputError` with `message`.
pub fn input(message: impl Into<String>) -> PyErr {
    err(Kind::Input, message)
}

/// `InputTypeError` with `message`.
pub fn type_error(message: impl Into<String>) -> PyErr {
    err(Kind::Type, message)
}

/// `IndexOutOfRangeError` with `message`.
pub fn index(message: impl Into<String>) -> PyErr {
    err(Kind::Index, message)
}

/// The Python exception (of `bipolar.errors`) for a `meshcore::MeshError`.
pub fn mesh(e: meshcore::MeshError) -> PyErr {
    use meshcore::MeshError as E;
    let kind = match e {
        E::IndexOutOfRange { .. } | E::FaceOutOfRange { .. } | E::VertexOutOfRange { .. } => {
            Kind::Index
        }
        _ => Kind::Input,
    };
    err(kind, e.to_string())
}

/// The message of an error followed by its sources (`a: b: c`): the library errors keep the
/// OS error as their source, not in their own text.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cur = e.source();
    while let Some(c) = cur {
        let t = c.to_string();
        if !s.ends_with(&t) {
            s.push_str(": ");
            s.push_str(&t);
        }
        cur = c.source();
    }
    s
}

fn io_kind(e: &mesh_io::IoError) -> Kind {
    use mesh_io::IoError as E;
    match e {
        E::Io(_) => Kind::File,
        E::Malformed { .. } | E::Unsupported { .. } | E::UnknownFormat { .. } | E::Mesh { .. } => {
            Kind::Format
        }
        E::InvalidInput { .. } | E::UnknownChoice(_) => Kind::Input,
    }
}

fn io_kind_err(e: &mesh_io::IoError, message: String) -> PyErr {
    err(io_kind(e), message)
}

/// The Python exception (of `bipolar.errors`) for a `mesh_io::IoError`.
pub fn io(e: mesh_io::IoError) -> PyErr {
    err(io_kind(&e), chain(&e))
}

fn geodesic_kind(e: &geodesic::GeodesicError) -> Kind {
    use geodesic::GeodesicError as E;
    match e {
        E::Mesh(meshcore::MeshError::IndexOutOfRange { .. })
        | E::Mesh(meshcore::MeshError::FaceOutOfRange { .. })
        | E::Mesh(meshcore::MeshError::VertexOutOfRange { .. })
        | E::SourceOutOfRange { .. } => Kind::Index,
        E::Mesh(_)
        | E::NoSource
        | E::UnknownChoice(_)
        | E::InvalidCutoff(_)
        | E::InvalidDirection(_)
        | E::InvalidLength(_) => Kind::Input,
        E::NotImplemented(_) | E::Numerical(_) | E::DegenerateFace(_) | E::WalkFailed(_) => {
            Kind::Computation
        }
    }
}

/// The Python exception (of `bipolar.errors`) for a `geodesic::GeodesicError`.
pub fn geodesic(e: geodesic::GeodesicError) -> PyErr {
    err(geodesic_kind(&e), e.to_string())
}

/// The Python exception (of `bipolar.errors`) for a `bipolar::BipolarError`.
pub fn descriptor(e: bipolar::BipolarError) -> PyErr {
    use bipolar::BipolarError as E;
    let kind = match &e {
        E::Mesh(m) => return mesh(m.clone()),
        E::Geodesic(g) => geodesic_kind(g),
        E::NoIntersections(_) => Kind::NoPoints,
        E::Spline(_) => Kind::Computation,
        E::Io(_) => Kind::File,
        E::File { .. } => Kind::Format,
        _ => Kind::Input,
    };
    err(kind, chain(&e))
}

/// `shapedist::ShapeDistError` (every variant is about the input sets or options).
pub fn shapedist(e: shapedist::ShapeDistError) -> PyErr {
    input(e.to_string())
}

/// The Python exception (of `bipolar.errors`) for a `landmarks::LandmarkError`.
pub fn landmarks(e: landmarks::LandmarkError) -> PyErr {
    use landmarks::LandmarkError as E;
    let kind = match &e {
        // A surface whose size fits no face is a face not found (the message says why).
        E::NotFound { .. } | E::Units(_) => Kind::NotFound,
        E::Mesh(m) => return mesh(m.clone()),
        E::Io(_) => Kind::File,
        E::File(f) => return io_kind_err(f, chain(&e)),
        E::MissingLandmark { .. } => Kind::Format,
        E::InvalidModel(_) | E::InvalidTraining(_) | E::InvalidOption(_) | E::UnknownChoice(_) => {
            Kind::Input
        }
    };
    err(kind, chain(&e))
}

/// The Python exception (of `bipolar.errors`) for a `rangescan::ScanError`.
pub fn scan(e: rangescan::ScanError) -> PyErr {
    use rangescan::ScanError as E;
    let kind = match &e {
        E::InvalidOption(_) | E::GridTooLarge(_) | E::BadLandmark { .. } => Kind::Input,
        E::NothingInView => Kind::Computation,
    };
    err(kind, chain(&e))
}

/// The Python exception (of `bipolar.errors`) for a `scanprep::ScanPrepError`.
pub fn scanprep(e: scanprep::ScanPrepError) -> PyErr {
    use scanprep::ScanPrepError as E;
    match e {
        E::Mesh(m) => mesh(m),
        E::Triangulation(i) => io(i),
        other => err(Kind::Input, chain(&other)),
    }
}

/// The Python exception (of `bipolar.errors`) for a `facecurves::FaceCurvesError`.
pub fn facecurves(e: facecurves::FaceCurvesError) -> PyErr {
    use facecurves::FaceCurvesError as E;
    let kind = match &e {
        E::Mesh(m) => return mesh(m.clone()),
        E::Geodesic(g) => geodesic_kind(g),
        E::ShapeDist(_) => Kind::Input,
        E::Io(_) => Kind::File,
        E::File { .. } => Kind::Format,
        E::NoCurves(_) | E::NoSharedCurves { .. } => Kind::NoPoints,
        _ => Kind::Input,
    };
    err(kind, chain(&e))
}

/// The Python exception (of `bipolar.errors`) for a `facematch::MatchError`.
pub fn matching(e: facematch::MatchError) -> PyErr {
    use facematch::MatchError as E;
    let kind = match &e {
        E::Clean(_) => Kind::Input,
        E::NoFace(_) | E::Landmarks(_) => Kind::NotFound,
        E::Geodesic(g) => geodesic_kind(g),
        E::Describe(_) => Kind::NoPoints,
        E::InvalidOption(_) | E::EmptyGallery(_) => Kind::Input,
        E::Template { .. } => Kind::Format,
        E::Settings { .. } => Kind::Settings,
        E::Io(_) => Kind::File,
    };
    err(kind, chain(&e))
}
