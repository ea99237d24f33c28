//! Default locations of the tasks' inputs and outputs (the defaults of `--faces`, `--model`,
//! `--out`).

use std::path::{Path, PathBuf};

/// The paper set in the shared data folder (`facemodel::default_paper_set`). Without a shared
/// folder the task cannot run: prints the lookup's error and exits with status 1.
pub fn default_paper_set() -> PathBuf {
    or_exit(facemodel::default_paper_set())
}

/// The ICT model folder in the shared data folder (`facemodel::default_model_dir`); exits like
/// [`default_paper_set`].
pub fn default_model_dir() -> PathBuf {
    or_exit(facemodel::default_model_dir())
}

fn or_exit(r: Result<PathBuf, facemodel::FaceModelError>) -> PathBuf {
    r.unwrap_or_else(|e| {
        eprintln!("Error: {e}");
        std::process::exit(1)
    })
}

/// Output folder `name` under the cargo target directory (`$CARGO_TARGET_DIR` if set,
/// else `<workspace>/target`).
pub fn default_out_dir(name: &str) -> PathBuf {
    let target = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."))
            .join("target"),
    };
    target.join(name)
}
