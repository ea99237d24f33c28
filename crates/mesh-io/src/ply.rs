//! Stanford PLY reader (ASCII, binary little and big endian; any elements, scalar and list
//! properties of any type) and writer.

use crate::text::push_f64;
use crate::{finish, IoError, LoadedMesh, ScalarField, ScalarType};
use meshcore::{DVec3, TriMesh};

/// PLY storage encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyEncoding {
    /// Text.
    Ascii,
    /// Binary, little endian.
    BinaryLittleEndian,
    /// Binary, big endian.
    BinaryBigEndian,
}

/// What [`crate::write_ply`] writes besides positions (always `double x y z`) and faces
/// (`list uchar int vertex_indices`).
#[derive(Debug, Clone, Copy)]
pub struct PlyWriteOptions<'a> {
    /// Encoding of the body.
    pub encoding: PlyEncoding,
    /// Per-vertex RGBA colours (`uchar red green blue alpha`), one per vertex.
    pub colors: Option<&'a [[u8; 4]]>,
    /// Named per-vertex scalars (`float` or `double` by [`ScalarType`]), one value per vertex.
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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn parse(s: &str) -> Option<Ty> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }
    fn is_float(self) -> bool {
        matches!(self, Ty::F32 | Ty::F64)
    }
}

#[derive(Debug, Clone)]
enum Prop {
    Scalar(Ty, String),
    List(Ty, Ty, String),
}

impl Prop {
    fn name(&self) -> &str {
        match self {
            Prop::Scalar(_, n) | Prop::List(_, _, n) => n,
        }
    }
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
    line: usize,
}

struct Header {
    encoding: PlyEncoding,
    elements: Vec<Element>,
    body_start: usize,
}

fn parse_header(bytes: &[u8], file: &str) -> Result<Header, IoError> {
    if !bytes.starts_with(b"ply\n") && !bytes.starts_with(b"ply\r\n") {
        return Err(IoError::line(
            file,
            1,
            "not a PLY file (first line must be 'ply')",
        ));
    }
    // The header is ASCII and ends with a line "end_header".
    let limit = bytes.len().min(1 << 20);
    let mut pos = 0usize;
    let mut ln = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= limit {
            return Err(IoError::line(
                file,
                ln.max(1),
                "header has no 'end_header' line (file truncated or not PLY)",
            ));
        }
        let end = bytes[pos..limit]
            .iter()
            .position(|&b| b == b'\n')
            .map(|i| pos + i)
            .ok_or_else(|| {
                IoError::line(
                    file,
                    ln + 1,
                    "header has no 'end_header' line (file truncated?)",
                )
            })?;
        ln += 1;
        let raw = &bytes[pos..end];
        pos = end + 1;
        let line = std::str::from_utf8(raw)
            .map_err(|_| IoError::line(file, ln, "header line is not ASCII text"))?
            .trim();
        let mut t = line.split_ascii_whitespace();
        match t.next() {
            None | Some("ply") | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                encoding = Some(match t.next() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some("binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(IoError::line(file, ln, format!("unknown format {other:?}")))
                    }
                });
            }
            Some("element") => {
                let name = t
                    .next()
                    .ok_or_else(|| IoError::line(file, ln, "element without a name"))?
                    .to_string();
                let count = crate::text::parse_usize(t.next(), file, ln, "element count")?;
                elements.push(Element {
                    name,
                    count,
                    props: Vec::new(),
                    line: ln,
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| IoError::line(file, ln, "property before any element"))?;
                let ty = t.next().unwrap_or("");
                let prop = if ty == "list" {
                    let ct = t.next().and_then(Ty::parse);
                    let it = t.next().and_then(Ty::parse);
                    let name = t.next();
                    match (ct, it, name) {
                        (Some(ct), Some(it), Some(n)) if !ct.is_float() => {
                            Prop::List(ct, it, n.to_string())
                        }
                        _ => {
                            return Err(IoError::line(
                                file,
                                ln,
                                format!("bad list property {line:?} (expected 'property list <int type> <type> <name>')"),
                            ))
                        }
                    }
                } else {
                    match (Ty::parse(ty), t.next()) {
                        (Some(ty), Some(n)) => Prop::Scalar(ty, n.to_string()),
                        _ => {
                            return Err(IoError::line(
                                file,
                                ln,
                                format!("bad property line {line:?}"),
                            ))
                        }
                    }
                };
                el.props.push(prop);
            }
            Some("end_header") => break,
            Some(other) => {
                return Err(IoError::line(
                    file,
                    ln,
                    format!("unknown header keyword {other:?}"),
                ))
            }
        }
    }
    let encoding =
        encoding.ok_or_else(|| IoError::line(file, ln, "header has no 'format' line"))?;
    Ok(Header {
        encoding,
        elements,
        body_start: pos,
    })
}

/// Where the parsed values go.
struct Sink {
    pos: Vec<DVec3>,
    colors: Vec<[u8; 4]>,
    scalars: Vec<(usize, ScalarField)>,
    tris: Vec<[u32; 3]>,
    tri_at: Vec<usize>,
    n_polygons: usize,
    /// Triangle strips decoded and the degenerate strip triangles (repeated vertex) skipped.
    n_strips: usize,
    n_strip_degenerate: usize,
}

/// Roles of the properties of the vertex element.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    X,
    Y,
    Z,
    Color(usize, bool),
    Scalar(usize),
    Ignore,
}

fn vertex_roles(el: &Element, file: &str) -> Result<(Vec<Role>, Vec<ScalarField>, bool), IoError> {
    let mut roles = Vec::new();
    let mut scalars = Vec::new();
    let mut has_color = false;
    for p in &el.props {
        let role = match p {
            Prop::Scalar(ty, name) => match name.as_str() {
                "x" => Role::X,
                "y" => Role::Y,
                "z" => Role::Z,
                "red" | "r" => {
                    has_color = true;
                    Role::Color(0, ty.is_float())
                }
                "green" | "g" => {
                    has_color = true;
                    Role::Color(1, ty.is_float())
                }
                "blue" | "b" => {
                    has_color = true;
                    Role::Color(2, ty.is_float())
                }
                "alpha" | "a" => Role::Color(3, ty.is_float()),
                "nx" | "ny" | "nz" => Role::Ignore,
                _ => {
                    scalars.push(ScalarField {
                        name: name.clone(),
                        values: Vec::new(),
                        ty: if *ty == Ty::F32 {
                            ScalarType::F32
                        } else {
                            ScalarType::F64
                        },
                    });
                    Role::Scalar(scalars.len() - 1)
                }
            },
            Prop::List(..) => Role::Ignore,
        };
        roles.push(role);
    }
    for (r, axis) in [(Role::X, "x"), (Role::Y, "y"), (Role::Z, "z")] {
        if !roles.contains(&r) {
            return Err(IoError::line(
                file,
                el.line,
                format!("vertex element has no '{axis}' property"),
            ));
        }
    }
    Ok((roles, scalars, has_color))
}

fn face_list_index(el: &Element, file: &str) -> Result<usize, IoError> {
    el.props
        .iter()
        .position(|p| {
            matches!(p, Prop::List(..))
                && (p.name() == "vertex_indices" || p.name() == "vertex_index")
        })
        .or_else(|| el.props.iter().position(|p| matches!(p, Prop::List(..))))
        .ok_or_else(|| {
            IoError::line(
                file,
                el.line,
                "face element has no list property (vertex_indices)",
            )
        })
}

fn color_value(v: f64, is_float: bool) -> u8 {
    if is_float {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    } else {
        v.clamp(0.0, 255.0) as u8
    }
}

/// Reads one scalar of type `ty` at `off` (bounds checked by the caller).
#[inline(always)]
fn get(b: &[u8], off: usize, ty: Ty, be: bool) -> f64 {
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

fn check_index(v: f64, file: &str, at: crate::Location) -> Result<u32, IoError> {
    if v < 0.0 || v.fract() != 0.0 || v > (u32::MAX - 1) as f64 {
        return Err(IoError::malformed(
            file,
            at,
            format!("invalid vertex index {v}"),
        ));
    }
    Ok(v as u32)
}

fn push_face(
    sink: &mut Sink,
    corners: &[u32],
    file: &str,
    at: crate::Location,
    where_: usize,
) -> Result<(), IoError> {
    if corners.len() < 3 {
        return Err(IoError::malformed(
            file,
            at,
            format!("face with {} corner(s); at least 3 needed", corners.len()),
        ));
    }
    if corners.len() > 3 {
        sink.n_polygons += 1;
    }
    for k in 1..corners.len() - 1 {
        sink.tris.push([corners[0], corners[k], corners[k + 1]]);
        sink.tri_at.push(where_);
    }
    Ok(())
}

/// Decodes a triangle strip (a `tristrips` list: `-1` restarts a strip, the winding alternates
/// from one triangle to the next; triangles with a repeated vertex, used to join strips, are
/// skipped).
fn push_strip(
    sink: &mut Sink,
    raw: &[f64],
    file: &str,
    at: crate::Location,
    where_: usize,
) -> Result<(), IoError> {
    let mut run: Vec<u32> = Vec::new();
    let flush = |run: &mut Vec<u32>, sink: &mut Sink| {
        if run.len() >= 3 {
            sink.n_strips += 1;
        }
        for k in 2..run.len() {
            let t = if k % 2 == 0 {
                [run[k - 2], run[k - 1], run[k]]
            } else {
                [run[k - 1], run[k - 2], run[k]]
            };
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                sink.n_strip_degenerate += 1;
            } else {
                sink.tris.push(t);
                sink.tri_at.push(where_);
            }
        }
        run.clear();
    };
    for &v in raw {
        if v == -1.0 {
            flush(&mut run, sink);
        } else {
            run.push(check_index(v, file, at)?);
        }
    }
    flush(&mut run, sink);
    Ok(())
}

fn read_binary(
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
                                match *role {
                                    Role::X => p.x = v,
                                    Role::Y => p.y = v,
                                    Role::Z => p.z = v,
                                    Role::Color(k, f) => c[k] = color_value(v, f),
                                    Role::Scalar(k) => sink.scalars[k].1.values.push(v),
                                    Role::Ignore => {}
                                }
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
                                if n < 0.0 {
                                    return Err(IoError::byte(
                                        file,
                                        rec,
                                        format!("negative list length {n}"),
                                    ));
                                }
                                let n = n as usize;
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

fn skip_list(
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
    if n < 0.0 {
        return Err(IoError::byte(
            file,
            off,
            format!("negative list length {n}"),
        ));
    }
    let len = (n as usize).saturating_mul(it.size());
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

/// Token stream over the ASCII body, with line numbers.
struct Tokens<'a> {
    lines: Box<dyn Iterator<Item = (usize, std::borrow::Cow<'a, str>)> + 'a>,
    cur: Vec<String>,
    idx: usize,
    line: usize,
    line_offset: usize,
}

impl<'a> Tokens<'a> {
    fn next(&mut self) -> Option<(&str, usize)> {
        while self.idx >= self.cur.len() {
            let (n, l) = self.lines.next()?;
            self.line = n + self.line_offset;
            self.cur = l.split_ascii_whitespace().map(str::to_string).collect();
            self.idx = 0;
        }
        self.idx += 1;
        Some((&self.cur[self.idx - 1], self.line))
    }
}

fn ascii_value(
    tok: Option<(&str, usize)>,
    ty: Ty,
    file: &str,
    last_line: usize,
    el: &str,
) -> Result<(f64, usize), IoError> {
    let (t, ln) = tok.ok_or_else(|| {
        IoError::line(file, last_line, format!("file ends inside element '{el}'"))
    })?;
    let v = match ty {
        Ty::F32 => t.parse::<f32>().map(f64::from).ok(),
        Ty::F64 => t.parse::<f64>().ok(),
        _ => t.parse::<i64>().ok().map(|v| v as f64),
    };
    match v {
        Some(v) => Ok((v, ln)),
        None => Err(IoError::line(
            file,
            ln,
            format!("{t:?} is not a valid {ty:?} value in element '{el}'"),
        )),
    }
}

fn read_ascii(
    bytes: &[u8],
    h: &Header,
    file: &str,
    sink: &mut Sink,
    header_lines: usize,
) -> Result<(), IoError> {
    let body = &bytes[h.body_start..];
    let mut toks = Tokens {
        lines: Box::new(crate::text::lines(body)),
        cur: Vec::new(),
        idx: 0,
        line: header_lines,
        line_offset: header_lines,
    };
    let mut corners = Vec::with_capacity(8);
    let mut raw: Vec<f64> = Vec::new();
    for el in &h.elements {
        // Each record needs at least one token (>= 1 byte plus a separator) per property.
        let min_rec = 2 * el.props.len().max(1);
        if (el.count as u128) * (min_rec as u128) > body.len() as u128 + 1 {
            return Err(IoError::line(
                file,
                el.line,
                format!(
                    "element '{}' declares {} records but the body has only {} bytes",
                    el.name,
                    el.count,
                    body.len()
                ),
            ));
        }
        let (roles, scalars, has_color) = if el.name == "vertex" {
            let r = vertex_roles(el, file)?;
            (r.0, r.1, r.2)
        } else {
            (vec![Role::Ignore; el.props.len()], Vec::new(), false)
        };
        let strips = el.name == "tristrips";
        let li = if el.name == "face" || strips {
            Some(face_list_index(el, file)?)
        } else {
            None
        };
        if el.name == "vertex" {
            sink.pos.reserve(el.count);
            sink.scalars = scalars.into_iter().map(|s| (0, s)).collect();
        }
        for _ in 0..el.count {
            let mut p = DVec3::ZERO;
            let mut c = [0u8, 0, 0, 255];
            let mut rec_line = 0;
            for (k, prop) in el.props.iter().enumerate() {
                let last = toks.line;
                match prop {
                    Prop::Scalar(ty, _) => {
                        let (v, ln) = ascii_value(toks.next(), *ty, file, last, &el.name)?;
                        rec_line = ln;
                        match roles[k] {
                            Role::X => p.x = v,
                            Role::Y => p.y = v,
                            Role::Z => p.z = v,
                            Role::Color(k, f) => c[k] = color_value(v, f),
                            Role::Scalar(k) => sink.scalars[k].1.values.push(v),
                            Role::Ignore => {}
                        }
                    }
                    Prop::List(ct, it, _) => {
                        let (n, ln) = ascii_value(toks.next(), *ct, file, last, &el.name)?;
                        rec_line = ln;
                        if n < 0.0 {
                            return Err(IoError::line(
                                file,
                                ln,
                                format!("negative list length {n}"),
                            ));
                        }
                        let n = n as usize;
                        if n > body.len() {
                            return Err(IoError::line(
                                file,
                                ln,
                                format!("list length {n} exceeds the file size"),
                            ));
                        }
                        corners.clear();
                        raw.clear();
                        for _ in 0..n {
                            let last = toks.line;
                            let (v, ln) = ascii_value(toks.next(), *it, file, last, &el.name)?;
                            if Some(k) == li && strips {
                                raw.push(v);
                            } else if Some(k) == li {
                                corners.push(check_index(v, file, crate::Location::Line(ln))?);
                            }
                        }
                        if Some(k) == li && strips {
                            push_strip(sink, &raw, file, crate::Location::Line(ln), ln)?;
                        } else if Some(k) == li {
                            push_face(sink, &corners, file, crate::Location::Line(ln), ln)?;
                        }
                    }
                }
            }
            if el.name == "vertex" {
                if !p.is_finite() {
                    return Err(IoError::line(
                        file,
                        rec_line,
                        format!("vertex {} has a non-finite coordinate", sink.pos.len()),
                    ));
                }
                sink.pos.push(p);
                if has_color {
                    sink.colors.push(c);
                }
            }
        }
    }
    let last = toks.line;
    if let Some((t, ln)) = toks.next() {
        return Err(IoError::line(
            file,
            ln.max(last),
            format!("unexpected data {t:?} after the last element: the header declares fewer records than the file holds"),
        ));
    }
    Ok(())
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

/// Serialises a PLY file.
pub(crate) fn write_ply(
    mesh: &TriMesh,
    o: &PlyWriteOptions<'_>,
    file: &str,
) -> Result<Vec<u8>, IoError> {
    let n = mesh.n_vertices();
    if let Some(c) = o.colors {
        if c.len() != n {
            return Err(IoError::invalid(
                file,
                format!("{} colours for {n} vertices", c.len()),
            ));
        }
    }
    for s in o.scalars {
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
        if s.name.is_empty()
            || s.name.chars().any(|c| c.is_whitespace())
            || ["x", "y", "z", "red", "green", "blue", "alpha"].contains(&s.name.as_str())
        {
            return Err(IoError::invalid(
                file,
                format!("invalid or reserved PLY property name {:?}", s.name),
            ));
        }
    }
    let fmt = match o.encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    let mut h = format!("ply\nformat {fmt} 1.0\ncomment written by bipolar mesh-io\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\n");
    if o.colors.is_some() {
        h.push_str(
            "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n",
        );
    }
    for s in o.scalars {
        let t = if s.ty == ScalarType::F32 {
            "float"
        } else {
            "double"
        };
        h.push_str(&format!("property {t} {}\n", s.name));
    }
    h.push_str(&format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.n_faces()
    ));
    let mut out = h.into_bytes();
    match o.encoding {
        PlyEncoding::Ascii => {
            let mut s = String::with_capacity(n * 60 + mesh.n_faces() * 20);
            for (i, p) in mesh.positions().iter().enumerate() {
                push_f64(&mut s, p.x);
                s.push(' ');
                push_f64(&mut s, p.y);
                s.push(' ');
                push_f64(&mut s, p.z);
                if let Some(c) = o.colors {
                    s.push_str(&format!(" {} {} {} {}", c[i][0], c[i][1], c[i][2], c[i][3]));
                }
                for f in o.scalars {
                    s.push(' ');
                    match f.ty {
                        ScalarType::F32 => s.push_str(&format!("{:?}", f.values[i] as f32)),
                        ScalarType::F64 => push_f64(&mut s, f.values[i]),
                    }
                }
                s.push('\n');
            }
            for t in mesh.triangles() {
                s.push_str(&format!("3 {} {} {}\n", t[0], t[1], t[2]));
            }
            out.extend_from_slice(s.as_bytes());
        }
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let be = o.encoding == PlyEncoding::BinaryBigEndian;
            let rec = 24
                + if o.colors.is_some() { 4 } else { 0 }
                + o.scalars
                    .iter()
                    .map(|s| if s.ty == ScalarType::F32 { 4 } else { 8 })
                    .sum::<usize>();
            out.reserve(n * rec + mesh.n_faces() * 13);
            macro_rules! put {
                ($v:expr) => {
                    if be {
                        out.extend_from_slice(&$v.to_be_bytes())
                    } else {
                        out.extend_from_slice(&$v.to_le_bytes())
                    }
                };
            }
            for (i, p) in mesh.positions().iter().enumerate() {
                put!(p.x);
                put!(p.y);
                put!(p.z);
                if let Some(c) = o.colors {
                    out.extend_from_slice(&c[i]);
                }
                for f in o.scalars {
                    match f.ty {
                        ScalarType::F32 => put!(f.values[i] as f32),
                        ScalarType::F64 => put!(f.values[i]),
                    }
                }
            }
            for t in mesh.triangles() {
                out.push(3);
                for &v in t {
                    put!(v as i32);
                }
            }
        }
    }
    Ok(out)
}
