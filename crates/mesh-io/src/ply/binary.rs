//! The body of a binary PLY file (little or big endian).

use super::header::{Header, Prop, Ty};
use super::records::{
    check_index, face_list_index, list_length, push_face, push_strip, vertex_roles, Sink,
};
use crate::IoError;
use meshcore::DVec3;

/// Reads one scalar of type `ty` at `off` (bounds checked by the caller).
#[inline(always)]
pub(super) fn get(b: &[u8], off: usize, ty: Ty, be: bool) -> f64 {
    macro_rules! rd {
        ($t:ty, $n:expr) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[off..off + $n]);
            if be {
                <$t>::from_be_bytes(a) as f64
            } else {
                <$t>::from_le_bytes(a) as f64
            }
        }};
    }
    match ty {
        Ty::I8 => b[off] as i8 as f64,
        Ty::U8 => b[off] as f64,
        Ty::I16 => rd!(i16, 2),
        Ty::U16 => rd!(u16, 2),
        Ty::I32 => rd!(i32, 4),
        Ty::U32 => rd!(u32, 4),
        Ty::F32 => rd!(f32, 4),
        Ty::F64 => rd!(f64, 8),
    }
}

pub(super) fn read_binary(
    bytes: &[u8],
    h: &Header,
    file: &str,
    sink: &mut Sink,
    be: bool,
) -> Result<(), IoError> {
    let mut off = h.body_start;
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    let mut raw: Vec<f64> = Vec::new();
    for el in &h.elements {
        // The smallest a record can be: scalars plus list counts with zero items.
        let min_rec: usize = el
            .props
            .iter()
            .map(|p| match p {
                Prop::Scalar(t, _) => t.size(),
                Prop::List(c, _, _) => c.size(),
            })
            .sum();
        let remaining = bytes.len() - off;
        if (el.count as u128) * (min_rec as u128) > remaining as u128 {
            return Err(IoError::byte(
                file,
                off,
                format!(
                    "element '{}' declares {} records (at least {} bytes) but only {remaining} bytes remain (truncated file or wrong count)",
                    el.name, el.count, el.count as u128 * min_rec as u128
                ),
            ));
        }
        let truncated =
            |o: usize| IoError::byte(file, o, format!("file ends inside element '{}'", el.name));
        match el.name.as_str() {
            "vertex" => {
                let (roles, scalars, has_color) = vertex_roles(el, file)?;
                sink.pos.reserve(el.count);
                sink.scalars = scalars.into_iter().map(|s| (0, s)).collect();
                for s in &mut sink.scalars {
                    s.1.values.reserve(el.count);
                }
                if has_color {
                    sink.colors.reserve(el.count);
                }
                for _ in 0..el.count {
                    let rec_start = off;
                    let mut p = DVec3::ZERO;
                    let mut c = [0u8, 0, 0, 255];
                    for (prop, role) in el.props.iter().zip(&roles) {
                        match prop {
                            Prop::Scalar(ty, _) => {
                                if off + ty.size() > bytes.len() {
                                    return Err(truncated(off));
                                }
                                let v = get(bytes, off, *ty, be);
                                off += ty.size();
                                role.store(v, &mut p, &mut c, sink);
                            }
                            Prop::List(ct, it, _) => {
                                off = skip_list(bytes, off, *ct, *it, be, file, &el.name)?;
                            }
                        }
                    }
                    if !p.is_finite() {
                        return Err(IoError::byte(
                            file,
                            rec_start,
                            format!(
                                "vertex {} has a non-finite coordinate ({}, {}, {})",
                                sink.pos.len(),
                                p.x,
                                p.y,
                                p.z
                            ),
                        ));
                    }
                    sink.pos.push(p);
                    if has_color {
                        sink.colors.push(c);
                    }
                }
            }
            "face" | "tristrips" => {
                let strips = el.name == "tristrips";
                let li = face_list_index(el, file)?;
                sink.tris.reserve(el.count);
                sink.tri_at.reserve(el.count);
                // Fast path for the common layout `list uchar int|uint vertex_indices` alone:
                // triangles are 13-byte records.
                let fast = !strips
                    && el.props.len() == 1
                    && matches!(el.props[0], Prop::List(Ty::U8, Ty::I32 | Ty::U32, _));
                for _ in 0..el.count {
                    if fast && off + 13 <= bytes.len() && bytes[off] == 3 {
                        let rd = |o: usize| {
                            let a = [bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]];
                            if be {
                                u32::from_be_bytes(a)
                            } else {
                                u32::from_le_bytes(a)
                            }
                        };
                        let t = [rd(off + 1), rd(off + 5), rd(off + 9)];
                        let signed = matches!(el.props[0], Prop::List(_, Ty::I32, _));
                        if let Some(k) = t
                            .iter()
                            .position(|&v| (signed && (v as i32) < 0) || v >= u32::MAX - 1)
                        {
                            return Err(IoError::byte(
                                file,
                                off + 1 + 4 * k,
                                format!(
                                    "invalid vertex index {}",
                                    if signed {
                                        t[k] as i64 as i32 as i64
                                    } else {
                                        t[k] as i64
                                    }
                                ),
                            ));
                        }
                        sink.tris.push(t);
                        sink.tri_at.push(off);
                        off += 13;
                        continue;
                    }
                    for (k, prop) in el.props.iter().enumerate() {
                        match prop {
                            Prop::Scalar(ty, _) => {
                                if off + ty.size() > bytes.len() {
                                    return Err(truncated(off));
                                }
                                off += ty.size();
                            }
                            Prop::List(ct, it, _) if k == li => {
                                let rec = off;
                                if off + ct.size() > bytes.len() {
                                    return Err(truncated(off));
                                }
                                let n = get(bytes, off, *ct, be);
                                off += ct.size();
                                let n = list_length(n, file, crate::Location::Byte(rec))?;
                                if n.saturating_mul(it.size()) > bytes.len() - off {
                                    return Err(IoError::byte(file, rec, format!("face list of {n} indices runs past the end of the file")));
                                }
                                if strips {
                                    raw.clear();
                                    for _ in 0..n {
                                        raw.push(get(bytes, off, *it, be));
                                        off += it.size();
                                    }
                                    push_strip(sink, &raw, file, crate::Location::Byte(rec), rec)?;
                                    continue;
                                }
                                corners.clear();
                                for _ in 0..n {
                                    corners.push(check_index(
                                        get(bytes, off, *it, be),
                                        file,
                                        crate::Location::Byte(off),
                                    )?);
                                    off += it.size();
                                }
                                push_face(sink, &corners, file, crate::Location::Byte(rec), rec)?;
                            }
                            Prop::List(ct, it, _) => {
                                off = skip_list(bytes, off, *ct, *it, be, file, &el.name)?;
                            }
                        }
                    }
                }
            }
            _ if el.props.is_empty() => {}
            _ => {
                for _ in 0..el.count {
                    for prop in &el.props {
                        match prop {
                            Prop::Scalar(ty, _) => {
                                if off + ty.size() > bytes.len() {
                                    return Err(truncated(off));
                                }
                                off += ty.size();
                            }
                            Prop::List(ct, it, _) => {
                                off = skip_list(bytes, off, *ct, *it, be, file, &el.name)?;
                            }
                        }
                    }
                }
            }
        }
    }
    let rest = &bytes[off..];
    if rest.iter().any(|b| !b.is_ascii_whitespace()) {
        return Err(IoError::byte(
            file,
            off,
            format!("{} bytes after the last element: the header declares fewer records than the file holds", rest.len()),
        ));
    }
    Ok(())
}

pub(super) fn skip_list(
    bytes: &[u8],
    off: usize,
    ct: Ty,
    it: Ty,
    be: bool,
    file: &str,
    el: &str,
) -> Result<usize, IoError> {
    if off + ct.size() > bytes.len() {
        return Err(IoError::byte(
            file,
            off,
            format!("file ends inside element '{el}'"),
        ));
    }
    let n = get(bytes, off, ct, be);
    let len = list_length(n, file, crate::Location::Byte(off))?.saturating_mul(it.size());
    let start = off + ct.size();
    if len > bytes.len() - start {
        return Err(IoError::byte(
            file,
            off,
            format!("list of {n} items runs past the end of the file"),
        ));
    }
    Ok(start + len)
}
