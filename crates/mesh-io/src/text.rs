//! Helpers for line-oriented text formats: line numbering, number parsing with errors that
//! name the file and the line.

use crate::IoError;

/// Iterates over the lines of a byte buffer as `(1-based line number, line)`, without the
/// line terminator (`\n`, `\r\n` or a lone `\r` before `\n`). Lines that are not valid UTF-8 are
/// decoded lossily (formats here only need ASCII numbers; labels keep what they can).
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, std::borrow::Cow<'_, str>)> {
    let mut rest = bytes;
    let mut n = 0usize;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        n += 1;
        let (line, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], &rest[i + 1..]),
            None => (rest, &rest[rest.len()..]),
        };
        rest = next;
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        Some((n, String::from_utf8_lossy(line)))
    })
}

/// Parses a finite f64, with an error naming `what`, the file and the line.
pub(crate) fn parse_f64(
    tok: Option<&str>,
    file: &str,
    line: usize,
    what: &str,
) -> Result<f64, IoError> {
    let tok = tok.ok_or_else(|| IoError::line(file, line, format!("missing {what}")))?;
    let v: f64 = tok
        .parse()
        .map_err(|_| IoError::line(file, line, format!("{what}: {tok:?} is not a number")))?;
    if !v.is_finite() {
        return Err(IoError::line(
            file,
            line,
            format!("{what} is not finite ({tok})"),
        ));
    }
    Ok(v)
}

/// Parses an unsigned integer, with an error naming `what`, the file and the line.
pub(crate) fn parse_usize(
    tok: Option<&str>,
    file: &str,
    line: usize,
    what: &str,
) -> Result<usize, IoError> {
    let tok = tok.ok_or_else(|| IoError::line(file, line, format!("missing {what}")))?;
    tok.parse().map_err(|_| {
        IoError::line(
            file,
            line,
            format!("{what}: {tok:?} is not a non-negative integer"),
        )
    })
}

/// Parses three finite coordinates.
pub(crate) fn parse_xyz<'a>(
    toks: &mut impl Iterator<Item = &'a str>,
    file: &str,
    line: usize,
) -> Result<meshcore::DVec3, IoError> {
    let x = parse_f64(toks.next(), file, line, "x coordinate")?;
    let y = parse_f64(toks.next(), file, line, "y coordinate")?;
    let z = parse_f64(toks.next(), file, line, "z coordinate")?;
    Ok(meshcore::DVec3::new(x, y, z))
}

/// Appends `f64` in the shortest form that reads back exactly.
pub(crate) fn push_f64(out: &mut String, v: f64) {
    use std::fmt::Write;
    let _ = write!(out, "{v:?}");
}
