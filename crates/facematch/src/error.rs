//! The crate's error type.

/// What can go wrong in face matching. Every message names the input or option at fault.
#[derive(Debug, thiserror::Error)]
pub enum MatchError {
    /// The scan could not be cleaned (empty, too sparse, bad options).
    #[error("cleaning the scan: {0}")]
    Clean(#[from] scanprep::ScanPrepError),
    /// No face was found on the scan: the detector's reason.
    #[error("no face found: {0}")]
    NoFace(String),
    /// The landmarks found do not give the poles a description needs.
    #[error("landmarks: {0}")]
    Landmarks(String),
    /// The geodesic solver refused the mesh.
    #[error("geodesic solver: {0}")]
    Geodesic(#[from] geodesic::GeodesicError),
    /// No pole pair could be described.
    #[error("description: {0}")]
    Describe(String),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// A template file is not one this build reads.
    #[error("template {file}: {what}")]
    Template {
        /// The file (or `<bytes>`).
        file: String,
        /// What is wrong with it.
        what: String,
    },
    /// A template was made with other settings than the ones it is compared with.
    #[error("template {file} was made with other settings than these\n  template: {template}\n  expected: {expected}")]
    Settings {
        /// The file (or `<bytes>`).
        file: String,
        /// The template's settings.
        template: String,
        /// The settings asked for.
        expected: String,
    },
    /// A gallery without templates.
    #[error("gallery {0}: no templates (a gallery is a folder of .bpt files or one .bpg file)")]
    EmptyGallery(String),
    /// Reading, writing or listing a file or folder.
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
}
