//! The ICT FaceKit morphable face model (`<shared>/faces/ict-facekit/model/`): loading and
//! sampling random faces.
//!
//! Files: `neutral.obj` (6,706 vertices, 13,120 triangles, cm), `identities.npy` (float32,
//! shape `(100, 6706, 3)`), `expressions.npy` (float32, shape `(27, 6706, 3)`) and `model.json`
//! (expression names, expression recipes, landmark vertex ids). A face is
//! `neutral + sum_i w_i * identities[i] + sum_j e_j * expressions[j]`, with `w_i ~ N(0, 1)` for a
//! plausible person and `e_j` in `[0, 1]`.
//!
//! Reusable by every experiment: [`FaceModel::load`], [`FaceModel::sample`],
//! [`FaceModel::random_identity`], [`FaceModel::random_expression`],
//! [`FaceModel::recipe_weights`], [`random_rigid_motion`], [`shared_dir`].

#![allow(dead_code)] // A library module: not every experiment uses every function.

use anyhow::{anyhow, bail, Context, Result};
use meshcore::{DAffine3, DQuat, DVec3, TriMesh};
use rand::Rng;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The shared data folder: `$BIPOLAR_SHARED` if set, else `../shared` relative to the workspace
/// root (the parent of `xtask/`).
pub fn shared_dir() -> PathBuf {
    if let Some(p) = std::env::var_os("BIPOLAR_SHARED") {
        return PathBuf::from(p);
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap_or(Path::new("."));
    root.join("..").join("shared")
}

/// Default location of the ICT model folder inside [`shared_dir`].
pub fn default_model_dir() -> PathBuf {
    shared_dir().join("faces").join("ict-facekit").join("model")
}

/// Names of the five landmarks of the model, in the order used by the experiments.
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
    /// Loads the model folder (see the module documentation for the files).
    pub fn load(dir: &Path) -> Result<Self> {
        let (neutral, triangles) = read_obj(&dir.join("neutral.obj"))?;
        let n = neutral.len();
        let json_path = dir.join("model.json");
        let text = std::fs::read_to_string(&json_path)
            .with_context(|| format!("reading {}", json_path.display()))?;
        let meta: serde_json::Value = serde_json::from_str(&text)
            .with_context(|| format!("parsing {}", json_path.display()))?;
        let expression_names: Vec<String> = meta["expressions"]
            .as_array()
            .ok_or_else(|| anyhow!("{}: no `expressions` array", json_path.display()))?
            .iter()
            .map(|v| v.as_str().map(str::to_owned))
            .collect::<Option<_>>()
            .ok_or_else(|| anyhow!("{}: non-string expression name", json_path.display()))?;
        let mut landmarks = BTreeMap::new();
        if let Some(obj) = meta["landmarks"].as_object() {
            for (k, v) in obj {
                let id = v
                    .as_u64()
                    .filter(|&id| (id as usize) < n)
                    .ok_or_else(|| anyhow!("{}: bad landmark id for {k}", json_path.display()))?;
                landmarks.insert(k.clone(), id as u32);
            }
        }
        let mut recipes = BTreeMap::new();
        if let Some(obj) = meta["expression_recipes"].as_object() {
            for (name, r) in obj {
                let mut m = BTreeMap::new();
                for (k, v) in r.as_object().into_iter().flatten() {
                    if !expression_names.contains(k) {
                        bail!("{}: recipe {name} uses unknown {k}", json_path.display());
                    }
                    m.insert(k.clone(), v.as_f64().unwrap_or(0.0));
                }
                recipes.insert(name.clone(), m);
            }
        }
        let units = meta["units"].as_str().unwrap_or("cm").to_owned();
        let (id_shape, id_data) = read_npy_f32(&dir.join("identities.npy"))?;
        let (ex_shape, ex_data) = read_npy_f32(&dir.join("expressions.npy"))?;
        for (name, shape) in [("identities", &id_shape), ("expressions", &ex_shape)] {
            if shape.len() != 3 || shape[1] != n || shape[2] != 3 {
                bail!("{name}.npy has shape {shape:?}, expected (k, {n}, 3)");
            }
        }
        if ex_shape[0] != expression_names.len() {
            bail!(
                "expressions.npy has {} blendshapes but model.json names {}",
                ex_shape[0],
                expression_names.len()
            );
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

    /// Names of the expression recipes of `model.json` (e.g. `happiness`).
    pub fn recipe_names(&self) -> impl Iterator<Item = &str> {
        self.recipes.keys().map(String::as_str)
    }

    /// Landmark name -> vertex id (`right_eye_outer`, `right_eye_inner`, `left_eye_inner`,
    /// `left_eye_outer`, `nose_tip`; "right" is the subject's right, at negative x).
    pub fn landmark_ids(&self) -> &BTreeMap<String, u32> {
        &self.landmarks
    }

    /// Vertex id of a named landmark.
    pub fn landmark_id(&self, name: &str) -> Result<u32> {
        self.landmarks
            .get(name)
            .copied()
            .ok_or_else(|| anyhow!("the face model has no landmark named {name}"))
    }

    /// Units of the coordinates (`cm`).
    pub fn units(&self) -> &str {
        &self.units
    }

    /// The neutral face.
    pub fn neutral(&self) -> Result<TriMesh> {
        Ok(TriMesh::new(self.neutral.clone(), self.triangles.clone())?)
    }

    /// Expression weights of a named recipe (e.g. `happiness`), scaled by `strength`.
    pub fn recipe_weights(&self, name: &str, strength: f64) -> Result<Vec<f64>> {
        let r = self
            .recipes
            .get(name)
            .ok_or_else(|| anyhow!("no expression recipe named {name}"))?;
        Ok(self
            .expression_names
            .iter()
            .map(|e| r.get(e).copied().unwrap_or(0.0) * strength)
            .collect())
    }

    /// `neutral + sum_i w_i identities[i] + sum_j e_j expressions[j]`. Shorter weight slices use
    /// the leading components only; longer ones are an error.
    pub fn sample(&self, identity_weights: &[f64], expression_weights: &[f64]) -> Result<TriMesh> {
        if identity_weights.len() > self.n_identities {
            bail!(
                "{} identity weights for a model of {} identities",
                identity_weights.len(),
                self.n_identities
            );
        }
        if expression_weights.len() > self.n_expressions() {
            bail!(
                "{} expression weights for a model of {} expressions",
                expression_weights.len(),
                self.n_expressions()
            );
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

    /// Positions of the named landmarks on a sampled (possibly moved) face, in
    /// [`LANDMARK_NAMES`] order.
    pub fn landmark_positions(&self, mesh: &TriMesh) -> Result<[DVec3; 5]> {
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

/// Reads a Wavefront OBJ file with `mesh_io` (the project's one OBJ reader: `v` and `f`
/// lines, polygons fan-triangulated, `v/vt/vn` and negative indices accepted): positions and
/// triangles.
pub fn read_obj(path: &Path) -> Result<(Vec<DVec3>, Vec<[u32; 3]>)> {
    let loaded = mesh_io::read_mesh(path).with_context(|| format!("reading {}", path.display()))?;
    Ok((
        loaded.mesh.positions().to_vec(),
        loaded.mesh.triangles().to_vec(),
    ))
}

/// Reads a little-endian float32 C-order `.npy` file with `mesh_io` (the project's one `.npy`
/// reader): shape and data.
pub fn read_npy_f32(path: &Path) -> Result<(Vec<usize>, Vec<f32>)> {
    mesh_io::read_npy_f32(path).with_context(|| format!("reading {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// FNV-1a (64 bit) over the little-endian bytes of every vertex coordinate, in vertex order.
    fn digest(mesh: &TriMesh) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for p in mesh.positions() {
            for c in p.to_array() {
                for b in c.to_bits().to_le_bytes() {
                    h ^= u64::from(b);
                    h = h.wrapping_mul(0x0000_0100_0000_01b3);
                }
            }
        }
        h
    }

    #[test]
    fn pin_sampled_faces() {
        let dir = default_model_dir();
        if !dir.is_dir() {
            eprintln!("skipping: {} not found", dir.display());
            return;
        }
        let model = FaceModel::load(&dir).unwrap();
        let pinned = [
            (1u64, 0xc6c4_0fbc_7305_1b7b_u64),
            (2, 0x17f1_0dfd_dc75_13db),
            (3, 0x3ace_7802_7c93_f4bb),
        ];
        for (seed, want) in pinned {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let id = model.random_identity(&mut rng);
            let ex = model.random_expression(&mut rng);
            let pose = random_rigid_motion(&mut rng, 10.0);
            let face = model.sample(&id, &ex).unwrap().transformed(&pose);
            assert_eq!(digest(&face), want, "seed {seed}: {:#018x}", digest(&face));
        }
        assert_eq!(digest(&model.neutral().unwrap()), 0xd6b5_da21_6777_0c29);
    }

    #[test]
    fn pin_obj_reader() {
        let shared = shared_dir();
        let mut files = vec![shared.join("faces/ict-facekit/model/neutral.obj")];
        let ps = shared.join("faces/ict-facekit/paper-set");
        if !ps.is_dir() {
            return;
        }
        let mut v: Vec<_> = std::fs::read_dir(&ps)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "obj"))
            .collect();
        v.sort();
        files.extend(v);
        for f in files {
            let a = crate::experiments::data::parse_obj(&std::fs::read_to_string(&f).unwrap())
                .unwrap();
            let b = mesh_io::read_mesh(&f).unwrap();
            assert!(b.warnings.is_empty(), "{:?}", b.warnings);
            let same_pos = a.positions().len() == b.mesh.positions().len()
                && a
                    .positions()
                    .iter()
                    .zip(b.mesh.positions())
                    .all(|(x, y)| x.to_array().map(f64::to_bits) == y.to_array().map(f64::to_bits));
            assert!(same_pos, "{}", f.display());
            assert_eq!(a.triangles(), b.mesh.triangles(), "{}", f.display());
            println!("{}: identical ({} vertices)", f.display(), a.n_vertices());
        }
    }
}
