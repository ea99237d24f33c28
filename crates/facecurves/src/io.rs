//! Curve files (JSON): either representation, lossless for what it stores.
//!
//! Layout: `{"format": "facecurves", "version": 1, "kind": "facial" | "iso-curvature", ...}`.
//! Facial curves store the options (`step`, `levels`) and per curve `level`, `closed`,
//! `pieces` and `points` (`[[x, y, z], ...]`). Iso-curvature networks store the levels, the
//! fitting radius and per curve `field` (`"k1"`, `"k2"`), `level_index`, `level`, `closed` and
//! `points`; the per-vertex curvature fields are not stored ([`read_json`] returns them empty).

use crate::{
    FaceCurvesError, FacialCurve, FacialCurvesDescriptor, FacialCurvesOptions,
    IsoCurvatureDescriptor, IsoCurve, PrincipalField,
};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A curve representation read from or written to a file.
#[derive(Debug, Clone, PartialEq)]
pub enum CurveSet {
    /// Facial curves.
    Facial(FacialCurvesDescriptor),
    /// An iso-curvature network.
    IsoCurvature(IsoCurvatureDescriptor),
}

#[derive(Serialize, Deserialize)]
struct FileFacialCurve {
    level: u32,
    closed: bool,
    pieces: usize,
    points: Vec<[f64; 3]>,
}

#[derive(Serialize, Deserialize)]
struct FileIsoCurve {
    field: String,
    level_index: usize,
    level: f64,
    closed: bool,
    points: Vec<[f64; 3]>,
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
enum Body {
    Facial {
        step: f64,
        levels: u32,
        curves: Vec<FileFacialCurve>,
    },
    IsoCurvature {
        levels_k1: Vec<f64>,
        levels_k2: Vec<f64>,
        radius: f64,
        curves: Vec<FileIsoCurve>,
    },
}

#[derive(Serialize, Deserialize)]
struct File {
    format: String,
    version: u32,
    #[serde(flatten)]
    body: Body,
}

const FORMAT: &str = "facecurves";

fn arr(p: &[DVec3]) -> Vec<[f64; 3]> {
    p.iter().map(|p| p.to_array()).collect()
}

/// A curve record of a file.
trait FileCurve {
    /// Its points as stored.
    fn points(&self) -> &[[f64; 3]];
}

impl FileCurve for FileFacialCurve {
    fn points(&self) -> &[[f64; 3]] {
        &self.points
    }
}

impl FileCurve for FileIsoCurve {
    fn points(&self) -> &[[f64; 3]] {
        &self.points
    }
}

/// Reads the curve records of a file in order: `read(i, record, points)` makes curve `i` from
/// its record and its points, which must all be finite (`bad` makes the error).
fn read_curves<C: FileCurve, T>(
    records: Vec<C>,
    bad: &dyn Fn(String) -> FaceCurvesError,
    mut read: impl FnMut(usize, C, Vec<DVec3>) -> Result<T, FaceCurvesError>,
) -> Result<Vec<T>, FaceCurvesError> {
    let mut out = Vec::with_capacity(records.len());
    for (i, c) in records.into_iter().enumerate() {
        if !c.points().iter().flatten().all(|x| x.is_finite()) {
            return Err(bad(format!("curve {i} has a non-finite coordinate")));
        }
        let points = c.points().iter().map(|a| DVec3::from_array(*a)).collect();
        out.push(read(i, c, points)?);
    }
    Ok(out)
}

/// JSON text of a curve set.
pub fn to_json_string(set: &CurveSet) -> String {
    let body = match set {
        CurveSet::Facial(d) => Body::Facial {
            step: d.options.step,
            levels: d.options.levels,
            curves: d
                .curves
                .iter()
                .map(|c| FileFacialCurve {
                    level: c.level,
                    closed: c.closed,
                    pieces: c.pieces,
                    points: arr(&c.points),
                })
                .collect(),
        },
        CurveSet::IsoCurvature(d) => Body::IsoCurvature {
            levels_k1: d.levels_k1.clone(),
            levels_k2: d.levels_k2.clone(),
            radius: d.radius,
            curves: d
                .curves
                .iter()
                .map(|c| FileIsoCurve {
                    field: meshcore::Choice::name(c.field).to_string(),
                    level_index: c.level_index,
                    level: c.level,
                    closed: c.closed,
                    points: arr(&c.points),
                })
                .collect(),
        },
    };
    let f = File {
        format: FORMAT.into(),
        version: 1,
        body,
    };
    // Plain data with finite floats: serialisation cannot fail; non-finite values become null.
    serde_json::to_string(&f).unwrap_or_default()
}

/// Parses JSON text; `path` only names the source in error messages.
pub fn parse_json(text: &str, path: &Path) -> Result<CurveSet, FaceCurvesError> {
    let bad = |message: String| FaceCurvesError::File {
        path: path.to_path_buf(),
        message,
    };
    let f: File = serde_json::from_str(text).map_err(|e| bad(format!("not a curve file: {e}")))?;
    if f.format != FORMAT || f.version != 1 {
        return Err(bad(format!(
            "format {:?} version {} (expected {FORMAT:?} version 1)",
            f.format, f.version
        )));
    }
    Ok(match f.body {
        Body::Facial {
            step,
            levels,
            curves,
        } => {
            let out = read_curves(curves, &bad, |_, c, points| {
                Ok(FacialCurve {
                    level: c.level,
                    points,
                    closed: c.closed,
                    pieces: c.pieces,
                })
            })?;
            if out.windows(2).any(|w| w[0].level >= w[1].level) {
                return Err(bad("facial curve levels are not increasing".into()));
            }
            CurveSet::Facial(FacialCurvesDescriptor {
                curves: out,
                options: FacialCurvesOptions { step, levels },
            })
        }
        Body::IsoCurvature {
            levels_k1,
            levels_k2,
            radius,
            curves,
        } => {
            let out = read_curves(curves, &bad, |i, c, points| {
                let field: PrincipalField = c
                    .field
                    .parse()
                    .map_err(|e| bad(format!("curve {i}: {e}")))?;
                Ok(IsoCurve {
                    field,
                    level_index: c.level_index,
                    level: c.level,
                    points,
                    closed: c.closed,
                })
            })?;
            CurveSet::IsoCurvature(IsoCurvatureDescriptor {
                curves: out,
                levels_k1,
                levels_k2,
                k1: Vec::new(),
                k2: Vec::new(),
                radius,
            })
        }
    })
}

/// Writes a curve file.
pub fn write_json(path: &Path, set: &CurveSet) -> Result<(), FaceCurvesError> {
    Ok(meshcore::write_bytes(path, to_json_string(set))?)
}

/// Reads a curve file.
pub fn read_json(path: &Path) -> Result<CurveSet, FaceCurvesError> {
    let text = meshcore::read_text(path)?;
    parse_json(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips() {
        let facial = CurveSet::Facial(FacialCurvesDescriptor {
            curves: vec![FacialCurve {
                level: 2,
                points: vec![DVec3::new(0.1, 1.0 / 3.0, -2.0), DVec3::X, DVec3::Y],
                closed: true,
                pieces: 2,
            }],
            options: FacialCurvesOptions {
                step: 0.7,
                levels: 3,
            },
        });
        let iso = CurveSet::IsoCurvature(IsoCurvatureDescriptor {
            curves: vec![IsoCurve {
                field: PrincipalField::K2,
                level_index: 1,
                level: -0.25,
                points: vec![DVec3::Z, DVec3::new(1e-300, 5.0, 7.25)],
                closed: false,
            }],
            levels_k1: vec![0.5],
            levels_k2: vec![0.0, -0.25],
            k1: Vec::new(),
            k2: Vec::new(),
            radius: 0.9,
        });
        for set in [facial, iso] {
            let s = to_json_string(&set);
            assert_eq!(parse_json(&s, Path::new("x.json")).unwrap(), set);
        }
        let e = parse_json("{\"format\":\"other\"}", Path::new("x.json")).unwrap_err();
        assert!(e.to_string().contains("x.json"), "{e}");
    }
}
