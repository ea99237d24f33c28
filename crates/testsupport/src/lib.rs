//! Test-side support shared by the tests and benchmarks of every crate (not published).
//!
//! * **Shared data, one skip rule.** [`shared_path`] (and the [`require_shared!`] macro around
//!   it) returns a path inside the shared data folder found by [`facemodel::shared_dir`], or
//!   prints one `skipped: ...` line and returns `None` when the folder (or the file inside it)
//!   is absent. A `BIPOLAR_SHARED` that names no folder is a user error, not a reason to skip:
//!   the test panics with the lookup's message.
//! * **Paths**: [`PAPER_SET`], [`MODEL`], [`paper_face`].
//! * **Meshes**: [`read_mesh`] (through `mesh-io`, the project's one reader) and the generators
//!   of [`meshcore::shapes`], re-exported as [`shapes`].
//! * **Analytic distance fields**: [`fields`].
//! * **The independent descriptor and distance** the crates are checked against: [`oracle`].

pub mod fields;
pub mod oracle;

pub use facemodel::{MODEL, PAPER_SET};
pub use meshcore::shapes;

use facemodel::FaceModelError;
use meshcore::TriMesh;
use std::path::{Path, PathBuf};

/// `rel` inside the shared data folder, or `None` after printing why the caller skips:
/// `skipped: ../shared not found ...` when there is no shared folder, `skipped: <path> not
/// found` when the folder lacks `rel`. Panics when `BIPOLAR_SHARED` names no folder.
pub fn shared_path(rel: impl AsRef<Path>) -> Option<PathBuf> {
    let root = match facemodel::shared_dir() {
        Ok(root) => root,
        Err(e @ FaceModelError::SharedNotFound { .. }) => {
            println!("skipped: ../shared not found ({e})");
            return None;
        }
        Err(e) => panic!("{e}"),
    };
    let p = root.join(rel);
    if p.exists() {
        Some(p)
    } else {
        println!("skipped: {} not found", p.display());
        None
    }
}

/// `<shared>/faces/ict-facekit/paper-set/<name>` (e.g. `id1_neutral.obj`), under the rule of
/// [`shared_path`].
pub fn paper_face(name: &str) -> Option<PathBuf> {
    shared_path(Path::new(PAPER_SET).join(name))
}

/// The path `rel` inside the shared data folder, or a `return` from the calling function (with
/// `Default::default()`, so `()` in a test) after the skip line of [`shared_path`].
///
/// ```
/// fn paper_set_is_a_folder() {
///     let dir = testsupport::require_shared!(testsupport::PAPER_SET);
///     assert!(dir.is_dir());
/// }
/// paper_set_is_a_folder();
/// ```
#[macro_export]
macro_rules! require_shared {
    ($rel:expr) => {
        match $crate::shared_path($rel) {
            Some(p) => p,
            None => return Default::default(),
        }
    };
}

/// Reads a mesh file with `mesh-io`; panics with the reader's message (test code).
pub fn read_mesh(path: impl AsRef<Path>) -> TriMesh {
    let path = path.as_ref();
    match mesh_io::read_mesh(path) {
        Ok(m) => m.mesh,
        Err(e) => panic!("reading {}: {e}", path.display()),
    }
}
