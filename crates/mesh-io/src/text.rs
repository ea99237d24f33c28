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

/// A number type of the text formats and the words its parse error uses.
pub(crate) trait Number: std::str::FromStr + Copy {
    /// What a token of this type is ("a number").
    const KIND: &'static str;
    /// Whether a parsed value is acceptable (floats: finite).
    fn acceptable(self) -> bool {
        true
    }
}

impl Number for f64 {
    const KIND: &'static str = "a number";
    fn acceptable(self) -> bool {
        self.is_finite()
    }
}

impl Number for usize {
    const KIND: &'static str = "a non-negative integer";
}

/// Parses a number (a finite `f64`, a `usize`), with an error naming `what`, the file and the
/// line.
pub(crate) fn parse_num<T: Number>(
    tok: Option<&str>,
    file: &str,
    line: usize,
    what: &str,
) -> Result<T, IoError> {
    let tok = tok.ok_or_else(|| IoError::line(file, line, format!("missing {what}")))?;
    let v: T = tok
        .parse()
        .map_err(|_| IoError::line(file, line, format!("{what}: {tok:?} is not {}", T::KIND)))?;
    if !v.acceptable() {
        return Err(IoError::line(
            file,
            line,
            format!("{what} is not finite ({tok})"),
        ));
    }
    Ok(v)
}

/// The next of the `n` records (`what`: "vertices", "landmarks") that the line `count_line`
/// announced, `k` of them read so far, or an error saying where the file ended.
pub(crate) fn next_record<T>(
    it: &mut impl Iterator<Item = T>,
    (file, count_line): (&str, usize),
    k: usize,
    n: usize,
    what: &str,
) -> Result<T, IoError> {
    it.next().ok_or_else(|| {
        IoError::line(
            file,
            count_line,
            format!("file ends after {k} of {n} {what}"),
        )
    })
}

/// Fan-triangulates a face from its first corner onto `tris`: `None` (nothing added) when it
/// has fewer than 3 corners, else whether it was a polygon (more than 3).
pub(crate) fn fan(corners: &[u32], tris: &mut Vec<[u32; 3]>) -> Option<bool> {
    if corners.len() < 3 {
        return None;
    }
    for k in 1..corners.len() - 1 {
        tris.push([corners[0], corners[k], corners[k + 1]]);
    }
    Some(corners.len() > 3)
}

/// Parses three finite coordinates.
pub(crate) fn parse_xyz<'a>(
    toks: &mut impl Iterator<Item = &'a str>,
    file: &str,
    line: usize,
) -> Result<meshcore::DVec3, IoError> {
    let x = parse_num(toks.next(), file, line, "x coordinate")?;
    let y = parse_num(toks.next(), file, line, "y coordinate")?;
    let z = parse_num(toks.next(), file, line, "z coordinate")?;
    Ok(meshcore::DVec3::new(x, y, z))
}

/// Appends `f64` in the shortest form that reads back exactly.
pub(crate) fn push_f64(out: &mut String, v: f64) {
    use std::fmt::Write;
    let _ = write!(out, "{v:?}");
}

/// Appends `x y z`, each by [`push_f64`].
pub(crate) fn push_xyz(out: &mut String, p: meshcore::DVec3) {
    push_f64(out, p.x);
    out.push(' ');
    push_f64(out, p.y);
    out.push(' ');
    push_f64(out, p.z);
}
