//! STL reader (ASCII and binary; vertices welded exactly) and binary writer.

use crate::text::{lines, parse_xyz};
use crate::{finish, IoError, LoadedMesh};
use meshcore::{DVec3, TriMesh};
use std::collections::HashMap;

/// Welds corners with bit-identical coordinates (+0 and -0 identified) into shared vertices.
struct Welder {
    map: HashMap<[u64; 3], u32>,
    pos: Vec<DVec3>,
}

impl Welder {
    fn new() -> Self {
        Self {
            map: HashMap::new(),
            pos: Vec::new(),
        }
    }
    fn add(&mut self, p: DVec3) -> u32 {
        let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
        let n = self.pos.len() as u32;
        let pos = &mut self.pos;
        *self.map.entry(key).or_insert_with(|| {
            pos.push(p);
            n
        })
    }
}

/// Parses an STL file. A file is binary when its size is exactly `84 + 50 * n` for the
/// triangle count `n` of its header; otherwise it must be ASCII (`solid ...`).
pub(crate) fn read_stl(bytes: &[u8], file: &str) -> Result<LoadedMesh, IoError> {
    let binary_size = if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        Some(84 + 50 * n)
    } else {
        None
    };
    let starts_solid = bytes.trim_ascii_start().starts_with(b"solid");
    if binary_size == Some(bytes.len() as u64) && !(starts_solid && looks_ascii(bytes)) {
        return read_binary(bytes, file);
    }
    if starts_solid {
        return read_ascii(bytes, file);
    }
    match binary_size {
        None => Err(IoError::byte(file, bytes.len(), format!("binary STL needs an 84-byte header; the file has {} bytes", bytes.len()))),
        Some(expected) => Err(IoError::byte(
            file,
            80,
            format!(
                "binary STL header claims {} triangles ({expected} bytes) but the file has {} bytes",
                (expected - 84) / 50,
                bytes.len()
            ),
        )),
    }
}

fn looks_ascii(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(512)];
    head.iter().all(|b| b.is_ascii()) && head.windows(5).any(|w| w == b"facet")
}

fn read_binary(bytes: &[u8], file: &str) -> Result<LoadedMesh, IoError> {
    let n = (bytes.len() - 84) / 50;
    let mut w = Welder::new();
    w.map.reserve(n / 2);
    let mut tris = Vec::with_capacity(n);
    for t in 0..n {
        let rec = 84 + 50 * t;
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let o = rec + 12 + 12 * k;
            let f = |i: usize| {
                f32::from_le_bytes([
                    bytes[o + 4 * i],
                    bytes[o + 4 * i + 1],
                    bytes[o + 4 * i + 2],
                    bytes[o + 4 * i + 3],
                ]) as f64
            };
            let p = DVec3::new(f(0), f(1), f(2));
            if !p.is_finite() {
                return Err(IoError::byte(
                    file,
                    o,
                    format!(
                        "triangle {t} has a non-finite corner ({}, {}, {})",
                        p.x, p.y, p.z
                    ),
                ));
            }
            *slot = w.add(p);
        }
        tris.push(tri);
    }
    if n == 0 {
        return Err(IoError::byte(file, 80, "binary STL with 0 triangles"));
    }
    finish(file, w.pos, tris)
}

fn read_ascii(bytes: &[u8], file: &str) -> Result<LoadedMesh, IoError> {
    let mut w = Welder::new();
    let mut tris = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut in_loop = None;
    let mut last = 0;
    for (ln, line) in lines(bytes) {
        last = ln;
        let mut t = line.split_ascii_whitespace();
        match t.next() {
            Some("vertex") => {
                if in_loop.is_none() {
                    return Err(IoError::line(file, ln, "'vertex' outside 'outer loop'"));
                }
                corners.push(w.add(parse_xyz(&mut t, file, ln)?));
            }
            Some("outer") => {
                corners.clear();
                in_loop = Some(ln);
            }
            Some("endloop") => {
                if corners.len() != 3 {
                    return Err(IoError::line(
                        file,
                        ln,
                        format!("facet has {} vertices; STL facets have 3", corners.len()),
                    ));
                }
                tris.push([corners[0], corners[1], corners[2]]);
                in_loop = None;
            }
            Some("solid") | Some("facet") | Some("endfacet") | Some("endsolid") | None => {}
            Some(other) => {
                return Err(IoError::line(
                    file,
                    ln,
                    format!("unexpected keyword {other:?} in ASCII STL"),
                ))
            }
        }
    }
    if let Some(l) = in_loop {
        return Err(IoError::line(
            file,
            last,
            format!("file ends inside the facet opened on line {l}"),
        ));
    }
    if tris.is_empty() {
        return Err(IoError::whole(file, "ASCII STL without facets"));
    }
    finish(file, w.pos, tris)
}

/// Serialises a binary STL (f32 coordinates, face normals computed from the corners).
pub(crate) fn write_stl(mesh: &TriMesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * mesh.n_faces());
    let mut header = [b' '; 80];
    let tag = b"binary STL written by bipolar mesh-io";
    header[..tag.len()].copy_from_slice(tag);
    out.extend_from_slice(&header);
    out.extend_from_slice(&(mesh.n_faces() as u32).to_le_bytes());
    for f in 0..mesh.n_faces() as u32 {
        let n = mesh.face_normal(f);
        for v in [n.x, n.y, n.z] {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
        for p in mesh.face_corners(f) {
            for v in [p.x, p.y, p.z] {
                out.extend_from_slice(&(v as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}
