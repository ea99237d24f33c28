//! Landmark files, read and written here only: Bosphorus `.lm3` (3D) and `.lm2` (2D image
//! coordinates), the landmark JSON written by `bipolar landmarks` (or a flat
//! `{label: [x, y, z]}` object) and the ICT FaceKit `landmarks.json` layout.

use crate::text::{lines, next_record, push_xyz};
use crate::IoError;
use meshcore::DVec3;
use std::collections::BTreeMap;
use std::path::Path;

/// A file of labelled 3D landmarks (`.lm3`, landmark JSON, one face of the ICT layout).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Landmarks3d {
    /// Labels, trimmed (e.g. "Nose tip", "Outer left eye corner", "nose_tip").
    pub labels: Vec<String>,
    /// Coordinates, one per label.
    pub points: Vec<DVec3>,
    /// Per label, the mesh vertex the file names (JSON `vertex`, ICT `vertex_ids`); empty when
    /// the file names no vertex (`.lm3`).
    pub vertices: Vec<Option<u32>>,
    /// Per label, a confidence (JSON `confidence`); empty when the file has none.
    pub confidences: Vec<Option<f64>>,
    /// Numbers about the whole set, in file order (JSON top-level numbers such as a detection's
    /// `confidence` or `fit_rms`); empty for `.lm3`.
    pub attributes: Vec<(String, f64)>,
}

impl Landmarks3d {
    /// The point with exactly this (trimmed) label.
    pub fn get(&self, label: &str) -> Option<DVec3> {
        self.index(label).map(|i| self.points[i])
    }

    /// The position of the entry with exactly this (trimmed) label.
    pub fn index(&self, label: &str) -> Option<usize> {
        self.labels.iter().position(|l| l == label.trim())
    }

    /// The vertex the file names for entry `i`, if any.
    pub fn vertex(&self, i: usize) -> Option<u32> {
        self.vertices.get(i).copied().flatten()
    }

    /// Appends an entry (keeping the optional columns aligned when they are in use).
    pub fn push(&mut self, label: impl Into<String>, point: DVec3, vertex: Option<u32>) {
        let n = self.labels.len();
        if vertex.is_some() && self.vertices.len() < n {
            self.vertices.resize(n, None);
        }
        if !self.vertices.is_empty() || vertex.is_some() {
            self.vertices.push(vertex);
        }
        if !self.confidences.is_empty() {
            self.confidences.resize(n + 1, None);
        }
        self.labels.push(label.into());
        self.points.push(point);
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

/// Numbered, trimmed lines: `(1-based line number, line)`.
type Lines = Vec<(usize, String)>;

/// The trimmed lines of `.lm3` / `.lm2` text, the index among them of the `<N> landmarks:`
/// line, and N.
fn counted_lines(bytes: &[u8], file: &str) -> Result<(Lines, usize, usize), IoError> {
    let all: Lines = lines(bytes)
        .map(|(n, l)| (n, l.trim().to_string()))
        .collect();
    let (start, n) = all
        .iter()
        .enumerate()
        .find_map(|(k, (_, l))| count_line(l).map(|n| (k, n)))
        .ok_or_else(|| IoError::whole(file, "no '<N> landmarks:' line"))?;
    Ok((all, start, n))
}

/// Parses an `.lm3` file: finds the line `<N> landmarks:`, then reads N pairs (label line,
/// `x y z` line), skipping blank lines.
pub fn parse_lm3(bytes: &[u8], file: &str) -> Result<Landmarks3d, IoError> {
    let (all, start, n) = counted_lines(bytes, file)?;
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
        let (_, label) = next_record(&mut it, (file, count_ln), k, n, "landmarks")?;
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
    crate::read_parsed(path.as_ref(), parse_lm3)
}

/// Parses an `.lm2` file: after the `<N> landmarks:` line, the labels are the N non-empty lines
/// that do not end with `:` and are not two numbers; the coordinates are the N lines that are
/// exactly two numbers.
pub fn parse_lm2(bytes: &[u8], file: &str) -> Result<Landmarks2d, IoError> {
    let (all, start, n) = counted_lines(bytes, file)?;
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
    crate::read_parsed(path.as_ref(), parse_lm2)
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
        push_xyz(&mut s, *p);
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|e| IoError::io("write", path, e))
}

fn json_vec3(v: &serde_json::Value, file: &str, what: &str) -> Result<DVec3, IoError> {
    let c: Vec<f64> = v
        .as_array()
        .map(|a| a.iter().filter_map(|c| c.as_f64()).collect())
        .unwrap_or_default();
    if c.len() != 3 || v.as_array().map_or(0, Vec::len) != 3 || c.iter().any(|c| !c.is_finite()) {
        return Err(IoError::whole(
            file,
            format!("{what}: expected [x, y, z] with finite numbers, got {v}"),
        ));
    }
    Ok(DVec3::new(c[0], c[1], c[2]))
}

fn json_value(bytes: &[u8], file: &str) -> Result<serde_json::Value, IoError> {
    serde_json::from_slice(bytes).map_err(|e| {
        IoError::line(
            file,
            e.line().max(1),
            format!("not a JSON landmark file: {e}"),
        )
    })
}

fn json_u32(v: Option<&serde_json::Value>) -> Option<u32> {
    v.and_then(|x| x.as_u64())
        .and_then(|x| u32::try_from(x).ok())
}

/// Parses landmark JSON: as written by [`landmarks_json`] (`{"landmarks": {label: {"vertex",
/// "position": [x, y, z], "confidence"}}, <numbers>}`) or a flat `{label: [x, y, z]}` object.
/// Entries that are neither an array nor have a `position` are skipped; at least one landmark
/// must be present.
pub fn parse_landmarks_json(bytes: &[u8], file: &str) -> Result<Landmarks3d, IoError> {
    let v = json_value(bytes, file)?;
    let nested = v.get("landmarks").and_then(|l| l.as_object());
    let obj = nested
        .or_else(|| v.as_object())
        .ok_or_else(|| IoError::whole(file, "expected a JSON object of landmarks"))?;
    let mut out = Landmarks3d::default();
    let mut confidences = Vec::new();
    for (label, x) in obj {
        let (position, vertex, confidence) = if let Some(p) = x.get("position") {
            (
                json_vec3(p, file, label)?,
                json_u32(x.get("vertex")),
                x.get("confidence").and_then(|c| c.as_f64()),
            )
        } else if x.is_array() {
            (json_vec3(x, file, label)?, None, None)
        } else {
            continue;
        };
        out.push(label.clone(), position, vertex);
        confidences.push(confidence);
    }
    if out.labels.is_empty() {
        return Err(IoError::whole(file, "no landmark positions found"));
    }
    if confidences.iter().any(Option::is_some) {
        out.confidences = confidences;
    }
    if let (Some(_), Some(top)) = (nested, v.as_object()) {
        out.attributes = top
            .iter()
            .filter_map(|(k, x)| x.as_f64().map(|x| (k.clone(), x)))
            .collect();
    }
    Ok(out)
}

/// The landmark JSON of `lm` (see [`parse_landmarks_json`]): its attributes at the top level and
/// `"landmarks": {label: {"position", "vertex"?, "confidence"?}}`.
pub fn landmarks_json(lm: &Landmarks3d) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for (i, (label, p)) in lm.labels.iter().zip(&lm.points).enumerate() {
        let mut e = serde_json::Map::new();
        e.insert("position".into(), serde_json::json!(p.to_array()));
        if let Some(v) = lm.vertex(i) {
            e.insert("vertex".into(), v.into());
        }
        if let Some(c) = lm.confidences.get(i).copied().flatten() {
            e.insert("confidence".into(), c.into());
        }
        m.insert(label.clone(), e.into());
    }
    let mut top = serde_json::Map::new();
    for (k, x) in &lm.attributes {
        top.insert(k.clone(), (*x).into());
    }
    top.insert("landmarks".into(), m.into());
    top.into()
}

/// Writes [`landmarks_json`] of `lm` (pretty-printed, newline-terminated).
pub fn write_landmarks_json(path: impl AsRef<Path>, lm: &Landmarks3d) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    if lm.labels.len() != lm.points.len() {
        return Err(IoError::invalid(
            &name,
            format!("{} labels for {} points", lm.labels.len(), lm.points.len()),
        ));
    }
    if lm.points.iter().any(|p| !p.is_finite()) {
        return Err(IoError::invalid(&name, "non-finite landmark coordinate"));
    }
    let s = serde_json::to_string_pretty(&landmarks_json(lm))
        .map_err(|e| IoError::invalid(&name, e.to_string()))?;
    std::fs::write(path, s + "\n").map_err(|e| IoError::io("write", path, e))
}

/// Parses the ICT FaceKit `landmarks.json` layout (`{"vertex_ids": {label: id}, "faces":
/// {face: {label: [x, y, z]}}}`): face name -> its landmarks, each with the vertex id of its
/// label when `vertex_ids` gives one.
pub fn parse_ict_landmarks(
    bytes: &[u8],
    file: &str,
) -> Result<BTreeMap<String, Landmarks3d>, IoError> {
    let v = json_value(bytes, file)?;
    let faces = v
        .get("faces")
        .and_then(|f| f.as_object())
        .ok_or_else(|| IoError::whole(file, "no \"faces\" object"))?;
    let ids = v.get("vertex_ids").and_then(|i| i.as_object());
    let mut out = BTreeMap::new();
    for (name, f) in faces {
        let f = f
            .as_object()
            .ok_or_else(|| IoError::whole(file, format!("faces.{name} is not an object")))?;
        let mut lm = Landmarks3d::default();
        for (label, p) in f {
            let q = json_vec3(p, file, &format!("faces.{name}.{label}"))?;
            lm.push(label.clone(), q, json_u32(ids.and_then(|i| i.get(label))));
        }
        out.insert(name.clone(), lm);
    }
    Ok(out)
}

/// Reads the ICT FaceKit `landmarks.json` layout (see [`parse_ict_landmarks`]).
pub fn read_ict_landmarks(
    path: impl AsRef<Path>,
) -> Result<BTreeMap<String, Landmarks3d>, IoError> {
    crate::read_parsed(path.as_ref(), parse_ict_landmarks)
}

/// Reads any file of labelled 3D landmarks: `.lm3` by extension, otherwise JSON: the ICT
/// layout (the face named `face`, usually the mesh file's stem; an error listing the faces when
/// it is missing or `None`), the landmark JSON of [`write_landmarks_json`] or a flat
/// `{label: [x, y, z]}` object.
pub fn read_landmark_file(
    path: impl AsRef<Path>,
    face: Option<&str>,
) -> Result<Landmarks3d, IoError> {
    let path = path.as_ref();
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("lm3"))
    {
        return read_lm3(path);
    }
    crate::read_parsed(path, |bytes, name| {
        let v = json_value(bytes, name)?;
        if !v.get("faces").is_some_and(|f| f.is_object()) {
            return parse_landmarks_json(bytes, name);
        }
        let mut faces = parse_ict_landmarks(bytes, name)?;
        let names: Vec<String> = faces.keys().cloned().collect();
        face.and_then(|f| faces.remove(f)).ok_or_else(|| {
            IoError::whole(
                name,
                format!(
                    "no face named {:?} in this ICT landmark file; it has: {}",
                    face.unwrap_or(""),
                    names.join(", ")
                ),
            )
        })
    })
}
