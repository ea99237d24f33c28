//! Reading a command's input mesh, with the one error context every command gives.

use anyhow::Context;
use std::path::Path;

/// Reads the mesh file `path` (any format `mesh_io::read_mesh` knows); the error names the
/// file.
pub fn mesh(path: &Path) -> anyhow::Result<mesh_io::LoadedMesh> {
    mesh_io::read_mesh(path).with_context(|| format!("cannot load {}", path.display()))
}
