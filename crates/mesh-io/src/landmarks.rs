//! Bosphorus landmark files: `.lm3` (3D) and `.lm2` (2D image coordinates).

use crate::text::{lines, push_f64};
use crate::IoError;
use meshcore::DVec3;
use std::path::Path;

/// Labelled 3D landmarks (`.lm3`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Landmarks3d {
    /// Labels, trimmed (e.g. "Nose tip", "Outer left eye corner").
    pub labels: Vec<String>,
    /// Coordinates, one per label.
    pub points: Vec<DVec3>,
}

impl Landmarks3d {
    /// The point with exactly this (trimmed) label.
    pub fn get(&self, label: &str) -> Option<DVec3> {
        self.labels
            .iter()
            .position(|l| l == label.trim())
            .map(|i| self.points[i])
    }
}

/// Labelled 2D landmarks (`.lm2`, pixel coordinates in the texture image).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Landmarks2d {
    /// Labels, trimmed.
    pub labels: Vec<String>,
    /// (x, y) pixel coordinates, one per label.
    pub points: Vec<[f64; 2]>,
}

fn count_line(l: &str) -> Option<usize> {
    let l = l.trim();
    let rest = l.strip_suffix("landmarks:")?;
    rest.trim().parse().ok()
}

fn numbers(l: &str) -> Option<Vec<f64>> {
    let v: Option<Vec<f64>> = l.split_ascii_whitespace().map(|t| t.parse().ok()).collect();
    v.filter(|v| !v.is_empty())
}

/// Parses an `.lm3` file: finds the line `<N> landmarks:`, then reads N pairs (label line,
/// `x y z` line), skipping blank lines.
pub fn parse_lm3(bytes: &[u8], file: &str) -> Result<Landmarks3d, IoError> {
    let all: Vec<(usize, String)> = lines(bytes)
        .map(|(n, l)| (n, l.trim().to_string()))
        .collect();
    let (start, n) = all
        .iter()
        .enumerate()
        .find_map(|(k, (_, l))| count_line(l).map(|n| (k, n)))
        .ok_or_else(|| IoError::whole(file, "no '<N> landmarks:' line"))?;
    let count_ln = all[start].0;
    if n > all.len() {
        return Err(IoError::line(
            file,
            count_ln,
            format!(
                "{n} landmarks announced but the file has only {} lines",
                all.len()
            ),
        ));
    }
    let mut it = all[start + 1..].iter().filter(|(_, l)| !l.is_empty());
    let mut out = Landmarks3d::default();
    for k in 0..n {
        let (_, label) = it.next().ok_or_else(|| {
            IoError::line(
                file,
                count_ln,
                format!("file ends after {k} of {n} landmarks"),
            )
        })?;
        let (ln, coords) = it.next().ok_or_else(|| {
            IoError::line(
                file,
                count_ln,
                format!("file ends after the label of landmark {} of {n}", k + 1),
            )
        })?;
        let v = numbers(coords).filter(|v| v.len() == 3).ok_or_else(|| {
            IoError::line(
                file,
                *ln,
                format!("expected 'x y z' for landmark {label:?}, found {coords:?}"),
            )
        })?;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(IoError::line(
                file,
                *ln,
                format!("non-finite coordinate for landmark {label:?}"),
            ));
        }
        out.labels.push(label.clone());
        out.points.push(DVec3::new(v[0], v[1], v[2]));
    }
    if let Some((ln, l)) = it.next() {
        return Err(IoError::line(
            file,
            *ln,
            format!("unexpected line {l:?} after the {n} landmarks"),
        ));
    }
    Ok(out)
}

/// Reads an `.lm3` file.
pub fn read_lm3(path: impl AsRef<Path>) -> Result<Landmarks3d, IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| IoError::io("read", path, e))?;
    parse_lm3(&bytes, &name)
}

/// Parses an `.lm2` file: after the `<N> landmarks:` line, the labels are the N non-empty lines
/// that do not end with `:` and are not two numbers; the coordinates are the N lines that are
/// exactly two numbers.
pub fn parse_lm2(bytes: &[u8], file: &str) -> Result<Landmarks2d, IoError> {
    let all: Vec<(usize, String)> = lines(bytes)
        .map(|(n, l)| (n, l.trim().to_string()))
        .collect();
    let (start, n) = all
        .iter()
        .enumerate()
        .find_map(|(k, (_, l))| count_line(l).map(|n| (k, n)))
        .ok_or_else(|| IoError::whole(file, "no '<N> landmarks:' line"))?;
    let count_ln = all[start].0;
    let mut out = Landmarks2d::default();
    for (ln, l) in &all[start + 1..] {
        if l.is_empty() || l.ends_with(':') {
            continue;
        }
        match numbers(l) {
            Some(v) if v.len() == 2 => {
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(IoError::line(file, *ln, "non-finite coordinate"));
                }
                out.points.push([v[0], v[1]]);
            }
            Some(_) => {
                return Err(IoError::line(
                    file,
                    *ln,
                    format!("expected 'x y', found {l:?}"),
                ))
            }
            None => out.labels.push(l.clone()),
        }
    }
    if out.labels.len() != n || out.points.len() != n {
        return Err(IoError::line(
            file,
            count_ln,
            format!(
                "{n} landmarks announced, found {} labels and {} coordinate lines",
                out.labels.len(),
                out.points.len()
            ),
        ));
    }
    Ok(out)
}

/// Reads an `.lm2` file.
pub fn read_lm2(path: impl AsRef<Path>) -> Result<Landmarks2d, IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| IoError::io("read", path, e))?;
    parse_lm2(&bytes, &name)
}

/// Writes an `.lm3` file in the Bosphorus layout (coordinates in shortest exact decimal form).
pub fn write_lm3(path: impl AsRef<Path>, lm: &Landmarks3d) -> Result<(), IoError> {
    write_lm3_with_notes(path, lm, &[])
}

/// The information block of `.lm3` text: the non-empty lines after the header line up to the
/// first empty line before the `<N> landmarks:` line (e.g. the landmarks a scanner could not
/// see, as [`write_lm3_with_notes`] writes them). Empty when there is none.
pub fn parse_lm3_notes(bytes: &[u8]) -> Vec<String> {
    let mut out = Vec::new();
    for (k, (_, l)) in lines(bytes).enumerate() {
        let l = l.trim();
        if k == 0 {
            continue;
        }
        if l.is_empty() || count_line(l).is_some() {
            break;
        }
        out.push(l.to_string());
    }
    out
}

/// Writes an `.lm3` file with an information block of `notes` (one line each, after the header
/// line, ended by an empty line; readers skip it). Notes must be non-empty single lines that do
/// not look like the `<N> landmarks:` line.
pub fn write_lm3_with_notes(
    path: impl AsRef<Path>,
    lm: &Landmarks3d,
    notes: &[String],
) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    if let Some(n) = notes.iter().find(|n| {
        n.trim().is_empty() || n.contains('\n') || n.contains('\r') || count_line(n).is_some()
    }) {
        return Err(IoError::invalid(
            &name,
            format!("invalid .lm3 note {n:?} (empty, multi-line or like the count line)"),
        ));
    }
    if lm.labels.len() != lm.points.len() {
        return Err(IoError::invalid(
            &name,
            format!("{} labels for {} points", lm.labels.len(), lm.points.len()),
        ));
    }
    if let Some(l) = lm
        .labels
        .iter()
        .find(|l| l.trim().is_empty() || l.contains('\n') || l.trim() != l.as_str())
    {
        return Err(IoError::invalid(
            &name,
            format!("invalid landmark label {l:?} (empty, multi-line or padded)"),
        ));
    }
    if lm.points.iter().any(|p| !p.is_finite()) {
        return Err(IoError::invalid(&name, "non-finite landmark coordinate"));
    }
    let mut s = String::from("# written by bipolar mesh-io\n");
    for n in notes {
        s.push_str(n.trim());
        s.push('\n');
    }
    s.push_str(&format!("\n{} landmarks:\n", lm.labels.len()));
    for (l, p) in lm.labels.iter().zip(&lm.points) {
        s.push_str(l);
        s.push('\n');
        push_f64(&mut s, p.x);
        s.push(' ');
        push_f64(&mut s, p.y);
        s.push(' ');
        push_f64(&mut s, p.z);
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|e| IoError::io("write", path, e))
}
