//! Test-side support shared by the tests and benchmarks of every crate (not published).
//!
//! * **Shared data, one skip rule.** [`shared_path`] (and the [`require_shared!`] macro around
//!   it) returns a path inside the shared data folder found by [`facemodel::shared_dir`], or
//!   prints one `skipped: ...` line and returns `None` when the folder (or the file inside it)
//!   is absent. A `BIPOLAR_SHARED` that names no folder is a user error, not a reason to skip:
//!   the test panics with the lookup's message.
//! * **Paths**: [`PAPER_SET`], [`MODEL`], [`paper_face`].
//! * **Meshes**: [`read_mesh`] (through `mesh-io`, the project's one reader) and the generators
//!   of [`meshcore::shapes`], re-exported as [`shapes`], plus [`jittered_unit_plane`] (the
//!   plane of the straightest-geodesic, single-pole and face-frame tests).
//! * **Temporary folders**: [`fresh_temp_dir`].
//! * **Analytic distance fields**: [`fields`].
//! * **The independent descriptor and distance** the crates are checked against: [`oracle`].

pub mod fields;
pub mod oracle;

pub use facemodel::{MODEL, PAPER_SET};
pub use meshcore::shapes;

use facemodel::FaceModelError;
use meshcore::TriMesh;
use std::path::{Path, PathBuf};

/// Planar grid on [0, 1]^2 (z = 0) of `n` cells a side, uniform diagonals, interior vertices
/// jittered by up to `jitter` cells per axis (ChaCha8 seeded by `seed`; boundary kept straight).
pub fn jittered_unit_plane(n: usize, jitter: f64, seed: u64) -> TriMesh {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let h = 1.0 / n as f64;
    shapes::grid(n, n, shapes::Diagonals::Uniform, |i, j| {
        let inner = i > 0 && j > 0 && i < n && j < n;
        let (dx, dy) = if inner && jitter > 0.0 {
            (
                rng.random_range(-jitter..jitter) * h,
                rng.random_range(-jitter..jitter) * h,
            )
        } else {
            (0.0, 0.0)
        };
        meshcore::DVec3::new(i as f64 * h + dx, j as f64 * h + dy, 0.0)
    })
    .expect("a unit grid is a valid mesh")
}

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

/// An empty folder `<temp>/<prefix>-<process id>-<name>` for a test's files (emptied first
/// when a previous run left it).
pub fn fresh_temp_dir(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    if let Err(e) = std::fs::create_dir_all(&d) {
        panic!("creating {}: {e}", d.display());
    }
    d
}

/// Reads a mesh file with `mesh-io`; panics with the reader's message (test code).
pub fn read_mesh(path: impl AsRef<Path>) -> TriMesh {
    let path = path.as_ref();
    match mesh_io::read_mesh(path) {
        Ok(m) => m.mesh,
        Err(e) => panic!("reading {}: {e}", path.display()),
    }
}
