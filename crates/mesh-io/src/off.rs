//! OFF (Object File Format) reader and writer.

use crate::text::{fan, lines, next_record, parse_num, parse_xyz, push_xyz};
use crate::{finish, IoError, LoadedMesh};
use meshcore::TriMesh;

/// Parses an OFF file: optional `OFF`/`COFF`/`NOFF`/`CNOFF` keyword (counts may follow it on
/// the same line), `nv nf ne`, `nv` vertex lines (extra values such as colours ignored), `nf`
/// face lines `k i1 .. ik [colour]` (fan-triangulated). `#` starts a comment.
pub(crate) fn read_off(bytes: &[u8], file: &str) -> Result<LoadedMesh, IoError> {
    let mut it = lines(bytes).filter_map(|(n, l)| {
        let l = match l.find('#') {
            Some(i) => l[..i].trim().to_string(),
            None => l.trim().to_string(),
        };
        (!l.is_empty()).then_some((n, l))
    });
    let (ln, first) = it
        .next()
        .ok_or_else(|| IoError::whole(file, "empty file"))?;
    let mut toks: Vec<&str> = first.split_ascii_whitespace().collect();
    let mut count_line = ln;
    let owned;
    if toks[0].ends_with("OFF") {
        if toks[0].starts_with("ST") || toks[0].contains('4') || toks[0].starts_with('n') {
            return Err(IoError::Unsupported {
                file: file.into(),
                at: crate::Location::Line(ln),
                problem: format!("OFF variant {:?}", toks[0]),
            });
        }
        toks.remove(0);
        if toks.is_empty() {
            let (l2, s) = it
                .next()
                .ok_or_else(|| IoError::line(file, ln, "file ends before the counts line"))?;
            owned = s;
            count_line = l2;
            toks = owned.split_ascii_whitespace().collect();
        }
    }
    let mut c = toks.iter().copied();
    let nv: usize = parse_num(c.next(), file, count_line, "vertex count")?;
    let nf: usize = parse_num(c.next(), file, count_line, "face count")?;
    // Each vertex line is at least 6 bytes ("0 0 0\n"), each face at least 8 ("3 0 0 0\n").
    if (nv as u128) * 6 + (nf as u128) * 8 > bytes.len() as u128 + 2 {
        return Err(IoError::line(
            file,
            count_line,
            format!("header claims {nv} vertices and {nf} faces, more than the {} bytes of the file can hold", bytes.len()),
        ));
    }
    let counts = (file, count_line);
    let mut pos = Vec::with_capacity(nv);
    for k in 0..nv {
        let (ln, l) = next_record(&mut it, counts, k, nv, "vertices")?;
        pos.push(parse_xyz(&mut l.split_ascii_whitespace(), file, ln)?);
    }
    let mut tris = Vec::with_capacity(nf);
    let mut n_poly = 0;
    for k in 0..nf {
        let (ln, l) = next_record(&mut it, counts, k, nf, "faces")?;
        let mut t = l.split_ascii_whitespace();
        let deg: usize = parse_num(t.next(), file, ln, "face size")?;
        if deg < 3 {
            return Err(IoError::line(
                file,
                ln,
                format!("face with {deg} corner(s)"),
            ));
        }
        let mut c = Vec::with_capacity(deg.min(64));
        for _ in 0..deg {
            let i: usize = parse_num(t.next(), file, ln, "vertex index")?;
            if i >= nv {
                return Err(IoError::line(
                    file,
                    ln,
                    format!("vertex index {i} out of range (the file has {nv} vertices)"),
                ));
            }
            c.push(i as u32);
        }
        if fan(&c, &mut tris) == Some(true) {
            n_poly += 1;
        }
    }
    if let Some((ln, l)) = it.next() {
        return Err(IoError::line(
            file,
            ln,
            format!(
                "unexpected data {l:?} after the {nv} vertices and {nf} faces the header declares"
            ),
        ));
    }
    let mut out = finish(file, pos, tris)?;
    if n_poly > 0 {
        out.warnings.push(format!(
            "{n_poly} polygon(s) with more than 3 corners fan-triangulated"
        ));
    }
    Ok(out)
}

/// Serialises an OFF file (exact decimal coordinates).
pub(crate) fn write_off(mesh: &TriMesh) -> Vec<u8> {
    use std::fmt::Write;
    let mut s = format!("OFF\n{} {} 0\n", mesh.n_vertices(), mesh.n_faces());
    for p in mesh.positions() {
        push_xyz(&mut s, *p);
        s.push('\n');
    }
    for t in mesh.triangles() {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s.into_bytes()
}
