//! Landmark files: Bosphorus `.lm3` (read and write), the ICT FaceKit `landmarks.json` layout
//! (read), and the JSON written by detection (read and write).

use crate::{LandmarkError, LandmarkName, Landmarks};
use meshcore::DVec3;
use std::collections::BTreeMap;
use std::path::Path;

fn io_err(path: &Path, e: std::io::Error) -> LandmarkError {
    LandmarkError::Io {
        path: path.display().to_string(),
        source: e,
    }
}

fn parse_err(path: &str, line: usize, message: impl Into<String>) -> LandmarkError {
    LandmarkError::Parse {
        path: path.to_owned(),
        line,
        message: message.into(),
    }
}

/// Parses `.lm3` text (`path` only names the source in errors): every `(label, x y z)` pair after
/// the `"<N> landmarks:"` line, in file order, labels trimmed (CR removed).
pub fn parse_lm3(text: &str, path: &str) -> Result<Vec<(String, DVec3)>, LandmarkError> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r').trim()))
        .collect();
    let (start, count) = lines
        .iter()
        .enumerate()
        .find_map(|(k, (_, l))| {
            let mut it = l.split_whitespace();
            let n: usize = it.next()?.parse().ok()?;
            (it.next()? == "landmarks:" && it.next().is_none()).then_some((k + 1, n))
        })
        .ok_or_else(|| parse_err(path, 0, "no \"<N> landmarks:\" line"))?;
    let mut out = Vec::with_capacity(count);
    let mut it = lines[start..].iter().filter(|(_, l)| !l.is_empty());
    for k in 0..count {
        let (ln, label) = it.next().ok_or_else(|| {
            parse_err(
                path,
                lines.len(),
                format!("{count} landmarks announced, {k} found"),
            )
        })?;
        let (lc, coords) = it
            .next()
            .ok_or_else(|| parse_err(path, *ln, format!("no coordinates after label {label}")))?;
        let v: Vec<f64> = coords
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| parse_err(path, *lc, format!("bad coordinates {coords:?}")))?;
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(parse_err(
                path,
                *lc,
                format!("expected 3 finite numbers, got {coords:?}"),
            ));
        }
        out.push((label.to_string(), DVec3::new(v[0], v[1], v[2])));
    }
    Ok(out)
}

/// Reads a `.lm3` file (see [`parse_lm3`]).
pub fn read_lm3(path: &Path) -> Result<Vec<(String, DVec3)>, LandmarkError> {
    let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
    parse_lm3(&text, &path.display().to_string())
}

/// The five landmarks of the crate among labelled points (`.lm3` labels, JSON keys); an error
/// naming the first missing one.
pub fn select_five(points: &[(String, DVec3)], source: &str) -> Result<[DVec3; 5], LandmarkError> {
    let mut out = [DVec3::ZERO; 5];
    for n in LandmarkName::ALL {
        out[n as usize] = points
            .iter()
            .find(|(l, _)| LandmarkName::parse(l) == Some(n))
            .map(|(_, p)| *p)
            .ok_or_else(|| parse_err(source, 0, format!("no landmark {:?}", n.lm3_label())))?;
    }
    Ok(out)
}

/// Writes the five landmarks as `.lm3` (Bosphorus labels).
pub fn write_lm3(path: &Path, lm: &Landmarks) -> Result<(), LandmarkError> {
    let mut s = String::from("# landmarks detected by bipolar\n\n5 landmarks:\n");
    for n in LandmarkName::ALL {
        let p = lm.get(n).position;
        s.push_str(&format!("{}\n{} {} {}\n", n.lm3_label(), p.x, p.y, p.z));
    }
    std::fs::write(path, s).map_err(|e| io_err(path, e))
}

fn vec3(v: &serde_json::Value, path: &str, what: &str) -> Result<DVec3, LandmarkError> {
    let a = v
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| parse_err(path, 0, format!("{what}: expected [x, y, z]")))?;
    let c: Vec<f64> = a.iter().filter_map(|x| x.as_f64()).collect();
    if c.len() != 3 || c.iter().any(|x| !x.is_finite()) {
        return Err(parse_err(
            path,
            0,
            format!("{what}: non-numeric coordinate"),
        ));
    }
    Ok(DVec3::new(c[0], c[1], c[2]))
}

/// Parses the ICT `landmarks.json` layout (`{"faces": {name: {right_eye_outer: [x,y,z], ...}}}`):
/// face name -> the five positions.
pub fn parse_ict_landmarks(
    text: &str,
    path: &str,
) -> Result<BTreeMap<String, [DVec3; 5]>, LandmarkError> {
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| parse_err(path, e.line(), e.to_string()))?;
    let faces = v["faces"]
        .as_object()
        .ok_or_else(|| parse_err(path, 0, "no \"faces\" object"))?;
    let mut out = BTreeMap::new();
    for (name, f) in faces {
        let mut pts = [DVec3::ZERO; 5];
        for n in LandmarkName::ALL {
            pts[n as usize] = vec3(&f[n.ict_key()], path, &format!("{name}.{}", n.ict_key()))?;
        }
        out.insert(name.clone(), pts);
    }
    Ok(out)
}

/// Reads the ICT `landmarks.json` layout (see [`parse_ict_landmarks`]).
pub fn read_ict_landmarks(path: &Path) -> Result<BTreeMap<String, [DVec3; 5]>, LandmarkError> {
    let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
    parse_ict_landmarks(&text, &path.display().to_string())
}

/// JSON of detected landmarks: `{"confidence", "fit_rms", "inlier_fraction", "symmetry", "landmarks":
/// {"outer_eye_right": {"vertex", "position": [x, y, z], "confidence"}, ...}}`.
pub fn landmarks_to_json(lm: &Landmarks) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for n in LandmarkName::ALL {
        let l = lm.get(n);
        m.insert(
            n.key().to_owned(),
            serde_json::json!({
                "vertex": l.vertex,
                "position": l.position.to_array(),
                "confidence": l.confidence,
            }),
        );
    }
    serde_json::json!({
        "confidence": lm.confidence,
        "fit_rms": lm.fit_rms,
        "inlier_fraction": lm.inlier_fraction,
        "symmetry": lm.symmetry,
        "landmarks": m,
    })
}

/// Writes [`landmarks_to_json`] (pretty-printed).
pub fn write_landmarks_json(path: &Path, lm: &Landmarks) -> Result<(), LandmarkError> {
    let s = serde_json::to_string_pretty(&landmarks_to_json(lm)).unwrap_or_default();
    std::fs::write(path, s + "\n").map_err(|e| io_err(path, e))
}

/// Reads labelled landmark positions from a file: `.lm3` by extension, otherwise JSON as written
/// by [`write_landmarks_json`] or a flat `{name: [x, y, z]}` object.
pub fn read_landmarks(path: &Path) -> Result<Vec<(String, DVec3)>, LandmarkError> {
    let is_lm3 = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("lm3"));
    if is_lm3 {
        return read_lm3(path);
    }
    let p = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| parse_err(&p, e.line(), e.to_string()))?;
    let obj = v
        .get("landmarks")
        .and_then(|l| l.as_object())
        .or_else(|| v.as_object())
        .ok_or_else(|| parse_err(&p, 0, "expected a JSON object of landmarks"))?;
    let mut out = Vec::new();
    for (k, val) in obj {
        let pos = if let Some(pp) = val.get("position") {
            vec3(pp, &p, k)?
        } else if val.is_array() {
            vec3(val, &p, k)?
        } else {
            continue;
        };
        out.push((k.clone(), pos));
    }
    Ok(out)
}
