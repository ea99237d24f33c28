//! Running a command-line program from a test: one call collects the exit status and both
//! output streams as text, and the two checks every end-to-end test makes (it succeeded, it
//! failed) print the stream that explains a surprise.

use meshcore::TriMesh;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

/// What one run of a program gave: whether it exited with success, and its output as text.
#[derive(Debug, Clone)]
pub struct Run {
    /// The program exited with status 0.
    pub ok: bool,
    /// The exit status (`None` when a signal ended the program).
    pub code: Option<i32>,
    /// Standard output (lossy UTF-8).
    pub stdout: String,
    /// Standard error (lossy UTF-8).
    pub stderr: String,
}

impl Run {
    /// The run itself; panics with its stderr (and stdout) unless it succeeded.
    #[track_caller]
    pub fn success(self) -> Self {
        assert!(
            self.ok,
            "expected success\nstdout:\n{}\nstderr:\n{}",
            self.stdout, self.stderr
        );
        self
    }

    /// Its stderr; panics with its stdout unless the run failed.
    #[track_caller]
    pub fn failure(self) -> String {
        assert!(
            !self.ok,
            "expected failure\nstdout:\n{}\nstderr:\n{}",
            self.stdout, self.stderr
        );
        self.stderr
    }

    /// Its stderr; panics unless the program failed as an error does (exit status 1: a panic
    /// exits with 101, a signal with none), without a panic message, and its stderr contains
    /// `word`.
    #[track_caller]
    pub fn error_naming(self, word: &str) -> String {
        assert_eq!(
            self.code,
            Some(1),
            "expected exit status 1\nstdout:\n{}\nstderr:\n{}",
            self.stdout,
            self.stderr
        );
        assert!(!self.stderr.contains("panicked"), "{}", self.stderr);
        assert!(
            self.stderr.contains(word),
            "expected {word:?} in stderr:\n{}",
            self.stderr
        );
        self.stderr
    }
}

/// Runs `exe` (in a test of a binary crate: `env!("CARGO_BIN_EXE_<name>")`) with `args`; panics
/// when the program cannot be started.
pub fn run<S: AsRef<OsStr>>(exe: impl AsRef<OsStr>, args: &[S]) -> Run {
    let exe = exe.as_ref();
    let out = Command::new(exe)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("running {}: {e}", exe.to_string_lossy()));
    Run {
        ok: out.status.success(),
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// `path` as text for an argument list (test paths are UTF-8; panics otherwise).
pub fn arg(path: &Path) -> &str {
    path.to_str()
        .unwrap_or_else(|| panic!("{} is not UTF-8", path.display()))
}

/// Writes `mesh` to `dir/name` with `mesh-io` (the format from the extension, e.g. `.obj`;
/// positions in their shortest exact decimal form) and returns the path.
pub fn write_mesh(dir: &Path, name: &str, mesh: &TriMesh) -> PathBuf {
    let path = dir.join(name);
    mesh_io::write_mesh(&path, &mesh_io::LoadedMesh::new(mesh.clone()))
        .unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
    path
}
