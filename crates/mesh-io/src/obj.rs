//! Wavefront OBJ reader (positions and faces; polygons fan-triangulated) and writer.

use crate::text::{fan, lines, parse_num, parse_xyz, push_xyz};
use crate::{finish, IoError, LoadedMesh};
use meshcore::{DVec3, TriMesh};

/// Parses an OBJ file. Reads `v` (optionally with `r g b` colour after `x y z`) and `f`
/// statements (`i`, `i/t`, `i//n`, `i/t/n`, negative indices relative to the vertices read so
/// far); other statements (`vn`, `vt`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`, ...) are
/// ignored. Faces with more than three corners are fan-triangulated.
pub(crate) fn read_obj(bytes: &[u8], file: &str) -> Result<LoadedMesh, IoError> {
    let mut pos: Vec<DVec3> = Vec::new();
    let mut colors: Vec<[u8; 4]> = Vec::new();
    let mut all_colored = true;
    let mut tris: Vec<[u32; 3]> = Vec::new();
    // For deferred range checks of positive indices: (line, index) of each triangle's source.
    let mut tri_lines: Vec<usize> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut n_polygons = 0usize;
    let mut n_lines = 0usize;
    for (ln, line) in lines(bytes) {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line.ends_with('\\') {
            return Err(IoError::line(
                file,
                ln,
                "line continuation ('\\') is not supported",
            ));
        }
        let mut toks = line.split_ascii_whitespace();
        match toks.next() {
            Some("v") => {
                let vals: Vec<&str> = toks.collect();
                if vals.len() < 3 {
                    return Err(IoError::line(
                        file,
                        ln,
                        format!("vertex needs 3 coordinates, found {}", vals.len()),
                    ));
                }
                pos.push(parse_xyz(&mut vals.iter().copied(), file, ln)?);
                if vals.len() == 6 && all_colored {
                    let mut c = [255u8; 4];
                    for k in 0..3 {
                        let v: f64 = parse_num(Some(vals[3 + k]), file, ln, "vertex colour")?;
                        c[k] = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                    colors.push(c);
                } else {
                    all_colored = false;
                }
            }
            Some("f") => {
                corners.clear();
                for tok in toks {
                    let idx = tok.split('/').next().unwrap_or("");
                    let i: i64 = idx.parse().map_err(|_| {
                        IoError::line(file, ln, format!("face index {tok:?} is not an integer"))
                    })?;
                    let resolved = if i > 0 {
                        i - 1
                    } else if i < 0 {
                        let r = pos.len() as i64 + i;
                        if r < 0 {
                            return Err(IoError::line(
                                file,
                                ln,
                                format!(
                                    "relative face index {i} points before the first vertex ({} read so far)",
                                    pos.len()
                                ),
                            ));
                        }
                        r
                    } else {
                        return Err(IoError::line(
                            file,
                            ln,
                            "face index 0 (OBJ indices start at 1)",
                        ));
                    };
                    if resolved > u32::MAX as i64 - 1 {
                        return Err(IoError::line(
                            file,
                            ln,
                            format!("face index {i} is too large"),
                        ));
                    }
                    corners.push(resolved as u32);
                }
                match fan(&corners, &mut tris) {
                    None => {
                        return Err(IoError::line(
                            file,
                            ln,
                            format!("face has {} corner(s); at least 3 needed", corners.len()),
                        ))
                    }
                    Some(polygon) => n_polygons += usize::from(polygon),
                }
                tri_lines.resize(tris.len(), ln);
            }
            Some("l") => n_lines += 1,
            _ => {}
        }
    }
    let n = pos.len();
    if let Some((t, tri)) = tris
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        let bad = tri.iter().find(|&&v| v as usize >= n).copied().unwrap_or(0);
        return Err(IoError::line(
            file,
            tri_lines[t],
            format!(
                "face refers to vertex {} but the file has {n} vertices",
                bad as u64 + 1
            ),
        ));
    }
    if tris.is_empty() {
        return Err(IoError::whole(
            file,
            format!("no faces ({n} vertices); an OBJ mesh needs 'f' statements"),
        ));
    }
    let mut out = finish(file, pos, tris)?;
    if all_colored && !colors.is_empty() && colors.len() == n {
        out.colors = Some(colors);
    }
    if n_polygons > 0 {
        out.warnings.push(format!(
            "{n_polygons} polygon(s) with more than 3 corners fan-triangulated"
        ));
    }
    if n_lines > 0 {
        out.warnings
            .push(format!("{n_lines} line ('l') statement(s) ignored"));
    }
    Ok(out)
}

/// Serialises positions (shortest exact decimal form) and 1-based faces.
pub(crate) fn write_obj(mesh: &TriMesh) -> Vec<u8> {
    let mut s = String::with_capacity(mesh.n_vertices() * 40 + mesh.n_faces() * 24);
    s.push_str("# written by bipolar mesh-io\n");
    for p in mesh.positions() {
        s.push_str("v ");
        push_xyz(&mut s, *p);
        s.push('\n');
    }
    for t in mesh.triangles() {
        use std::fmt::Write;
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s.into_bytes()
}
