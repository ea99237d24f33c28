//! Face-set loading: a folder of OBJ faces in the ICT topology (such as the paper set,
//! `<shared>/faces/ict-facekit/paper-set`) and its optional `landmarks.json`.

use crate::FaceModelError;
use meshcore::TriMesh;
use std::path::Path;

/// Vertex id of the right outer eye corner in the ICT face topology (ground truth).
pub const RIGHT_EYE_OUTER: u32 = 1507;
/// Vertex id of the left outer eye corner.
pub const LEFT_EYE_OUTER: u32 = 3721;
/// Vertex id of the nose tip.
pub const NOSE_TIP: u32 = 4857;

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
    /// Person label (`id1` ...): the stem before the first `_`.
    pub person: String,
    /// Expression label (`neutral`, `anger` ...): the stem after the first `_`.
    pub expression: String,
    /// The mesh (cm).
    pub mesh: TriMesh,
    /// Landmarks (vertex ids).
    pub landmarks: FaceLandmarks,
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

/// Loads every `*.obj` of `dir` (sorted by person, the person's `neutral` first, then the
/// expressions by name) with `mesh-io`, checks that each has the ground-truth landmark vertices
/// and, when `landmarks.json` is present, that its positions lie on those vertices (within
/// `1e-4` of the bounding-box diagonal).
pub fn load_face_set(dir: &Path) -> Result<Vec<Face>, FaceModelError> {
    let set_err = |problem: &str| FaceModelError::FaceSet {
        dir: dir.to_path_buf(),
        problem: problem.into(),
    };
    if !dir.is_dir() {
        return Err(set_err("face folder not found"));
    }
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| FaceModelError::io("list", dir, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("obj")))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort_by_key(|n| order_key(n));
    if names.is_empty() {
        return Err(set_err("no .obj file"));
    }
    let lm_path = dir.join("landmarks.json");
    let lms = if lm_path.is_file() {
        Some(
            mesh_io::read_ict_landmarks(&lm_path)
                .map_err(|e| FaceModelError::landmarks(&lm_path, e))?,
        )
    } else {
        None
    };
    let mut faces = Vec::new();
    for name in names {
        let path = dir.join(format!("{name}.obj"));
        let mesh = mesh_io::read_mesh(&path)
            .map_err(|e| FaceModelError::mesh(&path, e))?
            .mesh;
        let landmarks = FaceLandmarks::ground_truth();
        for v in [
            landmarks.right_eye_outer,
            landmarks.left_eye_outer,
            landmarks.nose_tip,
        ] {
            if v as usize >= mesh.n_vertices() {
                return Err(FaceModelError::MissingLandmarkVertex {
                    face: name,
                    vertex: v,
                    n_vertices: mesh.n_vertices(),
                });
            }
        }
        if let Some(m) = lms.as_ref().and_then(|l| l.get(&name)) {
            let tol = 1e-4 * mesh.bbox().diagonal();
            for (key, v) in [
                ("right_eye_outer", landmarks.right_eye_outer),
                ("left_eye_outer", landmarks.left_eye_outer),
                ("nose_tip", landmarks.nose_tip),
            ] {
                if let Some(p) = m.get(key) {
                    let d = (mesh.position(v) - p).length();
                    if d > tol {
                        return Err(FaceModelError::LandmarkMismatch {
                            face: name,
                            landmark: key.into(),
                            vertex: v,
                            distance: d,
                        });
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
    use meshcore::DVec3;
    use std::path::PathBuf;

    #[test]
    fn order_puts_neutral_first() {
        let mut v = vec!["id2_neutral", "id1_anger", "id1_neutral", "id1_disgust"];
        v.sort_by_key(|n| order_key(n));
        assert_eq!(
            v,
            ["id1_neutral", "id1_anger", "id1_disgust", "id2_neutral"]
        );
    }

    /// The vertex ids of the ICT topology are OBJ file order: mesh-io keeps it (1-based,
    /// negative and `v/vt/vn` indices, polygons fan-split from their first corner), the
    /// behaviour of the private reader this crate replaced.
    #[test]
    fn obj_vertices_keep_file_order() {
        let m = mesh_io::read_mesh_from_bytes(
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2/2/2 3/3/3 4/4/4\nf -4 -2 -1\n",
            mesh_io::Format::Obj,
        )
        .unwrap()
        .mesh;
        assert_eq!(m.n_vertices(), 4);
        assert_eq!(m.position(2), DVec3::new(1.0, 1.0, 0.0));
        assert_eq!(m.triangles(), &[[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        for bad in ["v 0 0\nf 1 2 3\n", "v 0 0 0\nf 1 2 9\n"] {
            assert!(mesh_io::read_mesh_from_bytes(bad.as_bytes(), mesh_io::Format::Obj).is_err());
        }
    }

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("facemodel-set-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// OBJ text of a strip of `n` vertices (enough for the ICT landmark ids when `n > 4857`).
    fn strip(n: usize) -> String {
        let mut s = String::new();
        for v in 0..n {
            s += &format!("v {} {} 0\n", v / 2, v % 2);
        }
        for v in 1..n - 1 {
            s += &format!("f {} {} {}\n", v, v + 1, v + 2);
        }
        s
    }

    #[test]
    fn face_sets_load_in_order_and_bad_sets_are_named() {
        let dir = tmp("ok");
        for name in ["id2_neutral", "id1_smile", "id1_neutral"] {
            std::fs::write(dir.join(format!("{name}.obj")), strip(4860)).unwrap();
        }
        std::fs::write(dir.join("notes.txt"), "not a face").unwrap();
        let faces = load_face_set(&dir).unwrap();
        let names: Vec<&str> = faces.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["id1_neutral", "id1_smile", "id2_neutral"]);
        assert_eq!(
            (faces[1].person.as_str(), faces[1].expression.as_str()),
            ("id1", "smile")
        );
        assert_eq!(faces[0].landmarks, FaceLandmarks::ground_truth());

        // landmarks.json on the vertex passes; off it by more than the tolerance fails.
        let p = faces[0].mesh.position(NOSE_TIP);
        let json = |dx: f64| {
            format!(
                "{{\"faces\": {{\"id1_neutral\": {{\"nose_tip\": [{}, {}, {}]}}}}}}",
                p.x + dx,
                p.y,
                p.z
            )
        };
        std::fs::write(dir.join("landmarks.json"), json(0.0)).unwrap();
        assert_eq!(load_face_set(&dir).unwrap().len(), 3);
        std::fs::write(dir.join("landmarks.json"), json(1.0)).unwrap();
        match load_face_set(&dir) {
            Err(FaceModelError::LandmarkMismatch {
                face,
                landmark,
                vertex,
                ..
            }) => {
                assert_eq!(
                    (face.as_str(), landmark.as_str(), vertex),
                    ("id1_neutral", "nose_tip", NOSE_TIP)
                );
            }
            other => panic!("{other:?}"),
        }
        std::fs::write(
            dir.join("landmarks.json"),
            "{\"faces\": {\"a\": {\"nose_tip\": [1, 2]}}}",
        )
        .unwrap();
        let e = load_face_set(&dir).unwrap_err();
        assert!(
            matches!(e, FaceModelError::Landmarks { .. })
                && e.to_string()
                    .contains("faces.a.nose_tip: expected [x, y, z]")
                && e.to_string().contains("landmarks.json"),
            "{e}"
        );
        std::fs::write(dir.join("landmarks.json"), "{\"faces\": ").unwrap();
        assert!(matches!(
            load_face_set(&dir),
            Err(FaceModelError::Landmarks { .. })
        ));
        std::fs::remove_file(dir.join("landmarks.json")).unwrap();

        // A face outside the ICT topology lacks the landmark vertices.
        std::fs::write(dir.join("id3_neutral.obj"), strip(100)).unwrap();
        assert!(matches!(
            load_face_set(&dir),
            Err(FaceModelError::MissingLandmarkVertex {
                vertex: RIGHT_EYE_OUTER,
                n_vertices: 100,
                ..
            })
        ));
        std::fs::write(dir.join("id3_neutral.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
        let e = load_face_set(&dir).unwrap_err();
        assert!(
            matches!(e, FaceModelError::Mesh { .. }) && e.to_string().contains("id3_neutral.obj"),
            "{e}"
        );

        let empty = tmp("empty");
        assert!(matches!(
            load_face_set(&empty),
            Err(FaceModelError::FaceSet { .. })
        ));
        let missing = empty.join("missing");
        let e = load_face_set(&missing).unwrap_err();
        assert!(e.to_string().contains("not found"), "{e}");
    }
}
