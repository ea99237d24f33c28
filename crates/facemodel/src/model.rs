//! The ICT FaceKit morphable face model (`<shared>/faces/ict-facekit/model/`): loading and
//! sampling random faces.
//!
//! Files: `neutral.obj` (6,706 vertices, 13,120 triangles, cm), `identities.npy` (float32,
//! shape `(100, 6706, 3)`), `expressions.npy` (float32, shape `(27, 6706, 3)`) and `model.json`
//! (expression names, expression recipes, landmark vertex ids). A face is
//! `neutral + sum_i w_i * identities[i] + sum_j e_j * expressions[j]`, with `w_i ~ N(0, 1)` for a
//! plausible person and `e_j` in `[0, 1]`.

use crate::FaceModelError;
use meshcore::{DAffine3, DQuat, DVec3, TriMesh};
use rand::Rng;
use std::collections::BTreeMap;
use std::path::Path;

/// Names of the five landmarks of the model, in the order of
/// [`FaceModel::landmark_positions`].
pub const LANDMARK_NAMES: [&str; 5] = [
    "right_eye_outer",
    "right_eye_inner",
    "left_eye_inner",
    "left_eye_outer",
    "nose_tip",
];

/// The ICT linear face model.
#[derive(Debug, Clone)]
pub struct FaceModel {
    neutral: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Identity offsets, `n_identities * n_vertices` vectors (row-major).
    identities: Vec<DVec3>,
    n_identities: usize,
    /// Expression offsets, `n_expressions * n_vertices` vectors.
    expressions: Vec<DVec3>,
    expression_names: Vec<String>,
    recipes: BTreeMap<String, BTreeMap<String, f64>>,
    landmarks: BTreeMap<String, u32>,
    units: String,
}

impl FaceModel {
    /// Loads the model folder (see the module documentation for the files). `model.json` needs
    /// an `expressions` array of names; `landmarks` (name -> vertex id), `expression_recipes`
    /// (name -> blendshape -> weight) and `units` (default `cm`) are optional.
    pub fn load(dir: &Path) -> Result<Self, FaceModelError> {
        let obj_path = dir.join("neutral.obj");
        let (neutral, triangles) = read_obj(&obj_path)?;
        let n = neutral.len();
        let json_path = dir.join("model.json");
        let text = std::fs::read_to_string(&json_path)
            .map_err(|e| FaceModelError::io("read", &json_path, e))?;
        let meta: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| FaceModelError::Json {
                path: json_path.clone(),
                source: e,
            })?;
        let bad = |problem: String| FaceModelError::json(&json_path, problem);
        let expression_names: Vec<String> = meta["expressions"]
            .as_array()
            .ok_or_else(|| bad("no `expressions` array".into()))?
            .iter()
            .map(|v| v.as_str().map(str::to_owned))
            .collect::<Option<_>>()
            .ok_or_else(|| bad("non-string name in `expressions`".into()))?;
        let mut landmarks = BTreeMap::new();
        if let Some(obj) = meta["landmarks"].as_object() {
            for (k, v) in obj {
                let id = v.as_u64().filter(|&id| (id as usize) < n).ok_or_else(|| {
                    bad(format!(
                        "`landmarks.{k}` = {v} is not a vertex id below {n}"
                    ))
                })?;
                landmarks.insert(k.clone(), id as u32);
            }
        }
        let mut recipes = BTreeMap::new();
        if let Some(obj) = meta["expression_recipes"].as_object() {
            for (name, r) in obj {
                let mut m = BTreeMap::new();
                for (k, v) in r.as_object().into_iter().flatten() {
                    if !expression_names.contains(k) {
                        return Err(bad(format!(
                            "`expression_recipes.{name}` uses unknown expression {k}"
                        )));
                    }
                    m.insert(k.clone(), v.as_f64().unwrap_or(0.0));
                }
                recipes.insert(name.clone(), m);
            }
        }
        let units = meta["units"].as_str().unwrap_or("cm").to_owned();
        let id_path = dir.join("identities.npy");
        let ex_path = dir.join("expressions.npy");
        let (id_shape, id_data) = read_npy_f32(&id_path)?;
        let (ex_shape, ex_data) = read_npy_f32(&ex_path)?;
        for (path, shape) in [(&id_path, &id_shape), (&ex_path, &ex_shape)] {
            if shape.len() != 3 || shape[1] != n || shape[2] != 3 {
                return Err(FaceModelError::NpyShape {
                    path: path.clone(),
                    shape: shape.clone(),
                    expected: format!("(k, {n}, 3) for the {n} vertices of neutral.obj"),
                });
            }
        }
        if ex_shape[0] != expression_names.len() {
            return Err(FaceModelError::NpyShape {
                path: ex_path,
                shape: ex_shape,
                expected: format!(
                    "({}, {n}, 3) for the {} expressions of model.json",
                    expression_names.len(),
                    expression_names.len()
                ),
            });
        }
        let to_vecs = |d: &[f32]| -> Vec<DVec3> {
            d.chunks_exact(3)
                .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
                .collect()
        };
        Ok(Self {
            neutral,
            triangles,
            identities: to_vecs(&id_data),
            n_identities: id_shape[0],
            expressions: to_vecs(&ex_data),
            expression_names,
            recipes,
            landmarks,
            units,
        })
    }

    /// Number of vertices of every sampled face.
    pub fn n_vertices(&self) -> usize {
        self.neutral.len()
    }

    /// Number of identity components.
    pub fn n_identities(&self) -> usize {
        self.n_identities
    }

    /// Number of expression blendshapes.
    pub fn n_expressions(&self) -> usize {
        self.expression_names.len()
    }

    /// Expression blendshape names, in the order of the weights.
    pub fn expression_names(&self) -> &[String] {
        &self.expression_names
    }

    /// Names of the expression recipes of `model.json` (e.g. `happiness`), sorted.
    pub fn recipe_names(&self) -> impl Iterator<Item = &str> {
        self.recipes.keys().map(String::as_str)
    }

    /// Landmark name -> vertex id (`right_eye_outer`, `right_eye_inner`, `left_eye_inner`,
    /// `left_eye_outer`, `nose_tip`; "right" is the subject's right, at negative x).
    pub fn landmark_ids(&self) -> &BTreeMap<String, u32> {
        &self.landmarks
    }

    /// Vertex id of a named landmark.
    pub fn landmark_id(&self, name: &str) -> Result<u32, FaceModelError> {
        self.landmarks
            .get(name)
            .copied()
            .ok_or_else(|| FaceModelError::UnknownLandmark { name: name.into() })
    }

    /// Units of the coordinates (`cm`).
    pub fn units(&self) -> &str {
        &self.units
    }

    /// The neutral face.
    pub fn neutral(&self) -> Result<TriMesh, FaceModelError> {
        Ok(TriMesh::new(self.neutral.clone(), self.triangles.clone())?)
    }

    /// Expression weights of a named recipe (e.g. `happiness`), scaled by `strength`.
    pub fn recipe_weights(&self, name: &str, strength: f64) -> Result<Vec<f64>, FaceModelError> {
        let r = self
            .recipes
            .get(name)
            .ok_or_else(|| FaceModelError::UnknownRecipe { name: name.into() })?;
        Ok(self
            .expression_names
            .iter()
            .map(|e| r.get(e).copied().unwrap_or(0.0) * strength)
            .collect())
    }

    /// `neutral + sum_i w_i identities[i] + sum_j e_j expressions[j]`. Shorter weight slices use
    /// the leading components only; longer ones are an error. Non-finite weights give a
    /// [`FaceModelError::Geometry`] error.
    pub fn sample(
        &self,
        identity_weights: &[f64],
        expression_weights: &[f64],
    ) -> Result<TriMesh, FaceModelError> {
        if identity_weights.len() > self.n_identities {
            return Err(FaceModelError::TooManyWeights {
                kind: "identity",
                given: identity_weights.len(),
                available: self.n_identities,
            });
        }
        if expression_weights.len() > self.n_expressions() {
            return Err(FaceModelError::TooManyWeights {
                kind: "expression",
                given: expression_weights.len(),
                available: self.n_expressions(),
            });
        }
        let n = self.neutral.len();
        let mut pos = self.neutral.clone();
        for (basis, weights) in [
            (&self.identities, identity_weights),
            (&self.expressions, expression_weights),
        ] {
            for (i, &w) in weights.iter().enumerate() {
                if w == 0.0 {
                    continue;
                }
                let off = &basis[i * n..(i + 1) * n];
                for (p, d) in pos.iter_mut().zip(off) {
                    *p += w * *d;
                }
            }
        }
        Ok(TriMesh::new(pos, self.triangles.clone())?)
    }

    /// Identity weights `w_i ~ N(0, 1)` for every component.
    pub fn random_identity<R: Rng>(&self, rng: &mut R) -> Vec<f64> {
        (0..self.n_identities)
            .map(|_| standard_normal(rng))
            .collect()
    }

    /// A random expression: with probability 1/2 a random recipe at strength U(0.3, 1); on top,
    /// each blendshape independently with probability 0.15 at U(0, 0.6); weights clamped to
    /// `[0, 1]`.
    pub fn random_expression<R: Rng>(&self, rng: &mut R) -> Vec<f64> {
        let mut w = vec![0.0; self.n_expressions()];
        if !self.recipes.is_empty() && rng.random::<f64>() < 0.5 {
            let k = rng.random_range(0..self.recipes.len());
            if let Some(name) = self.recipes.keys().nth(k) {
                let s = rng.random_range(0.3..1.0);
                if let Ok(r) = self.recipe_weights(name, s) {
                    w = r;
                }
            }
        }
        for x in w.iter_mut() {
            if rng.random::<f64>() < 0.15 {
                *x += rng.random_range(0.0..0.6);
            }
            *x = x.clamp(0.0, 1.0);
        }
        w
    }

    /// The weights of `identities` x `expressions` faces drawn from `rng` identity by identity:
    /// its [`FaceModel::random_identity`], then per face after the first (which is neutral:
    /// no weights) a [`FaceModel::random_expression`]; as `(identity weights, expression
    /// weights per face)`.
    pub fn random_faces<R: Rng>(
        &self,
        rng: &mut R,
        identities: usize,
        expressions: usize,
    ) -> Vec<(Vec<f64>, Vec<Vec<f64>>)> {
        (0..identities)
            .map(|_| {
                let w = self.random_identity(rng);
                let ex = (0..expressions)
                    .map(|e| match e {
                        0 => Vec::new(),
                        _ => self.random_expression(rng),
                    })
                    .collect();
                (w, ex)
            })
            .collect()
    }

    /// Positions of the named landmarks on a sampled (possibly moved) face, in
    /// [`LANDMARK_NAMES`] order.
    pub fn landmark_positions(&self, mesh: &TriMesh) -> Result<[DVec3; 5], FaceModelError> {
        let mut out = [DVec3::ZERO; 5];
        for (o, name) in out.iter_mut().zip(LANDMARK_NAMES) {
            *o = mesh.try_position(self.landmark_id(name)?)?;
        }
        Ok(out)
    }
}

/// A standard normal variate (Box-Muller).
pub fn standard_normal<R: Rng>(rng: &mut R) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A uniformly random rotation (normalised Gaussian quaternion) followed by a translation with
/// independent `N(0, translation_sigma^2)` coordinates.
pub fn random_rigid_motion<R: Rng>(rng: &mut R, translation_sigma: f64) -> DAffine3 {
    let q = loop {
        let q = DQuat::from_xyzw(
            standard_normal(rng),
            standard_normal(rng),
            standard_normal(rng),
            standard_normal(rng),
        );
        if q.length() > 1e-6 {
            break q.normalize();
        }
    };
    let t = DVec3::new(
        standard_normal(rng),
        standard_normal(rng),
        standard_normal(rng),
    ) * translation_sigma;
    DAffine3::from_rotation_translation(q, t)
}

/// Reads a Wavefront OBJ file with `mesh_io` (the project's one OBJ reader; vertices in file
/// order, polygons fan-triangulated): positions and triangles.
fn read_obj(path: &Path) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), FaceModelError> {
    let loaded = mesh_io::read_mesh(path).map_err(|e| FaceModelError::mesh(path, e))?;
    Ok((
        loaded.mesh.positions().to_vec(),
        loaded.mesh.triangles().to_vec(),
    ))
}

/// Reads a little-endian float32 C-order `.npy` file with `mesh_io` (the project's one `.npy`
/// reader): shape and data.
fn read_npy_f32(path: &Path) -> Result<(Vec<usize>, Vec<f32>), FaceModelError> {
    mesh_io::read_npy_f32(path).map_err(|e| FaceModelError::npy(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use std::path::PathBuf;

    /// Bytes of a version-1 `.npy` file holding `data` as `<f4` of `shape`.
    fn npy(shape: &[usize], data: &[f32]) -> Vec<u8> {
        let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
        let mut header = format!(
            "{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}",
            dims.join(", ")
        );
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend((header.len() as u16).to_le_bytes());
        b.extend(header.as_bytes());
        for x in data {
            b.extend(x.to_le_bytes());
        }
        b
    }

    /// A 4-vertex model: a unit square, 2 identity and 3 expression components with offsets
    /// `(k + 1) * 0.5^v` along x (identities) and y (expressions).
    fn write_model(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("facemodel-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("neutral.obj"),
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        )
        .unwrap();
        let offsets = |k: usize, axis: usize| -> Vec<f32> {
            (0..k)
                .flat_map(|c| {
                    (0..4).flat_map(move |v| {
                        let mut d = [0.0f32; 3];
                        d[axis] = (c + 1) as f32 * 0.5f32.powi(v);
                        d
                    })
                })
                .collect()
        };
        std::fs::write(dir.join("identities.npy"), npy(&[2, 4, 3], &offsets(2, 0))).unwrap();
        std::fs::write(dir.join("expressions.npy"), npy(&[3, 4, 3], &offsets(3, 1))).unwrap();
        std::fs::write(
            dir.join("model.json"),
            r#"{"units": "cm", "expressions": ["a", "b", "c"],
                "landmarks": {"right_eye_outer": 0, "right_eye_inner": 1, "left_eye_inner": 1,
                              "left_eye_outer": 2, "nose_tip": 3},
                "expression_recipes": {"smile": {"a": 1, "c": 0.5}}}"#,
        )
        .unwrap();
        dir
    }

    #[test]
    fn sample_is_the_linear_combination() {
        let m = FaceModel::load(&write_model("linear")).unwrap();
        assert_eq!(
            (m.n_vertices(), m.n_identities(), m.n_expressions()),
            (4, 2, 3)
        );
        assert_eq!(m.units(), "cm");
        assert_eq!(m.recipe_names().collect::<Vec<_>>(), ["smile"]);
        assert_eq!(m.recipe_weights("smile", 0.5).unwrap(), [0.5, 0.0, 0.25]);
        let face = m.sample(&[1.0, -2.0], &[0.0, 0.5]).unwrap();
        // Identities: (1 - 2 * 2) * 0.5^v along x; expression 1: 0.5 * 2 * 0.5^v along y.
        for v in 0..4 {
            let s = 0.5f64.powi(v as i32);
            let expect = m.neutral().unwrap().position(v) + DVec3::new(-3.0 * s, s, 0.0);
            assert_eq!(face.position(v), expect, "vertex {v}");
        }
        assert_eq!(face.triangles(), m.neutral().unwrap().triangles());
        // Shorter weight slices use the leading components; no weights give the neutral face.
        assert_eq!(m.sample(&[], &[]).unwrap(), m.neutral().unwrap());
        assert!(matches!(
            m.sample(&[0.0; 3], &[]),
            Err(FaceModelError::TooManyWeights {
                kind: "identity",
                given: 3,
                available: 2
            })
        ));
        assert!(matches!(
            m.sample(&[], &[0.0; 4]),
            Err(FaceModelError::TooManyWeights {
                kind: "expression",
                ..
            })
        ));
        assert!(matches!(
            m.sample(&[f64::NAN], &[]),
            Err(FaceModelError::Geometry(_))
        ));
        assert!(matches!(
            m.landmark_id("chin"),
            Err(FaceModelError::UnknownLandmark { .. })
        ));
        assert!(matches!(
            m.recipe_weights("sob", 1.0),
            Err(FaceModelError::UnknownRecipe { .. })
        ));
        let lm = m.landmark_positions(&face).unwrap();
        assert_eq!(lm[3], face.position(2));
        assert_eq!(lm[4], face.position(3));
    }

    #[test]
    fn sampling_is_deterministic_under_a_seed() {
        let m = FaceModel::load(&write_model("seed")).unwrap();
        let draw = |seed: u64| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let id = m.random_identity(&mut rng);
            let ex = m.random_expression(&mut rng);
            let pose = random_rigid_motion(&mut rng, 10.0);
            let face = m.sample(&id, &ex).unwrap().transformed(&pose);
            (id, ex, pose, face)
        };
        let a = draw(7);
        let b = draw(7);
        assert_eq!(a, b);
        assert_ne!(a.0, draw(8).0);
        assert_eq!(a.0.len(), 2);
        for seed in 0..200 {
            let (_, ex, _, _) = draw(seed);
            assert!(ex.iter().all(|w| (0.0..=1.0).contains(w)), "{ex:?}");
        }
    }

    #[test]
    fn random_faces_draw_identity_then_expressions_first_neutral() {
        let m = FaceModel::load(&write_model("faces")).unwrap();
        let faces = m.random_faces(&mut ChaCha8Rng::seed_from_u64(3), 2, 3);
        // The same stream drawn by hand, in the same order.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for (w, ex) in &faces {
            assert_eq!(*w, m.random_identity(&mut rng));
            assert!(ex[0].is_empty() && ex.len() == 3);
            for e in &ex[1..] {
                assert_eq!(*e, m.random_expression(&mut rng));
            }
        }
        assert_eq!(faces.len(), 2);
        assert_ne!(faces[0].0, faces[1].0);
    }

    #[test]
    fn random_rigid_motions_are_rotations() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut mean_t = DVec3::ZERO;
        for _ in 0..500 {
            let m = random_rigid_motion(&mut rng, 2.0);
            let r = m.matrix3;
            let rtr = r.transpose() * r;
            for (c, e) in
                [rtr.x_axis, rtr.y_axis, rtr.z_axis]
                    .iter()
                    .zip([DVec3::X, DVec3::Y, DVec3::Z])
            {
                assert!((*c - e).length() < 1e-12, "R^T R = {rtr}");
            }
            assert!((r.determinant() - 1.0).abs() < 1e-12);
            mean_t += m.translation / 500.0;
        }
        // Translations are N(0, 2^2) per axis: the mean of 500 is within 5 standard errors.
        assert!(
            mean_t.abs().max_element() < 5.0 * 2.0 / 500f64.sqrt(),
            "{mean_t}"
        );
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pure = random_rigid_motion(&mut rng, 0.0);
        assert_eq!(pure.translation, DVec3::ZERO);
    }

    #[test]
    fn standard_normal_has_unit_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let x: Vec<f64> = (0..20_000).map(|_| standard_normal(&mut rng)).collect();
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
        assert!(x.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn malformed_npy_files_are_named() {
        let cases: [(&str, Vec<u8>); 4] = [
            ("not npy", b"hello world, not an array".to_vec()),
            ("truncated", npy(&[2, 4, 3], &[0.0; 23])),
            ("shape", npy(&[2, 5, 3], &[0.0; 30])),
            ("dtype", {
                let mut b = npy(&[2, 4, 3], &[0.0; 24]);
                let at = b.windows(3).position(|w| w == b"<f4").unwrap();
                b[at + 1] = b'i';
                b
            }),
        ];
        for (what, bytes) in cases {
            let dir = write_model(&format!("npy-{}", what.replace(' ', "-")));
            let path = dir.join("identities.npy");
            std::fs::write(&path, bytes).unwrap();
            let e = FaceModel::load(&dir).unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains("identities.npy"), "{what}: {msg}");
            match (what, &e) {
                ("shape", FaceModelError::NpyShape { path: p, shape, .. }) => {
                    assert_eq!((p, shape.as_slice()), (&path, &[2, 5, 3][..]));
                }
                ("shape", _) => panic!("{what}: {e:?}"),
                (_, FaceModelError::Npy { path: p, .. }) => assert_eq!(p, &path),
                _ => panic!("{what}: {e:?}"),
            }
        }
        // Expression count differing from model.json.
        let dir = write_model("npy-count");
        std::fs::write(dir.join("expressions.npy"), npy(&[2, 4, 3], &[0.0; 24])).unwrap();
        let e = FaceModel::load(&dir).unwrap_err();
        assert!(
            matches!(&e, FaceModelError::NpyShape { expected, .. } if expected.contains("3 expressions")),
            "{e:?}"
        );
        // A missing file keeps the OS error and the path.
        let dir = write_model("npy-missing");
        std::fs::remove_file(dir.join("expressions.npy")).unwrap();
        match FaceModel::load(&dir).unwrap_err() {
            FaceModelError::Io(meshcore::FileError { path, source, .. }) => {
                assert_eq!(path, dir.join("expressions.npy"));
                assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
            }
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn malformed_model_json_names_the_key() {
        for (json, needle) in [
            ("{\"expressions\": [\"a\", ", "line 1"),
            ("{\"units\": \"cm\"}", "`expressions`"),
            ("{\"expressions\": [\"a\", 2, \"c\"]}", "non-string"),
            (
                "{\"expressions\": [\"a\", \"b\", \"c\"], \"landmarks\": {\"nose_tip\": 4}}",
                "`landmarks.nose_tip`",
            ),
            (
                "{\"expressions\": [\"a\", \"b\", \"c\"], \"expression_recipes\": {\"x\": {\"z\": 1}}}",
                "`expression_recipes.x` uses unknown expression z",
            ),
        ] {
            let dir = write_model("json");
            std::fs::write(dir.join("model.json"), json).unwrap();
            let e = FaceModel::load(&dir).unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains("model.json") && msg.contains(needle), "{json}: {msg}");
            assert!(matches!(
                e,
                FaceModelError::Json { .. } | FaceModelError::JsonContent { .. }
            ));
        }
        let dir = write_model("obj");
        std::fs::write(dir.join("neutral.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
        let e = FaceModel::load(&dir).unwrap_err();
        assert!(matches!(e, FaceModelError::Mesh { .. }), "{e:?}");
        assert!(e.to_string().contains("neutral.obj"), "{e}");
    }
}
