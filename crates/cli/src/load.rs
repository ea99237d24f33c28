//! Reading a command's input mesh, with the one error context every command gives.

use anyhow::Context;
use std::path::Path;

/// Reads the mesh file `path` (any format `mesh_io::read_mesh` knows); the error names the
/// file.
pub fn mesh(path: &Path) -> anyhow::Result<mesh_io::LoadedMesh> {
    mesh_io::read_mesh(path).with_context(|| format!("cannot load {}", path.display()))
}

/// The direction toward the scanner for a range grid (`.bnt`: the scanner looks down its z
/// axis, so `+z`); `None` for a mesh file, whose viewpoint is unknown. Landmark detection
/// reads the rims of unseen surface with it (`landmarks::DetectOptions::toward_viewer`).
pub fn toward_scanner(path: &Path) -> Option<meshcore::DVec3> {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("bnt"))
        .then_some(meshcore::DVec3::Z)
}
