//! Descriptor files: CSV, JSON and PLY.
//!
//! * **CSV**: a header line `x,y,z,a,b,i,j,side,sign,cos,ambiguous`, then one point a row
//!   (`ambiguous` is 0 or 1; floats in shortest round-trip form). Only the points are stored:
//!   [`read_csv`] returns a descriptor whose `step`/`reference_distance` are NaN, references
//!   empty, options default, and whose points have `face = u32::MAX`, `bary = 0`.
//! * **JSON**: everything (points with face and barycentrics, step, references, options except
//!   the vertex mask, stats); lossless round trip.
//! * **PLY** (ASCII, write only): one vertex per point with the key fields and `cos` as extra
//!   properties, for viewers.

use crate::{BipolarError, Descriptor, DescriptorOptions, DescriptorPoint, DescriptorStats, Key};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// The CSV header line.
pub const CSV_HEADER: &str = "x,y,z,a,b,i,j,side,sign,cos,ambiguous";

fn io_err(path: &Path, message: impl Into<String>) -> BipolarError {
    BipolarError::File {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// CSV text of a descriptor (see the module docs).
pub fn to_csv_string(d: &Descriptor) -> String {
    let mut s = String::with_capacity(64 * (d.points.len() + 1));
    s.push_str(CSV_HEADER);
    s.push('\n');
    push_points(&mut s, d, ',');
    s
}

/// Writes the CSV file.
pub fn write_csv(path: &Path, d: &Descriptor) -> Result<(), BipolarError> {
    Ok(meshcore::write_bytes(path, to_csv_string(d))?)
}

/// Parses CSV text; `path` only names the source in error messages.
pub fn parse_csv(text: &str, path: &Path) -> Result<Descriptor, BipolarError> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == CSV_HEADER => {}
        Some((_, h)) => {
            return Err(io_err(
                path,
                format!("line 1: expected header {CSV_HEADER:?}, found {h:?}"),
            ))
        }
        None => return Err(io_err(path, "empty file (expected a header line)")),
    }
    let mut points = Vec::new();
    for (ln, line) in lines {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let lno = ln + 1;
        if f.len() != 11 {
            return Err(io_err(
                path,
                format!("line {lno}: expected 11 fields, found {}", f.len()),
            ));
        }
        fn num<T: std::str::FromStr>(
            s: &str,
            name: &str,
            lno: usize,
            path: &Path,
        ) -> Result<T, BipolarError> {
            s.parse::<T>()
                .map_err(|_| io_err(path, format!("line {lno}: bad {name} value {s:?}")))
        }
        let x: f64 = num(f[0], "x", lno, path)?;
        let y: f64 = num(f[1], "y", lno, path)?;
        let z: f64 = num(f[2], "z", lno, path)?;
        let key = Key {
            a: num(f[3], "a", lno, path)?,
            b: num(f[4], "b", lno, path)?,
            i: num(f[5], "i", lno, path)?,
            j: num(f[6], "j", lno, path)?,
            side: num(f[7], "side", lno, path)?,
            sign: num(f[8], "sign", lno, path)?,
        };
        if key.i > Key::MAX_LEVEL
            || key.j > Key::MAX_LEVEL
            || key.side.abs() > 1
            || key.sign.abs() > 1
        {
            return Err(io_err(
                path,
                format!("line {lno}: key out of range {key:?}"),
            ));
        }
        let cos: f64 = num(f[9], "cos", lno, path)?;
        let ambiguous = match f[10] {
            "0" | "false" => false,
            "1" | "true" => true,
            o => {
                return Err(io_err(
                    path,
                    format!("line {lno}: bad ambiguous value {o:?} (expected 0 or 1)"),
                ))
            }
        };
        let position = DVec3::new(x, y, z);
        if !position.is_finite() {
            return Err(io_err(path, format!("line {lno}: non-finite position")));
        }
        points.push(DescriptorPoint {
            position,
            key,
            cos,
            face: u32::MAX,
            bary: DVec3::ZERO,
            ambiguous,
        });
    }
    let max_level = points.iter().map(|p| p.key.i).max().unwrap_or(0);
    Ok(Descriptor {
        points,
        step: f64::NAN,
        max_level,
        reference_distance: f64::NAN,
        references: Vec::new(),
        options: DescriptorOptions::default(),
        stats: DescriptorStats::default(),
    })
}

/// Reads a CSV file written by [`write_csv`].
pub fn read_csv(path: &Path) -> Result<Descriptor, BipolarError> {
    parse_csv(&meshcore::read_text(path)?, path)
}

#[derive(Serialize, Deserialize)]
struct WirePoint {
    position: [f64; 3],
    key: Key,
    cos: f64,
    face: u32,
    bary: [f64; 3],
    ambiguous: bool,
}

#[derive(Serialize, Deserialize)]
struct WireDescriptor {
    format: String,
    step: Option<f64>,
    max_level: u32,
    reference_distance: Option<f64>,
    references: Vec<[f64; 3]>,
    options: DescriptorOptions,
    stats: DescriptorStats,
    points: Vec<WirePoint>,
}

const JSON_FORMAT: &str = "bipolar-descriptor-1";

fn finite_or_none(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// JSON text of a descriptor.
pub fn to_json_string(d: &Descriptor) -> String {
    let w = WireDescriptor {
        format: JSON_FORMAT.to_string(),
        step: finite_or_none(d.step),
        max_level: d.max_level,
        reference_distance: finite_or_none(d.reference_distance),
        references: d.references.iter().map(|p| p.to_array()).collect(),
        options: d.options.clone(),
        stats: d.stats,
        points: d
            .points
            .iter()
            .map(|p| WirePoint {
                position: p.position.to_array(),
                key: p.key,
                cos: p.cos,
                face: p.face,
                bary: p.bary.to_array(),
                ambiguous: p.ambiguous,
            })
            .collect(),
    };
    serde_json::to_string_pretty(&w).unwrap_or_default()
}

/// Writes the JSON file.
pub fn write_json(path: &Path, d: &Descriptor) -> Result<(), BipolarError> {
    Ok(meshcore::write_bytes(path, to_json_string(d))?)
}

/// Parses JSON text; `path` only names the source in error messages.
pub fn parse_json(text: &str, path: &Path) -> Result<Descriptor, BipolarError> {
    let w: WireDescriptor = serde_json::from_str(text).map_err(|e| {
        io_err(
            path,
            format!("line {}, column {}: {e}", e.line(), e.column()),
        )
    })?;
    if w.format != JSON_FORMAT {
        return Err(io_err(
            path,
            format!("unknown format {:?} (expected {JSON_FORMAT:?})", w.format),
        ));
    }
    Ok(Descriptor {
        points: w
            .points
            .into_iter()
            .map(|p| DescriptorPoint {
                position: DVec3::from_array(p.position),
                key: p.key,
                cos: p.cos,
                face: p.face,
                bary: DVec3::from_array(p.bary),
                ambiguous: p.ambiguous,
            })
            .collect(),
        step: w.step.unwrap_or(f64::NAN),
        max_level: w.max_level,
        reference_distance: w.reference_distance.unwrap_or(f64::NAN),
        references: w.references.into_iter().map(DVec3::from_array).collect(),
        options: w.options,
        stats: w.stats,
    })
}

/// Reads a JSON file written by [`write_json`].
pub fn read_json(path: &Path) -> Result<Descriptor, BipolarError> {
    parse_json(&meshcore::read_text(path)?, path)
}

/// ASCII PLY text of the points (with key fields and cos as vertex properties).
pub fn to_ply_string(d: &Descriptor) -> String {
    let mut s = String::new();
    s.push_str("ply\nformat ascii 1.0\ncomment bipolar descriptor\n");
    let _ = writeln!(s, "element vertex {}", d.points.len());
    for p in ["x", "y", "z"] {
        let _ = writeln!(s, "property double {p}");
    }
    s.push_str("property uchar a\nproperty uchar b\nproperty uint i\nproperty uint j\n");
    s.push_str(
        "property char side\nproperty char sign\nproperty double cos\nproperty uchar ambiguous\n",
    );
    s.push_str("end_header\n");
    push_points(&mut s, d, ' ');
    s
}

/// One line per point, the fields separated by `sep`: the CSV columns and the PLY vertex
/// properties, in the order of [`CSV_HEADER`].
fn push_points(s: &mut String, d: &Descriptor, sep: char) {
    for p in &d.points {
        let k = p.key;
        let (x, y, z) = (p.position.x, p.position.y, p.position.z);
        let (a, b, i, j, side, sign) = (k.a, k.b, k.i, k.j, k.side, k.sign);
        let (cos, amb) = (p.cos, u8::from(p.ambiguous));
        let _ = writeln!(
            s,
            "{x}{sep}{y}{sep}{z}{sep}{a}{sep}{b}{sep}{i}{sep}{j}{sep}{side}{sep}{sign}{sep}{cos}{sep}{amb}"
        );
    }
}

/// Writes the PLY file.
pub fn write_ply(path: &Path, d: &Descriptor) -> Result<(), BipolarError> {
    Ok(meshcore::write_bytes(path, to_ply_string(d))?)
}

meshcore::choice! {
    /// A descriptor file format, named by the file's extension.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Format: "descriptor file", BipolarError {
        /// [`write_csv`], [`read_csv`].
        Csv = "csv",
        /// [`write_json`], [`read_json`].
        Json = "json",
        /// [`write_ply`] (write only).
        Ply = "ply",
    }
}

impl Format {
    /// The format named by the extension of `path` (ASCII case ignored), if any.
    pub fn of_path(path: &Path) -> Option<Format> {
        use meshcore::Choice;
        Format::from_name(path.extension()?.to_str()?).ok()
    }
}

/// Writes `d` in the format named by the extension of `path` (`.csv`, `.json`, `.ply`).
pub fn write_auto(path: &Path, d: &Descriptor) -> Result<(), BipolarError> {
    match Format::of_path(path) {
        Some(Format::Csv) => write_csv(path, d),
        Some(Format::Json) => write_json(path, d),
        Some(Format::Ply) => write_ply(path, d),
        None => Err(io_err(
            path,
            "unknown descriptor file extension (expected .csv, .json or .ply)",
        )),
    }
}

/// Reads `.csv` or `.json` descriptor files by extension.
pub fn read_auto(path: &Path) -> Result<Descriptor, BipolarError> {
    match Format::of_path(path) {
        Some(Format::Csv) => read_csv(path),
        Some(Format::Json) => read_json(path),
        _ => Err(io_err(
            path,
            "unknown descriptor file extension (expected .csv or .json)",
        )),
    }
}
