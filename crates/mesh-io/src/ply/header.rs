//! The PLY header: format line, elements and their scalar and list properties.

use super::PlyEncoding;
use crate::IoError;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Ty {
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
    pub(super) fn parse(s: &str) -> Option<Ty> {
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
    pub(super) fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }
    pub(super) fn is_float(self) -> bool {
        matches!(self, Ty::F32 | Ty::F64)
    }
}

#[derive(Debug, Clone)]
pub(super) enum Prop {
    Scalar(Ty, String),
    List(Ty, Ty, String),
}

impl Prop {
    pub(super) fn name(&self) -> &str {
        match self {
            Prop::Scalar(_, n) | Prop::List(_, _, n) => n,
        }
    }
}

#[derive(Debug, Clone)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) props: Vec<Prop>,
    pub(super) line: usize,
}

pub(super) struct Header {
    pub(super) encoding: PlyEncoding,
    pub(super) elements: Vec<Element>,
    pub(super) body_start: usize,
}

pub(super) fn parse_header(bytes: &[u8], file: &str) -> Result<Header, IoError> {
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
                let count = crate::text::parse_num(t.next(), file, ln, "element count")?;
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
