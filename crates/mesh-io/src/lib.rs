//! Readers and writers for triangle meshes and landmark files.
//!
//! * Readers: OBJ, PLY (ASCII, binary little and big endian), STL (ASCII and binary), OFF,
//!   glTF/GLB, Bosphorus `.bnt` range grids, landmark files (`.lm3`/`.lm2`, landmark JSON,
//!   the ICT `landmarks.json` layout; the only landmark-file code of the workspace) and `.npy`
//!   arrays.
//!   [`read_mesh`] picks the reader from the file extension; [`read_mesh_from_bytes`] takes
//!   the [`Format`] explicitly.
//! * Writers: OBJ, PLY (ASCII or binary, optional per-vertex colours and named scalar
//!   properties), STL binary, OFF, GLB (a mesh plus point sets and polylines with colours, see
//!   [`gltf_io::GltfScene`]), `.bnt` range grids ([`write_bnt`]) and `.lm3`.
//!
//! Every reader returns [`IoError`] naming the file and the line (text) or byte offset
//! (binary) of the problem; nothing panics on bad input, and no allocation is sized from a
//! header count before checking it against the bytes actually present.
//!
//! Readers never repair: degenerate faces and duplicate vertices are reported in
//! [`LoadedMesh::warnings`] and fixed only on request ([`LoadedMesh::weld`],
//! [`LoadedMesh::drop_degenerate`]).
//!
//! OBJ is read by a line-numbered parser of this crate rather than `tobj`: `tobj` stores
//! positions as `f32` and re-indexes vertices per object/group (a vertex shared by two groups
//! becomes two vertices), which would change the geometry and the topology of the file. `tobj`
//! is used in the tests as an independent oracle.

mod bnt;
mod error;
pub mod gltf_io;
mod landmarks;
mod npy;
mod obj;
mod off;
mod ply;
mod stl;
mod text;

pub use bnt::{
    bnt_grid_to_mesh, read_bnt, read_bnt_grid, read_bnt_grid_from_bytes, write_bnt,
    write_bnt_to_bytes, BntGrid, BntOptions,
};
pub use error::{IoError, Location};
pub use gltf_io::{write_glb, GltfScene};
pub use gltf_io::{write_glb_to_bytes, LineMode, PointSet, Polyline, SceneMesh};
pub use landmarks::{
    landmarks_json, parse_ict_landmarks, parse_landmarks_json, parse_lm2, parse_lm3,
    parse_lm3_notes, read_ict_landmarks, read_landmark_file, read_lm2, read_lm3,
    write_landmarks_json, write_lm3, write_lm3_with_notes, Landmarks2d, Landmarks3d,
};
pub use npy::{parse_npy_f32, read_npy_f32};
pub use ply::{PlyEncoding, PlyWriteOptions};

use meshcore::{DVec3, TriMesh};
use std::path::Path;

meshcore::choice! {
    /// The mesh file formats known to [`read_mesh`] and [`write_mesh`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum Format: "mesh format", IoError {
        /// Wavefront OBJ (text).
        Obj = "obj",
        /// Stanford PLY (ASCII or binary).
        Ply = "ply",
        /// STL (ASCII or binary).
        Stl = "stl",
        /// Object File Format (text).
        Off = "off",
        /// glTF 2.0 JSON (`.gltf`, buffers embedded as data URIs or next to the file).
        Gltf = "gltf",
        /// glTF 2.0 binary (`.glb`).
        Glb = "glb",
        /// Bosphorus range grid (`.bnt`, read only).
        Bnt = "bnt",
    }
}

impl Format {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, IoError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        <Format as meshcore::Choice>::from_name(&ext).map_err(|_| IoError::UnknownFormat {
            file: path.display().to_string(),
            ext,
        })
    }
}

meshcore::choice! {
    /// How a per-vertex scalar was (or is to be) stored.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum ScalarType: "scalar type", IoError {
        /// 32-bit float.
        F32 = "f32" | "float32" | "float",
        /// 64-bit float.
        F64 = "f64" | "float64" | "double",
    }
}

/// A named per-vertex scalar property (e.g. a geodesic distance field).
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarField {
    /// Property name (a PLY identifier: no whitespace).
    pub name: String,
    /// One value per vertex.
    pub values: Vec<f64>,
    /// Storage type in the file.
    pub ty: ScalarType,
}

/// A mesh as read from a file, with the optional per-vertex extras the file carried.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMesh {
    /// The triangle mesh (validated: non-empty, finite, indices in range).
    pub mesh: TriMesh,
    /// For meshes made from a range grid (BNT): per vertex, the index `row * ncols + col` of its
    /// sample in the grid (rows in image order, top row 0).
    pub grid_index: Option<Vec<u32>>,
    /// Per-vertex RGBA colours, if the file had them.
    pub colors: Option<Vec<[u8; 4]>>,
    /// Other per-vertex scalar properties the file had (PLY).
    pub scalars: Vec<ScalarField>,
    /// Things worth knowing that were not repaired (degenerate faces, duplicate vertices,
    /// skipped primitives, ...).
    pub warnings: Vec<String>,
}

/// What [`LoadedMesh::weld`] or [`LoadedMesh::drop_degenerate`] changed (the report of
/// [`meshcore::repair`], which does the work).
pub use meshcore::repair::RepairReport;

impl LoadedMesh {
    /// A loaded mesh without extras; computes the warnings.
    pub fn new(mesh: TriMesh) -> Self {
        let warnings = diagnose(&mesh);
        Self {
            mesh,
            grid_index: None,
            colors: None,
            scalars: Vec::new(),
            warnings,
        }
    }

    /// Merges vertices closer than `tol` (absolute length; `0` merges exact duplicates only),
    /// keeping the first occurrence and its extras, then removes faces that collapsed and
    /// unused vertices ([`meshcore::repair::weld_vertices`]). When no face would remain, the
    /// mesh is left unchanged, a warning says so and the report is all zeros.
    pub fn weld(&mut self, tol: f64) -> RepairReport {
        let r = meshcore::repair::weld_vertices(&self.mesh, tol);
        self.apply(r)
    }

    /// Removes faces with a repeated vertex or an area `<= rel_tol * bbox_diagonal^2`, then
    /// unused vertices, extras following their vertices
    /// ([`meshcore::repair::remove_degenerate_faces`]). When no face would remain, the mesh is
    /// left unchanged, a warning says so and the report is all zeros.
    pub fn drop_degenerate(&mut self, rel_tol: f64) -> RepairReport {
        let r = meshcore::repair::remove_degenerate_faces(&self.mesh, rel_tol);
        self.apply(r)
    }

    fn apply(
        &mut self,
        r: Result<meshcore::repair::Repaired, meshcore::MeshError>,
    ) -> RepairReport {
        let Ok(r) = r else {
            // Refuse to produce an invalid (empty) mesh: leave it unchanged.
            self.warnings
                .push("repair would remove every face; mesh left unchanged".into());
            return RepairReport::default();
        };
        let order = &r.source_vertices;
        if let Some(g) = &mut self.grid_index {
            *g = order.iter().map(|&v| g[v as usize]).collect();
        }
        if let Some(c) = &mut self.colors {
            *c = order.iter().map(|&v| c[v as usize]).collect();
        }
        for s in &mut self.scalars {
            s.values = order.iter().map(|&v| s.values[v as usize]).collect();
        }
        self.mesh = r.mesh;
        self.warnings = diagnose(&self.mesh);
        r.report
    }

    /// Checks that the extras have one entry per vertex.
    pub(crate) fn check_extras(&self, file: &str) -> Result<(), IoError> {
        check_extras(
            file,
            self.mesh.n_vertices(),
            self.colors.as_deref(),
            &self.scalars,
        )
    }
}

/// Checks that colours and scalar fields have one entry per each of `n` vertices.
pub(crate) fn check_extras(
    file: &str,
    n: usize,
    colors: Option<&[[u8; 4]]>,
    scalars: &[ScalarField],
) -> Result<(), IoError> {
    if let Some(c) = colors {
        if c.len() != n {
            return Err(IoError::invalid(
                file,
                format!("{} colours for {n} vertices", c.len()),
            ));
        }
    }
    for s in scalars {
        if s.values.len() != n {
            return Err(IoError::invalid(
                file,
                format!(
                    "scalar {:?} has {} values for {n} vertices",
                    s.name,
                    s.values.len()
                ),
            ));
        }
    }
    Ok(())
}

/// Reads the file `path` and hands its bytes and its name (for error messages) to `parse`.
pub(crate) fn read_parsed<T>(
    path: &Path,
    parse: impl FnOnce(&[u8], &str) -> Result<T, IoError>,
) -> Result<T, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io("read", path, e))?;
    parse(&bytes, &path.display().to_string())
}

pub use meshcore::repair::{count_degenerate_faces, count_duplicate_vertices};

/// The warnings every reader attaches: exact duplicate vertices and degenerate faces.
pub fn diagnose(mesh: &TriMesh) -> Vec<String> {
    let mut w = Vec::new();
    let d = count_degenerate_faces(mesh);
    if d > 0 {
        w.push(format!(
            "{d} degenerate face(s) (repeated vertex or zero area); not removed"
        ));
    }
    let dup = count_duplicate_vertices(mesh);
    if dup > 0 {
        w.push(format!(
            "{dup} vertex/vertices exactly duplicate an earlier vertex; not welded"
        ));
    }
    w
}

/// Reads a mesh, choosing the reader from the file extension.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<LoadedMesh, IoError> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    read_parsed(path, |bytes, name| {
        read_bytes_named(bytes, format, name, path.parent())
    })
}

/// Reads a mesh held in memory. For [`Format::Gltf`], only embedded (data URI) buffers can be
/// resolved.
pub fn read_mesh_from_bytes(bytes: &[u8], format: Format) -> Result<LoadedMesh, IoError> {
    read_bytes_named(bytes, format, "<memory>", None)
}

fn read_bytes_named(
    bytes: &[u8],
    format: Format,
    name: &str,
    base: Option<&Path>,
) -> Result<LoadedMesh, IoError> {
    match format {
        Format::Obj => obj::read_obj(bytes, name),
        Format::Ply => ply::read_ply(bytes, name),
        Format::Stl => stl::read_stl(bytes, name),
        Format::Off => off::read_off(bytes, name),
        Format::Gltf | Format::Glb => gltf_io::read_gltf(bytes, name, base),
        Format::Bnt => bnt::read_bnt_bytes(bytes, name, &BntOptions::default()),
    }
}

/// Serialises a mesh (and the extras the format can carry: colours and scalars in PLY, colours
/// in GLB) into the bytes of a file of the given format. PLY is written binary little endian.
pub fn write_mesh_to_bytes(mesh: &LoadedMesh, format: Format) -> Result<Vec<u8>, IoError> {
    write_named(mesh, format, "<memory>")
}

fn write_named(mesh: &LoadedMesh, format: Format, name: &str) -> Result<Vec<u8>, IoError> {
    mesh.check_extras(name)?;
    match format {
        Format::Obj => Ok(obj::write_obj(&mesh.mesh)),
        Format::Ply => ply::write_ply(
            &mesh.mesh,
            &PlyWriteOptions {
                encoding: PlyEncoding::BinaryLittleEndian,
                colors: mesh.colors.as_deref(),
                scalars: &mesh.scalars,
            },
            name,
        ),
        Format::Stl => Ok(stl::write_stl(&mesh.mesh)),
        Format::Off => Ok(off::write_off(&mesh.mesh)),
        Format::Glb => {
            let mut scene = GltfScene::default();
            scene.add_mesh("mesh", &mesh.mesh, mesh.colors.clone());
            gltf_io::glb_bytes(&scene, name)
        }
        Format::Gltf => Err(IoError::invalid(
            name,
            "writing .gltf is not supported; write .glb (binary glTF)",
        )),
        Format::Bnt => Err(IoError::invalid(name, "writing .bnt is not supported")),
    }
}

/// Writes a mesh, choosing the format from the extension (see [`write_mesh_to_bytes`]).
pub fn write_mesh(path: impl AsRef<Path>, mesh: &LoadedMesh) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let format = Format::from_path(path)?;
    let bytes = write_named(mesh, format, &name)?;
    std::fs::write(path, bytes).map_err(|e| IoError::io("write", path, e))
}

/// Writes a PLY file with explicit options (encoding, colours, scalar properties).
pub fn write_ply(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    options: &PlyWriteOptions<'_>,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = ply::write_ply(mesh, options, &name)?;
    std::fs::write(path, bytes).map_err(|e| IoError::io("write", path, e))
}

/// Serialises a PLY file with explicit options into memory.
pub fn write_ply_to_bytes(
    mesh: &TriMesh,
    options: &PlyWriteOptions<'_>,
) -> Result<Vec<u8>, IoError> {
    ply::write_ply(mesh, options, "<memory>")
}

/// Builds a [`LoadedMesh`] from parsed positions and triangles, converting a mesh validation
/// failure into an error naming the file.
pub(crate) fn finish(
    file: &str,
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
) -> Result<LoadedMesh, IoError> {
    let mesh = TriMesh::new(positions, triangles).map_err(|e| IoError::mesh(file, e))?;
    Ok(LoadedMesh::new(mesh))
}
