//! The body of an ASCII PLY file, read as a token stream with line numbers.

use super::header::{Header, Prop, Ty};
use super::records::{
    check_index, face_list_index, list_length, push_face, push_strip, vertex_roles, Role, Sink,
};
use crate::IoError;
use meshcore::DVec3;

/// Token stream over the ASCII body, with line numbers.
pub(super) struct Tokens<'a> {
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

pub(super) fn ascii_value(
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

pub(super) fn read_ascii(
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
                        roles[k].store(v, &mut p, &mut c, sink);
                    }
                    Prop::List(ct, it, _) => {
                        let (n, ln) = ascii_value(toks.next(), *ct, file, last, &el.name)?;
                        rec_line = ln;
                        let n = list_length(n, file, crate::Location::Line(ln))?;
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
