//! Face-set loading: the shared data folder, OBJ meshes and `landmarks.json`.

use anyhow::{bail, Context, Result};
use meshcore::{DVec3, TriMesh};
use std::path::{Path, PathBuf};

/// Vertex id of the right outer eye corner in the ICT face topology (ground truth).
pub const RIGHT_EYE_OUTER: u32 = 1507;
/// Vertex id of the left outer eye corner.
pub const LEFT_EYE_OUTER: u32 = 3721;
/// Vertex id of the nose tip.
pub const NOSE_TIP: u32 = 4857;

/// Root of the workspace (the folder holding the root `Cargo.toml`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// The shared data folder: `$BIPOLAR_SHARED`, else `../shared` relative to the workspace root.
pub fn shared_dir() -> PathBuf {
    match std::env::var_os("BIPOLAR_SHARED") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => workspace_root().join("..").join("shared"),
    }
}

/// Default folder of the paper set (12 faces + `landmarks.json`).
pub fn default_paper_set() -> PathBuf {
    shared_dir()
        .join("faces")
        .join("ict-facekit")
        .join("paper-set")
}

/// Output folder `name` under the cargo target directory (`$CARGO_TARGET_DIR` if set,
/// else `<workspace>/target`).
pub fn default_out_dir(name: &str) -> PathBuf {
    let target = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => workspace_root().join("target"),
    };
    target.join(name)
}

/// Three landmarks of one face: vertex ids (ground truth) and positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceLandmarks {
    /// Right outer eye corner (reference point r).
    pub right_eye_outer: u32,
    /// Left outer eye corner (reference point q, the one the paper perturbs).
    pub left_eye_outer: u32,
    /// Nose tip (the single-pole representation's pole).
    pub nose_tip: u32,
}

impl FaceLandmarks {
    /// The ground-truth landmarks of the ICT topology.
    pub fn ground_truth() -> Self {
        Self {
            right_eye_outer: RIGHT_EYE_OUTER,
            left_eye_outer: LEFT_EYE_OUTER,
            nose_tip: NOSE_TIP,
        }
    }
}

/// One face of the set.
#[derive(Debug, Clone)]
pub struct Face {
    /// File stem, e.g. `id1_neutral`.
    pub name: String,
    /// Person label (`id1` ...).
    pub person: String,
    /// Expression label (`neutral`, `anger` ...).
    #[allow(dead_code)] // descriptive; tables use `name`
    pub expression: String,
    /// The mesh (cm).
    pub mesh: TriMesh,
    /// Landmarks (vertex ids).
    pub landmarks: FaceLandmarks,
}

/// Reads a triangle mesh from a file with `mesh-io` (warnings are ignored here).
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    Ok(mesh_io::read_mesh(path)
        .with_context(|| format!("reading {}", path.display()))?
        .mesh)
}

#[allow(dead_code)] // kept as the reference reader of the tests
/// Minimal OBJ parser: `v x y z` and `f a b c ...` (1-based or negative indices, `a/b/c`
/// tokens, polygons fan-triangulated). Everything else is ignored.
pub fn parse_obj(text: &str) -> Result<TriMesh> {
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut c = [0.0f64; 3];
                for x in c.iter_mut() {
                    let tok = it.next().with_context(|| {
                        format!("line {}: vertex with fewer than 3 coordinates", ln + 1)
                    })?;
                    *x = tok
                        .parse()
                        .with_context(|| format!("line {}: bad coordinate {tok:?}", ln + 1))?;
                }
                pos.push(DVec3::from_array(c));
            }
            Some("f") => {
                let mut idx = Vec::new();
                for tok in it {
                    let first = tok.split('/').next().unwrap_or("");
                    let i: i64 = first
                        .parse()
                        .with_context(|| format!("line {}: bad face index {tok:?}", ln + 1))?;
                    let n = pos.len() as i64;
                    let k = if i > 0 { i - 1 } else { n + i };
                    if k < 0 {
                        bail!("line {}: face index {i} out of range", ln + 1);
                    }
                    idx.push(k as u32);
                }
                if idx.len() < 3 {
                    bail!("line {}: face with fewer than 3 vertices", ln + 1);
                }
                for k in 1..idx.len() - 1 {
                    tris.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(TriMesh::new(pos, tris)?)
}

/// Landmark positions per face from `landmarks.json` (`faces.<name>.<landmark> = [x, y, z]`).
pub fn read_landmark_positions(
    path: &Path,
) -> Result<std::collections::BTreeMap<String, std::collections::BTreeMap<String, DVec3>>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let faces = v
        .get("faces")
        .and_then(|f| f.as_object())
        .with_context(|| format!("{}: no \"faces\" object", path.display()))?;
    let mut out = std::collections::BTreeMap::new();
    for (name, lms) in faces {
        let mut m = std::collections::BTreeMap::new();
        if let Some(obj) = lms.as_object() {
            for (lm, arr) in obj {
                let a: Vec<f64> = arr
                    .as_array()
                    .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
                    .unwrap_or_default();
                if a.len() != 3 {
                    bail!("{}: {name}.{lm} is not [x, y, z]", path.display());
                }
                m.insert(lm.clone(), DVec3::new(a[0], a[1], a[2]));
            }
        }
        out.insert(name.clone(), m);
    }
    Ok(out)
}

/// Sort key putting `id1_neutral` first, then person 1's expressions, then the other persons.
fn order_key(name: &str) -> (String, u8, String) {
    let (person, expr) = name.split_once('_').unwrap_or((name, ""));
    (
        person.to_string(),
        u8::from(expr != "neutral"),
        expr.to_string(),
    )
}

/// Loads every `*.obj` of `dir` (sorted: person, neutral first, then expressions) and checks
/// the ground-truth landmark vertices against `landmarks.json` when it is present.
pub fn load_face_set(dir: &Path) -> Result<Vec<Face>> {
    if !dir.is_dir() {
        bail!(
            "face folder {} not found (set --faces DIR or BIPOLAR_SHARED)",
            dir.display()
        );
    }
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .with_context(|| format!("listing {}", dir.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("obj")))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort_by_key(|n| order_key(n));
    if names.is_empty() {
        bail!("no .obj file in {}", dir.display());
    }
    let lm_path = dir.join("landmarks.json");
    let lms = if lm_path.is_file() {
        Some(read_landmark_positions(&lm_path)?)
    } else {
        None
    };
    let mut faces = Vec::new();
    for name in names {
        let mesh = read_mesh(&dir.join(format!("{name}.obj")))?;
        let landmarks = FaceLandmarks::ground_truth();
        for v in [
            landmarks.right_eye_outer,
            landmarks.left_eye_outer,
            landmarks.nose_tip,
        ] {
            mesh.try_position(v)
                .with_context(|| format!("{name}: landmark vertex {v} missing"))?;
        }
        if let Some(m) = lms.as_ref().and_then(|l| l.get(&name)) {
            let tol = 1e-4 * mesh.bbox().diagonal();
            for (key, v) in [
                ("right_eye_outer", landmarks.right_eye_outer),
                ("left_eye_outer", landmarks.left_eye_outer),
                ("nose_tip", landmarks.nose_tip),
            ] {
                if let Some(p) = m.get(key) {
                    let d = (mesh.position(v) - *p).length();
                    if d > tol {
                        bail!("{name}: landmarks.json {key} is {d} away from vertex {v}");
                    }
                }
            }
        }
        let (person, expression) = name
            .split_once('_')
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .unwrap_or((name.clone(), String::new()));
        faces.push(Face {
            name,
            person,
            expression,
            mesh,
            landmarks,
        });
    }
    Ok(faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_parser_handles_quads_slashes_and_negative_indices() {
        let m = parse_obj(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2/2/2 3/3/3 4/4/4\nf -4 -2 -1\n",
        )
        .unwrap();
        assert_eq!(m.n_vertices(), 4);
        assert_eq!(m.triangles(), &[[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert!(parse_obj("v 0 0\nf 1 2 3\n").is_err());
        assert!(parse_obj("v 0 0 0\nf 1 2 9\n").is_err());
    }

    #[test]
    fn order_puts_neutral_first() {
        let mut v = vec!["id2_neutral", "id1_anger", "id1_neutral", "id1_disgust"];
        v.sort_by_key(|n| order_key(n));
        assert_eq!(
            v,
            ["id1_neutral", "id1_anger", "id1_disgust", "id2_neutral"]
        );
    }

    #[test]
    fn paper_set_loads_with_landmarks() {
        let dir = default_paper_set();
        if !dir.is_dir() {
            eprintln!("skipping: {} not found", dir.display());
            return;
        }
        let faces = load_face_set(&dir).unwrap();
        assert_eq!(faces.len(), 12);
        assert_eq!(faces[0].name, "id1_neutral");
        assert!(faces.iter().all(|f| f.mesh.n_vertices() == 6706));
    }
}
