//! The generic face model: mean landmark configuration, a mean face surface sample and local
//! surface templates around each landmark, in a canonical frame; learned from training faces.

#![allow(clippy::needless_range_loop)] // Dense small linear algebra reads best with indices.

use crate::curvature::{vertex_curvatures, CurvatureOptions};
use crate::regress::LandmarkRegressor;
use crate::{LandmarkError, LandmarkName};
use meshcore::linalg::{fit_rigid, rigid_inverse};
use meshcore::{DAffine3, DVec3, TriMesh};
use serde::{Deserialize, Serialize};

/// The default model shipped with the crate, trained by `cargo xtask landmarks-eval --write-default`
/// on faces sampled from the ICT FaceKit model (units: cm).
const DEFAULT_MODEL_JSON: &str = include_str!("../data/generic-model.json");

/// Sizes used by training, as fractions of the mean inner-eye-corner distance `d` of the
/// training set (so training is unit-free).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrainOptions {
    /// Curvature fitting radius / d.
    pub curvature_radius: f64,
    /// Grid spacing of the mean face sample / d.
    pub face_spacing: f64,
    /// Radius of the mean face sample around the nose tip / d.
    pub face_radius: f64,
    /// How far below the nose tip the face template reaches / d.
    pub face_below: f64,
    /// Radius of the landmark templates / d.
    pub patch_radius: f64,
    /// Grid spacing of the landmark templates / d.
    pub patch_spacing: f64,
    /// Share of training faces that must cover a grid cell for it to enter a template.
    pub min_coverage: f64,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            curvature_radius: 0.3,
            face_spacing: 0.17,
            face_radius: 2.2,
            face_below: 0.4,
            patch_radius: 0.3,
            patch_spacing: 0.05,
            min_coverage: 0.6,
        }
    }
}

/// Thresholds and sizes used at detection time (model units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DetectParams {
    /// Curvature fitting radius.
    pub curvature_radius: f64,
    /// Curvature signature of the nose tip on training faces.
    pub nose: Signature,
    /// Curvature signature of the inner eye corners on training faces.
    pub eye: Signature,
    /// Non-maximum suppression radius of candidates.
    pub candidate_radius: f64,
    /// Inlier distance of the surface fits.
    pub inlier_distance: f64,
    /// Radius of the local search around each predicted landmark.
    pub search_radius: f64,
    /// Typical RMS residual of the face fit on training faces (confidence scale).
    pub typical_rms: f64,
    /// Typical inlier share of the face fit on training faces.
    pub typical_inliers: f64,
}

/// Mean and spread of the shape index and of the log-curvedness of a landmark on training faces.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Signature {
    /// Mean shape index.
    pub shape_index: f64,
    /// Its standard deviation (floored at 0.08).
    pub shape_index_sd: f64,
    /// Mean of `ln(curvedness)`.
    pub log_curvedness: f64,
    /// Its standard deviation (floored at 0.25).
    pub log_curvedness_sd: f64,
}

impl Signature {
    fn learn(s: &[f64], c: &[f64]) -> Self {
        let ms = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len().max(1) as f64;
            (m, var.sqrt())
        };
        let lc: Vec<f64> = c.iter().map(|x| x.max(1e-12).ln()).collect();
        let (a, b) = ms(s);
        let (e, f) = ms(&lc);
        Self {
            shape_index: a,
            shape_index_sd: b.max(0.08),
            log_curvedness: e,
            log_curvedness_sd: f.max(0.25),
        }
    }

    /// Squared normalised distance of a (shape index, curvedness) pair to the signature.
    pub fn distance2(&self, shape_index: f64, curvedness: f64) -> f64 {
        let a = (shape_index - self.shape_index) / self.shape_index_sd;
        let b = (curvedness.max(1e-12).ln() - self.log_curvedness) / self.log_curvedness_sd;
        a * a + b * b
    }
}

/// Surface template: points and unit normals in the canonical frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Template {
    /// `[x, y, z, nx, ny, nz]` per point (landmark templates: relative to the landmark).
    pub points: Vec<[f64; 6]>,
}

impl Template {
    /// Points and normals as vectors.
    pub fn pairs(&self) -> Vec<(DVec3, DVec3)> {
        self.points
            .iter()
            .map(|p| (DVec3::new(p[0], p[1], p[2]), DVec3::new(p[3], p[4], p[5])))
            .collect()
    }

    /// The farthest a point lies from the origin (for a landmark template: from the landmark).
    pub fn reach(&self) -> f64 {
        self.points
            .iter()
            .map(|p| DVec3::new(p[0], p[1], p[2]).length())
            .fold(0.0, f64::max)
    }
}

/// The generic face model (serialisable to JSON).
///
/// Canonical frame: origin at the mean nose tip, `x` from the subject's right to left outer eye
/// corner, `y` up (towards the eyes), `z = x × y` out of the face.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GenericModel {
    /// Format version (1).
    pub version: u32,
    /// Units of the training data (free text, e.g. `cm`), informative.
    pub units: String,
    /// Number of training faces.
    pub n_training: usize,
    /// Mean landmark positions in [`LandmarkName::ALL`] order.
    pub landmarks: [[f64; 3]; 5],
    /// Mean unit normal at the nose tip.
    pub nose_normal: [f64; 3],
    /// Mean face surface sample around the nose tip.
    pub face: Template,
    /// One template per landmark ([`LandmarkName::ALL`] order), relative to the landmark.
    pub patches: Vec<Template>,
    /// Detection parameters.
    pub params: DetectParams,
    /// Learned landmark offsets from the local depth maps (see [`LandmarkRegressor`]); absent in
    /// models trained without it, which then use the local template search alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub regressor: Option<LandmarkRegressor>,
}

/// Front-most depth map of a triangle mesh along canonical `z` on a square grid.
pub(crate) struct DepthMap {
    pub(crate) x0: f64,
    pub(crate) y0: f64,
    pub(crate) h: f64,
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    pub(crate) z: Vec<f64>,
    n: Vec<DVec3>,
}

impl DepthMap {
    pub(crate) fn new(center: (f64, f64), radius: f64, h: f64) -> Self {
        let k = (radius / h).ceil() as usize;
        let nx = 2 * k + 1;
        Self {
            x0: center.0 - k as f64 * h,
            y0: center.1 - k as f64 * h,
            h,
            nx,
            ny: nx,
            z: vec![f64::NEG_INFINITY; nx * nx],
            n: vec![DVec3::ZERO; nx * nx],
        }
    }

    /// Rasterises the triangles of `mesh` moved by `t`, keeping the largest `z` per node.
    fn rasterise(&mut self, mesh: &TriMesh, t: &DAffine3) {
        let pos: Vec<DVec3> = mesh
            .positions()
            .iter()
            .map(|p| t.transform_point3(*p))
            .collect();
        self.rasterise_moved(&pos, mesh.triangles());
    }

    /// [`DepthMap::rasterise`] on positions already moved to the canonical frame.
    pub(crate) fn rasterise_moved(&mut self, pos: &[DVec3], triangles: &[[u32; 3]]) {
        let xmax = self.x0 + (self.nx - 1) as f64 * self.h;
        let ymax = self.y0 + (self.ny - 1) as f64 * self.h;
        for tri in triangles {
            let [a, b, c] = tri.map(|v| pos[v as usize]);
            let lo = a.min(b).min(c);
            let hi = a.max(b).max(c);
            if hi.x < self.x0 || hi.y < self.y0 || lo.x > xmax || lo.y > ymax {
                continue;
            }
            let nrm = (b - a).cross(c - a);
            let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
            if det.abs() < 1e-300 || nrm.length_squared() == 0.0 {
                continue;
            }
            let nrm = nrm.normalize();
            let i0 = (((lo.x - self.x0) / self.h).ceil().max(0.0)) as usize;
            let i1 = (((hi.x - self.x0) / self.h).floor() as isize).min(self.nx as isize - 1);
            let j0 = (((lo.y - self.y0) / self.h).ceil().max(0.0)) as usize;
            let j1 = (((hi.y - self.y0) / self.h).floor() as isize).min(self.ny as isize - 1);
            if i1 < 0 || j1 < 0 {
                continue;
            }
            for j in j0..=j1 as usize {
                let y = self.y0 + j as f64 * self.h;
                for i in i0..=i1 as usize {
                    let x = self.x0 + i as f64 * self.h;
                    let l1 = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
                    let l2 = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
                    let l0 = 1.0 - l1 - l2;
                    if l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12 {
                        continue;
                    }
                    let z = l0 * a.z + l1 * b.z + l2 * c.z;
                    let k = j * self.nx + i;
                    if z > self.z[k] {
                        self.z[k] = z;
                        self.n[k] = nrm;
                    }
                }
            }
        }
    }
}

/// Accumulates depth maps of several faces into a mean template.
struct DepthAccumulator {
    center: (f64, f64),
    radius: f64,
    h: f64,
    sum_z: Vec<f64>,
    sum_n: Vec<DVec3>,
    count: Vec<u32>,
    faces: usize,
}

impl DepthAccumulator {
    fn new(center: (f64, f64), radius: f64, h: f64) -> Self {
        let m = DepthMap::new(center, radius, h);
        let len = m.z.len();
        Self {
            center,
            radius,
            h,
            sum_z: vec![0.0; len],
            sum_n: vec![DVec3::ZERO; len],
            count: vec![0; len],
            faces: 0,
        }
    }

    fn add(&mut self, mesh: &TriMesh, t: &DAffine3) {
        let mut m = DepthMap::new(self.center, self.radius, self.h);
        m.rasterise(mesh, t);
        for k in 0..m.z.len() {
            if m.z[k].is_finite() {
                self.sum_z[k] += m.z[k];
                self.sum_n[k] += m.n[k];
                self.count[k] += 1;
            }
        }
        self.faces += 1;
    }

    /// Mean points within the radius covered by at least `min_coverage` of the faces, relative
    /// to `origin`.
    fn template(&self, min_coverage: f64, origin: DVec3) -> Template {
        let m = DepthMap::new(self.center, self.radius, self.h);
        let need = ((min_coverage * self.faces as f64).ceil() as u32).max(1);
        let mut points = Vec::new();
        for j in 0..m.ny {
            for i in 0..m.nx {
                let k = j * m.nx + i;
                if self.count[k] < need {
                    continue;
                }
                let x = m.x0 + i as f64 * m.h;
                let y = m.y0 + j as f64 * m.h;
                if (x - self.center.0).hypot(y - self.center.1) > self.radius {
                    continue;
                }
                let z = self.sum_z[k] / self.count[k] as f64;
                let n = self.sum_n[k].normalize_or_zero();
                if n == DVec3::ZERO {
                    continue;
                }
                let p = DVec3::new(x, y, z) - origin;
                points.push([p.x, p.y, p.z, n.x, n.y, n.z]);
            }
        }
        Template { points }
    }
}

fn to_v(a: [f64; 3]) -> DVec3 {
    DVec3::new(a[0], a[1], a[2])
}

/// Nearest vertex of `mesh` to `p` (brute force; training only).
fn nearest_vertex(mesh: &TriMesh, p: DVec3) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (i, q) in mesh.positions().iter().enumerate() {
        let d = (*q - p).length_squared();
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
}

fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    let i = ((v.len() - 1) as f64 * q).round() as usize;
    v[i]
}

impl GenericModel {
    /// The model shipped with the crate (trained on ICT FaceKit faces, cm).
    pub fn default_model() -> Result<Self, LandmarkError> {
        Self::from_json(DEFAULT_MODEL_JSON)
    }

    /// Parses a model from JSON and validates it.
    pub fn from_json(text: &str) -> Result<Self, LandmarkError> {
        let m: Self =
            serde_json::from_str(text).map_err(|e| LandmarkError::InvalidModel(e.to_string()))?;
        m.validate()?;
        Ok(m)
    }

    /// Reads a model file.
    pub fn load(path: &std::path::Path) -> Result<Self, LandmarkError> {
        let text = meshcore::read_text(path)?;
        Self::from_json(&text).map_err(|e| match e {
            LandmarkError::InvalidModel(m) => {
                LandmarkError::InvalidModel(format!("{}: {m}", path.display()))
            }
            e => e,
        })
    }

    /// Serialises the model to JSON (compact, coordinates rounded to 1e-5 model units).
    pub fn to_json(&self) -> String {
        let mut m = self.clone();
        let r = |x: &mut f64| *x = (*x * 1e5).round() / 1e5;
        for t in std::iter::once(&mut m.face).chain(m.patches.iter_mut()) {
            for p in &mut t.points {
                p.iter_mut().for_each(r);
            }
        }
        for l in &mut m.landmarks {
            l.iter_mut().for_each(r);
        }
        if let Some(reg) = &mut m.regressor {
            let r6 = |x: &mut f64| *x = (*x * 1e6).round() / 1e6;
            for p in &mut reg.patches {
                p.mean.iter_mut().for_each(r);
                p.coef.iter_mut().flatten().for_each(r6);
                p.intercept.iter_mut().for_each(r6);
            }
        }
        serde_json::to_string(&m).unwrap_or_default()
    }

    /// Checks the internal consistency (finite numbers, templates present, positive sizes).
    pub fn validate(&self) -> Result<(), LandmarkError> {
        let bad = |m: &str| Err(LandmarkError::InvalidModel(m.to_owned()));
        if self.patches.len() != 5 {
            return bad("the model needs 5 landmark templates");
        }
        if self.face.points.len() < 20 {
            return bad("the face template has fewer than 20 points");
        }
        if self.patches.iter().any(|p| p.points.len() < 10) {
            return bad("a landmark template has fewer than 10 points");
        }
        let finite = self.landmarks.iter().flatten().all(|x| x.is_finite())
            && self
                .face
                .points
                .iter()
                .chain(self.patches.iter().flat_map(|p| p.points.iter()))
                .flatten()
                .all(|x| x.is_finite());
        if !finite {
            return bad("non-finite number in the model");
        }
        let p = &self.params;
        if [
            p.curvature_radius,
            p.candidate_radius,
            p.inlier_distance,
            p.search_radius,
            p.typical_rms,
        ]
        .iter()
        .any(|x| !(x.is_finite() && *x > 0.0))
        {
            return bad("non-positive size parameter in the model");
        }
        if let Some(r) = &self.regressor {
            r.validate()?;
        }
        Ok(())
    }

    /// Mean landmark position in the canonical frame.
    pub fn landmark(&self, name: LandmarkName) -> DVec3 {
        to_v(self.landmarks[name as usize])
    }

    /// Mean inner-eye-corner distance (the model's length unit for relative sizes).
    pub fn eye_distance(&self) -> f64 {
        (self.landmark(LandmarkName::InnerEyeLeft) - self.landmark(LandmarkName::InnerEyeRight))
            .length()
    }

    /// Learns the model from training faces with their landmarks (in [`LandmarkName::ALL`]
    /// order, any pose, units of the meshes) using [`TrainOptions::default`].
    pub fn train(faces: &[(TriMesh, [DVec3; 5])]) -> Result<Self, LandmarkError> {
        Self::train_with(faces, &TrainOptions::default(), "unknown")
    }

    /// [`GenericModel::train`] with explicit options and a units label.
    pub fn train_with(
        faces: &[(TriMesh, [DVec3; 5])],
        opt: &TrainOptions,
        units: &str,
    ) -> Result<Self, LandmarkError> {
        if faces.len() < 2 {
            return Err(LandmarkError::InvalidTraining(format!(
                "{} training faces; at least 2 are needed",
                faces.len()
            )));
        }
        for (i, (_, l)) in faces.iter().enumerate() {
            if l.iter().any(|p| !p.is_finite()) {
                return Err(LandmarkError::InvalidTraining(format!(
                    "face {i}: non-finite landmark"
                )));
            }
        }
        // Generalised Procrustes (rigid) of the landmark sets.
        let mut mean: Vec<DVec3> = faces[0].1.to_vec();
        let mut aligns: Vec<DAffine3> = vec![DAffine3::IDENTITY; faces.len()];
        for _ in 0..5 {
            for (k, (_, l)) in faces.iter().enumerate() {
                aligns[k] = fit_rigid(l, &mean, None).ok_or_else(|| {
                    LandmarkError::InvalidTraining(format!("face {k}: degenerate landmarks"))
                })?;
            }
            let mut acc = [DVec3::ZERO; 5];
            for (k, (_, l)) in faces.iter().enumerate() {
                for (a, p) in acc.iter_mut().zip(l) {
                    *a += aligns[k].transform_point3(*p);
                }
            }
            mean = acc.iter().map(|a| *a / faces.len() as f64).collect();
        }
        // Canonical frame of the mean: x from right to left outer eye corner, z forward (mean
        // area-weighted surface normal around the nose in the aligned faces), y = z × x.
        use LandmarkName as L;
        let nose = mean[L::NoseTip as usize];
        let x = (mean[L::OuterEyeLeft as usize] - mean[L::OuterEyeRight as usize]).normalize();
        let d0 = (mean[L::InnerEyeLeft as usize] - mean[L::InnerEyeRight as usize]).length();
        let mut fwd = DVec3::ZERO;
        for (k, (mesh, _)) in faces.iter().enumerate() {
            for f in 0..mesh.n_faces() as u32 {
                let [a, b, c] = mesh.face_corners(f);
                let g = aligns[k].transform_point3((a + b + c) / 3.0);
                if (g - nose).length() < 2.0 * d0 {
                    fwd += aligns[k].transform_vector3(mesh.face_cross(f));
                }
            }
        }
        let z = (fwd - x * fwd.dot(x)).normalize();
        let y = z.cross(x);
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(LandmarkError::InvalidTraining(
                "degenerate mean landmark configuration or no surface around the nose".into(),
            ));
        }
        // Eyes above the nose (y up); if not, the surface normals point into the head.
        let eyes_mid = mean[..4].iter().copied().sum::<DVec3>() / 4.0;
        if (eyes_mid - nose).dot(y) <= 0.0 {
            return Err(LandmarkError::InvalidTraining(
                "eyes below the nose in the normal-based frame: training meshes need outward normals"
                    .into(),
            ));
        }
        let rot = meshcore::DMat3::from_cols(x, y, z).transpose();
        let to_canon = DAffine3::from_mat3_translation(rot, -(rot * nose));
        let canon: Vec<DVec3> = mean.iter().map(|p| to_canon.transform_point3(*p)).collect();
        let aligns: Vec<DAffine3> = aligns.iter().map(|a| to_canon * *a).collect();
        let d = (canon[L::InnerEyeLeft as usize] - canon[L::InnerEyeRight as usize]).length();
        if !(d.is_finite() && d > 0.0) {
            return Err(LandmarkError::InvalidTraining(
                "inner eye corners coincide".into(),
            ));
        }
        // Depth templates.
        let mut face_acc =
            DepthAccumulator::new((0.0, 0.0), opt.face_radius * d, opt.face_spacing * d);
        let mut patch_acc: Vec<DepthAccumulator> = canon
            .iter()
            .map(|c| DepthAccumulator::new((c.x, c.y), opt.patch_radius * d, opt.patch_spacing * d))
            .collect();
        // Curvature statistics at the landmarks.
        let rho = opt.curvature_radius * d;
        let mut nose_s = Vec::new();
        let mut nose_c = Vec::new();
        let mut eye_s = Vec::new();
        let mut eye_c = Vec::new();
        let mut nose_n = DVec3::ZERO;
        for (k, (mesh, l)) in faces.iter().enumerate() {
            let a = &aligns[k];
            face_acc.add(mesh, a);
            for p in patch_acc.iter_mut() {
                p.add(mesh, a);
            }
            let curv = vertex_curvatures(mesh, &CurvatureOptions::with_radius(rho));
            let vn = nearest_vertex(mesh, l[L::NoseTip as usize]);
            nose_s.push(curv[vn].shape_index());
            nose_c.push(curv[vn].curvedness());
            nose_n += a.transform_vector3(curv[vn].normal);
            for e in [L::InnerEyeRight, L::InnerEyeLeft] {
                let ve = nearest_vertex(mesh, l[e as usize]);
                eye_s.push(curv[ve].shape_index());
                eye_c.push(curv[ve].curvedness());
            }
        }
        // The face template keeps the upper face (above the upper lip: nose, eyes, cheeks,
        // forehead), which moves little with expressions.
        let mut face = face_acc.template(opt.min_coverage, DVec3::ZERO);
        face.points.retain(|p| p[1] > -opt.face_below * d);
        let patches: Vec<Template> = patch_acc
            .iter()
            .zip(&canon)
            .map(|(acc, c)| {
                // Depth templates are relative to the landmark; use its mean depth.
                acc.template(opt.min_coverage, *c)
            })
            .collect();
        let params = DetectParams {
            curvature_radius: rho,
            nose: Signature::learn(&nose_s, &nose_c),
            eye: Signature::learn(&eye_s, &eye_c),
            candidate_radius: 0.25 * d,
            inlier_distance: 0.1 * d,
            search_radius: 0.25 * d,
            typical_rms: 0.02 * d,
            typical_inliers: 0.9,
        };
        let mut model = Self {
            version: 1,
            units: units.to_owned(),
            n_training: faces.len(),
            landmarks: [0, 1, 2, 3, 4].map(|i| canon[i].to_array()),
            nose_normal: nose_n.normalize_or_zero().to_array(),
            face,
            patches,
            params,
            regressor: None,
        };
        model.validate()?;
        // Typical fit quality on the training faces themselves.
        let mut rms = Vec::new();
        let mut inl = Vec::new();
        for (k, (mesh, _)) in faces.iter().enumerate() {
            let idx = crate::detect::surface_index(mesh);
            let inv = rigid_inverse(&aligns[k]);
            let s = crate::geom::score(
                &idx,
                &model.face.pairs(),
                &inv,
                model.params.inlier_distance,
                0.5,
            );
            rms.push(s.rms);
            inl.push(s.inlier_fraction);
        }
        model.params.typical_rms = quantile(&mut rms, 0.5).max(1e-3 * d);
        model.params.typical_inliers = quantile(&mut inl, 0.5);
        Ok(model)
    }
}
