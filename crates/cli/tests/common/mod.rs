//! What the end-to-end tests of the `bipolar` binary share: running it, and the small meshes
//! they give it.

// Each test file uses a part of this module.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
// Not every test file uses both.
#[allow(unused_imports)]
pub use testsupport::cli::{arg, Run};

/// Runs the `bipolar` binary of this crate with `args`.
pub fn bipolar(args: &[&str]) -> Run {
    testsupport::cli::run(env!("CARGO_BIN_EXE_bipolar"), args)
}

/// Runs `bipolar <command>` with `args` after the command.
pub fn bipolar_cmd(command: &str, args: &[&str]) -> Run {
    bipolar(&[&[command][..], args].concat())
}

/// Writes a unit icosphere (3 subdivisions, 642 vertices; bounding-box diagonal about 3.46) as
/// `dir/sphere.obj`.
pub fn sphere_obj(dir: &Path) -> PathBuf {
    testsupport::cli::write_mesh(dir, "sphere.obj", &testsupport::shapes::icosphere(3))
}

/// Writes a flat grid of `n x n` square cells of side `h` in the plane z = 0 (vertex `(i, j)`
/// at `(i h, j h, 0)` has id `j * (n + 1) + i`, every square split along the same diagonal) as
/// `dir/<name>`.
pub fn grid_obj(dir: &Path, name: &str, n: usize, h: f64) -> PathBuf {
    let grid = testsupport::shapes::grid(n, n, testsupport::shapes::Diagonals::Uniform, |i, j| {
        meshcore::DVec3::new(i as f64 * h, j as f64 * h, 0.0)
    })
    .expect("a unit grid is a valid mesh");
    testsupport::cli::write_mesh(dir, name, &grid)
}

/// The paper-set face `name` (under the skip rule of [`testsupport::paper_face`]) and a fresh
/// temporary folder for a test's outputs.
pub fn paper_face_and_tempdir(name: &str) -> Option<(PathBuf, tempfile::TempDir)> {
    let face = testsupport::paper_face(name)?;
    Some((face, tempfile::tempdir().unwrap()))
}
