//! Stanford PLY reader (ASCII, binary little and big endian; any elements, scalar and list
//! properties of any type) and writer.

mod ascii;
mod binary;
mod header;
mod records;
mod write;

pub(crate) use write::write_ply;

use crate::{finish, IoError, LoadedMesh, ScalarField};
use ascii::read_ascii;
use binary::read_binary;
use header::parse_header;
use records::Sink;

meshcore::choice! {
    /// PLY storage encoding.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum PlyEncoding: "PLY encoding", crate::IoError {
        /// Text.
        Ascii = "ascii",
        /// Binary, little endian.
        BinaryLittleEndian = "binary_little_endian" | "binary_le" | "binary",
        /// Binary, big endian.
        BinaryBigEndian = "binary_big_endian" | "binary_be",
    }
}

/// What [`crate::write_ply`] writes besides positions (always `double x y z`) and faces
/// (`list uchar int vertex_indices`).
#[derive(Debug, Clone, Copy)]
pub struct PlyWriteOptions<'a> {
    /// Encoding of the body.
    pub encoding: PlyEncoding,
    /// Per-vertex RGBA colours (`uchar red green blue alpha`), one per vertex.
    pub colors: Option<&'a [[u8; 4]]>,
    /// Named per-vertex scalars (`float` or `double` by [`ScalarType`](crate::ScalarType)), one value per vertex.
    pub scalars: &'a [ScalarField],
}

impl Default for PlyWriteOptions<'_> {
    fn default() -> Self {
        Self {
            encoding: PlyEncoding::BinaryLittleEndian,
            colors: None,
            scalars: &[],
        }
    }
}

/// Parses a PLY file.
pub(crate) fn read_ply(bytes: &[u8], file: &str) -> Result<LoadedMesh, IoError> {
    let h = parse_header(bytes, file)?;
    if !h.elements.iter().any(|e| e.name == "vertex") {
        return Err(IoError::whole(file, "no 'vertex' element"));
    }
    if !h
        .elements
        .iter()
        .any(|e| e.name == "face" || e.name == "tristrips")
    {
        return Err(IoError::whole(
            file,
            "no 'face' or 'tristrips' element (point clouds are not meshes)",
        ));
    }
    let mut sink = Sink {
        pos: Vec::new(),
        colors: Vec::new(),
        scalars: Vec::new(),
        tris: Vec::new(),
        tri_at: Vec::new(),
        n_polygons: 0,
        n_strips: 0,
        n_strip_degenerate: 0,
    };
    let header_lines = bytes[..h.body_start]
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    match h.encoding {
        PlyEncoding::Ascii => read_ascii(bytes, &h, file, &mut sink, header_lines)?,
        PlyEncoding::BinaryLittleEndian => read_binary(bytes, &h, file, &mut sink, false)?,
        PlyEncoding::BinaryBigEndian => read_binary(bytes, &h, file, &mut sink, true)?,
    }
    let n = sink.pos.len();
    if let Some(t) = sink
        .tris
        .iter()
        .position(|t| t.iter().any(|&v| v as usize >= n))
    {
        let bad = sink.tris[t]
            .iter()
            .find(|&&v| v as usize >= n)
            .copied()
            .unwrap_or(0);
        let at = if h.encoding == PlyEncoding::Ascii {
            crate::Location::Line(sink.tri_at[t])
        } else {
            crate::Location::Byte(sink.tri_at[t])
        };
        return Err(IoError::malformed(
            file,
            at,
            format!("face refers to vertex {bad} but the file has {n} vertices"),
        ));
    }
    let mut out = finish(file, sink.pos, sink.tris)?;
    if !sink.colors.is_empty() {
        out.colors = Some(sink.colors);
    }
    out.scalars = sink.scalars.into_iter().map(|(_, s)| s).collect();
    if sink.n_polygons > 0 {
        out.warnings.push(format!(
            "{} polygon(s) with more than 3 corners fan-triangulated",
            sink.n_polygons
        ));
    }
    if sink.n_strips > 0 {
        out.warnings.push(format!(
            "{} triangle strip(s) decoded; {} degenerate strip triangle(s) (repeated vertex) skipped",
            sink.n_strips, sink.n_strip_degenerate
        ));
    }
    Ok(out)
}
