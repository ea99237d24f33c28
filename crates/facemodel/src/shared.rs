//! The one lookup of the project's shared data folder (faces, paper, peer scripts).
//!
//! Rule, in this order:
//!
//! 1. `$BIPOLAR_SHARED`, when set and not empty. It must name an existing folder; a value that
//!    does not is an error ([`FaceModelError::SharedEnvNotAFolder`]), never a silent fallback.
//! 2. Otherwise `shared/` beside the workspace root (`<root>/../shared`), where the workspace
//!    root is the nearest folder holding a `Cargo.toml` with a `[workspace]` table, found by
//!    walking up from the current directory, then from `$CARGO_MANIFEST_DIR` as set at run time
//!    by `cargo run`, `cargo test` and `cargo bench`. The first such `shared/` that is a folder
//!    wins.
//! 3. Otherwise [`FaceModelError::SharedNotFound`], listing the places looked at.
//!
//! Nothing is baked in at compile time, so a binary moved out of its checkout does not read the
//! checkout's data behind the user's back.

use crate::FaceModelError;
use std::path::{Path, PathBuf};

/// Environment variable naming the shared data folder.
pub const SHARED_ENV: &str = "BIPOLAR_SHARED";

/// The 12-face paper set (`*.obj` and `landmarks.json`), relative to the shared folder.
pub const PAPER_SET: &str = "faces/ict-facekit/paper-set";

/// The ICT FaceKit model folder (`neutral.obj`, `identities.npy`, `expressions.npy`,
/// `model.json`), relative to the shared folder.
pub const MODEL: &str = "faces/ict-facekit/model";

/// The shared data folder, found by the rule of the [module documentation](self).
pub fn shared_dir() -> Result<PathBuf, FaceModelError> {
    let cwd = std::env::current_dir().ok();
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR").map(PathBuf::from);
    shared_dir_from(
        std::env::var_os(SHARED_ENV).map(PathBuf::from),
        cwd.iter().chain(manifest.iter()).map(PathBuf::as_path),
    )
}

/// [`shared_dir`] with the variable's value and the starting folders given (for tests).
fn shared_dir_from<'a>(
    env: Option<PathBuf>,
    starts: impl IntoIterator<Item = &'a Path>,
) -> Result<PathBuf, FaceModelError> {
    if let Some(p) = env.filter(|p| !p.as_os_str().is_empty()) {
        return if p.is_dir() {
            Ok(p)
        } else {
            Err(FaceModelError::SharedEnvNotAFolder { path: p })
        };
    }
    let mut searched = Vec::new();
    for start in starts {
        let Some(root) = workspace_root_from(start) else {
            continue;
        };
        let candidate = root.parent().unwrap_or(&root).join("shared");
        if candidate.is_dir() {
            return Ok(candidate);
        }
        if !searched.contains(&candidate) {
            searched.push(candidate);
        }
    }
    Err(FaceModelError::SharedNotFound { searched })
}

/// The nearest ancestor of `start` (itself included) holding a `Cargo.toml` with a
/// `[workspace]` table.
pub fn workspace_root_from(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .find(|dir| {
            std::fs::read_to_string(dir.join("Cargo.toml"))
                .is_ok_and(|text| text.lines().any(|l| l.trim() == "[workspace]"))
        })
        .map(Path::to_path_buf)
}

/// The paper-set folder: [`shared_dir`] joined with [`PAPER_SET`].
pub fn default_paper_set() -> Result<PathBuf, FaceModelError> {
    Ok(shared_dir()?.join(PAPER_SET))
}

/// The ICT model folder: [`shared_dir`] joined with [`MODEL`].
pub fn default_model_dir() -> Result<PathBuf, FaceModelError> {
    Ok(shared_dir()?.join(MODEL))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("facemodel-shared-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn variable_wins_and_must_name_a_folder() {
        let d = tmp("env");
        assert_eq!(shared_dir_from(Some(d.clone()), []).unwrap(), d);
        let missing = d.join("nope");
        match shared_dir_from(Some(missing.clone()), []) {
            Err(FaceModelError::SharedEnvNotAFolder { path }) => assert_eq!(path, missing),
            other => panic!("expected SharedEnvNotAFolder, got {other:?}"),
        }
        // An empty value counts as unset.
        assert!(matches!(
            shared_dir_from(Some(PathBuf::new()), []),
            Err(FaceModelError::SharedNotFound { .. })
        ));
    }

    #[test]
    fn walks_up_to_the_workspace_root_and_looks_beside_it() {
        let d = tmp("walk");
        let root = d.join("repo");
        let deep = root.join("crates").join("x").join("src");
        std::fs::create_dir_all(&deep).unwrap();
        // A member manifest without [workspace] does not stop the walk.
        std::fs::write(
            root.join("crates/x/Cargo.toml"),
            "[package]\nname = \"x\"\n",
        )
        .unwrap();
        std::fs::write(root.join("Cargo.toml"), "[workspace]\nmembers = []\n").unwrap();
        assert_eq!(workspace_root_from(&deep).unwrap(), root);
        match shared_dir_from(None, [deep.as_path()]) {
            Err(FaceModelError::SharedNotFound { searched }) => {
                assert_eq!(searched, [d.join("shared")]);
            }
            other => panic!("expected SharedNotFound, got {other:?}"),
        }
        std::fs::create_dir(d.join("shared")).unwrap();
        assert_eq!(
            shared_dir_from(None, [deep.as_path()]).unwrap(),
            d.join("shared")
        );
        // A start outside any workspace is skipped; the next start is tried.
        let outside = tmp("outside");
        assert_eq!(
            shared_dir_from(None, [outside.as_path(), deep.as_path()]).unwrap(),
            d.join("shared")
        );
        assert!(matches!(
            shared_dir_from(None, [outside.as_path()]),
            Err(FaceModelError::SharedNotFound { searched }) if searched.is_empty()
        ));
    }
}
