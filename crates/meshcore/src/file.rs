//! Operating-system failures on files, shared by every crate that reads or writes one.

use std::path::{Path, PathBuf};
use thiserror::Error;

/// The operating system could not do `action` on `path`; the OS error is the source.
///
/// Every crate's error type carries this as its `Io` variant, so that a file error keeps the
/// path and the [`std::io::Error`] the same way everywhere.
#[derive(Debug, Error)]
#[error("cannot {action} {}", path.display())]
pub struct FileError {
    /// What was being done (`"read"`, `"write"`, `"list"`, ...).
    pub action: &'static str,
    /// The file or folder.
    pub path: PathBuf,
    /// The OS error.
    #[source]
    pub source: std::io::Error,
}

impl FileError {
    /// A failure to `action` `path`.
    pub fn new(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        Self {
            action,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Reads a whole text file.
pub fn read_text(path: &Path) -> Result<String, FileError> {
    std::fs::read_to_string(path).map_err(|e| FileError::new("read", path, e))
}

/// Writes `bytes` to `path`, replacing it.
pub fn write_bytes(path: &Path, bytes: impl AsRef<[u8]>) -> Result<(), FileError> {
    std::fs::write(path, bytes).map_err(|e| FileError::new("write", path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_path_and_source() {
        let dir = std::env::temp_dir().join(format!("meshcore-file-{}", std::process::id()));
        let missing = dir.join("missing.txt");
        let e = read_text(&missing).unwrap_err();
        assert_eq!(e.action, "read");
        assert_eq!(e.path, missing);
        assert_eq!(e.source.kind(), std::io::ErrorKind::NotFound);
        assert!(e.to_string().starts_with("cannot read "), "{e}");
        assert!(std::error::Error::source(&e).is_some());
        // Writing into a folder that does not exist fails the same way.
        let e = write_bytes(&missing, "x").unwrap_err();
        assert_eq!((e.action, e.path.as_path()), ("write", missing.as_path()));
    }
}
