//! Learned landmark offsets: a ridge regression from the depth map around each landmark, in the
//! canonical frame of the fitted pose, to the landmark's position in that frame.
//!
//! The rigid generic face predicts every landmark at its mean position; the real position moves
//! with the identity (wider or narrower eyes) and the expression (squints, smiles), and the local
//! template search finds a weak feature such as the outer eye corner only within a few
//! millimetres (it slides along the eyelid). The depth map around the landmark, resampled on a
//! fixed grid of the canonical frame, carries that information linearly enough for a ridge
//! regression: trained on faces with known landmarks and the poses the detector fitted to them
//! (so the pose errors of detection are in the training data), it maps the depth values (and
//! which grid nodes saw no surface, e.g. the eye openings of a mesh) to the landmark's offset.

#![allow(clippy::needless_range_loop)] // Dense small linear algebra reads best with indices.

use crate::model::{DepthMap, GenericModel};
use crate::{LandmarkError, LandmarkName};
use meshcore::linalg::rigid_inverse;
use meshcore::{DAffine3, DVec3, TriMesh};
use serde::{Deserialize, Serialize};

/// Options of [`LandmarkRegressor::train`]; sizes are fractions of the model's mean inner-eye
/// distance `d`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RegressorOptions {
    /// Radius of the depth patch around each landmark / d.
    pub radius: f64,
    /// Grid spacing of the depth patch / d.
    pub spacing: f64,
    /// Ridge penalty relative to the mean diagonal of the normal matrix.
    pub ridge: f64,
    /// Extra training samples per face with the fitted pose moved by a small random rigid
    /// motion (deterministic).
    #[serde(default)]
    pub perturbations: usize,
    /// Standard deviation of the rotation angle of those motions (degrees).
    #[serde(default)]
    pub perturb_angle_deg: f64,
    /// Standard deviation of each translation coordinate of those motions / d.
    #[serde(default)]
    pub perturb_shift: f64,
}

impl Default for RegressorOptions {
    fn default() -> Self {
        Self {
            radius: 0.6,
            spacing: 0.08,
            ridge: 0.1,
            perturbations: 0,
            perturb_angle_deg: 2.0,
            perturb_shift: 0.04,
        }
    }
}

/// The regression of one landmark.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegressorPatch {
    /// Patch centre in the canonical frame (the model's mean landmark).
    pub center: [f64; 3],
    /// Patch radius (model units).
    pub radius: f64,
    /// Grid spacing (model units).
    pub spacing: f64,
    /// Grid nodes used (row-major indices of the square grid of the patch, within the radius).
    pub cells: Vec<u32>,
    /// Mean feature per input (depths relative to the centre, then the missing-surface
    /// indicators, one of each per cell); a missing depth takes its mean value.
    pub mean: Vec<f64>,
    /// Coefficients, one `[x, y, z]` per input.
    pub coef: Vec<[f64; 3]>,
    /// Mean offset of the landmark from the centre on the training faces.
    pub intercept: [f64; 3],
}

/// Learned offsets of the five landmarks ([`LandmarkName::ALL`] order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LandmarkRegressor {
    /// Training faces used.
    pub n_training: usize,
    /// Options it was trained with.
    pub options: RegressorOptions,
    /// One regression per landmark.
    pub patches: Vec<RegressorPatch>,
}

/// Depth map of the grid of a patch: per cell, the depth relative to the centre or `None`.
fn patch_depths(canon: &[DVec3], triangles: &[[u32; 3]], p: &RegressorPatch) -> Vec<Option<f64>> {
    let mut m = DepthMap::new((p.center[0], p.center[1]), p.radius, p.spacing);
    m.rasterise_moved(canon, triangles);
    p.cells
        .iter()
        .map(|&k| {
            let z = m.z.get(k as usize).copied().unwrap_or(f64::NEG_INFINITY);
            z.is_finite().then_some(z - p.center[2])
        })
        .collect()
}

/// Cells of the square grid of `DepthMap::new(center, radius, spacing)` within the radius.
fn grid_cells(center: (f64, f64), radius: f64, spacing: f64) -> Vec<u32> {
    let m = DepthMap::new(center, radius, spacing);
    let mut out = Vec::new();
    for j in 0..m.ny {
        for i in 0..m.nx {
            let x = m.x0 + i as f64 * m.h;
            let y = m.y0 + j as f64 * m.h;
            if (x - center.0).hypot(y - center.1) <= radius {
                out.push((j * m.nx + i) as u32);
            }
        }
    }
    out
}

/// Raw inputs of a patch: depths (missing: NaN) then indicators.
fn raw_inputs(depths: &[Option<f64>]) -> Vec<f64> {
    let mut x: Vec<f64> = depths.iter().map(|d| d.unwrap_or(f64::NAN)).collect();
    x.extend(depths.iter().map(|d| if d.is_some() { 0.0 } else { 1.0 }));
    x
}

/// Solves `a x = b` for a symmetric positive definite `a` (n x n, row-major) with several
/// right-hand sides `b` (n x 3) by Cholesky; `None` when `a` is not positive definite.
fn cholesky_solve(mut a: Vec<f64>, n: usize, mut b: Vec<[f64; 3]>) -> Option<Vec<[f64; 3]>> {
    for j in 0..n {
        let mut s = a[j * n + j];
        for k in 0..j {
            s -= a[j * n + k] * a[j * n + k];
        }
        if !(s > 0.0 && s.is_finite()) {
            return None;
        }
        let l = s.sqrt();
        a[j * n + j] = l;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / l;
        }
    }
    for c in 0..3 {
        for i in 0..n {
            let mut s = b[i][c];
            for k in 0..i {
                s -= a[i * n + k] * b[k][c];
            }
            b[i][c] = s / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = b[i][c];
            for k in i + 1..n {
                s -= a[k * n + i] * b[k][c];
            }
            b[i][c] = s / a[i * n + i];
        }
    }
    Some(b)
}

/// A deterministic pseudo-random rigid motion: rotation by an angle with standard deviation
/// `angle` about a random axis through the origin, then a translation with standard deviation
/// `shift` per coordinate (splitmix64 and Box-Muller on `seed`).
fn perturbation(seed: u64, angle: f64, shift: f64) -> DAffine3 {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
    let mut uniform = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut normal = || {
        let (u, v) = (uniform(), uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let axis = DVec3::new(normal(), normal(), normal()).normalize_or_zero();
    let a = angle * normal();
    let r = if axis == DVec3::ZERO {
        meshcore::DMat3::IDENTITY
    } else {
        meshcore::DMat3::from_axis_angle(axis, a)
    };
    let t = DVec3::new(normal(), normal(), normal()) * shift;
    DAffine3::from_mat3_translation(r, t)
}

impl LandmarkRegressor {
    /// Trains the regression on faces with their true landmarks ([`LandmarkName::ALL`] order)
    /// and the model-to-mesh poses the detector fitted to them (as in
    /// [`crate::Landmarks::model_to_mesh`]; meshes in the model's units). Faces whose pose is
    /// wrong (some landmark farther than half the inner-eye distance from its prediction) are
    /// left out. Needs at least 10 usable faces.
    pub fn train(
        model: &GenericModel,
        samples: &[(&TriMesh, [DVec3; 5], DAffine3)],
        opt: &RegressorOptions,
    ) -> Result<Self, LandmarkError> {
        let d = model.eye_distance();
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if !(ok(opt.radius)
            && ok(opt.spacing)
            && ok(opt.ridge)
            && opt.radius > 0.0
            && opt.spacing > 0.0)
        {
            return Err(LandmarkError::InvalidOption(format!(
                "regressor options must be positive and finite: {opt:?}"
            )));
        }
        let mut patches: Vec<RegressorPatch> = LandmarkName::ALL
            .iter()
            .map(|&n| {
                let c = model.landmark(n);
                RegressorPatch {
                    center: c.to_array(),
                    radius: opt.radius * d,
                    spacing: opt.spacing * d,
                    cells: grid_cells((c.x, c.y), opt.radius * d, opt.spacing * d),
                    mean: Vec::new(),
                    coef: Vec::new(),
                    intercept: [0.0; 3],
                }
            })
            .collect();
        // Inputs and targets per landmark.
        let mut xs: Vec<Vec<Vec<f64>>> = vec![Vec::new(); 5];
        let mut ys: Vec<Vec<DVec3>> = vec![Vec::new(); 5];
        let mut used = 0;
        for (mesh, truth, pose) in samples {
            let inv = rigid_inverse(pose);
            let canon_truth = truth.map(|p| inv.transform_point3(p));
            let wrong = LandmarkName::ALL
                .iter()
                .any(|&n| (canon_truth[n as usize] - model.landmark(n)).length() > 0.5 * d);
            if wrong || !canon_truth.iter().all(|p| p.is_finite()) {
                continue;
            }
            used += 1;
            let canon: Vec<DVec3> = mesh
                .positions()
                .iter()
                .map(|p| inv.transform_point3(*p))
                .collect();
            // The detected pose, then the same pose moved by small random rigid motions about
            // the nose tip (canonical origin): the regression then learns to correct pose errors
            // too, not only the offsets seen under the detector's typical pose error.
            for j in 0..=opt.perturbations {
                let delta = if j == 0 {
                    DAffine3::IDENTITY
                } else {
                    perturbation(
                        (used as u64) << 16 | j as u64,
                        opt.perturb_angle_deg.to_radians(),
                        opt.perturb_shift * d,
                    )
                };
                let di = rigid_inverse(&delta);
                let moved: Vec<DVec3> = canon.iter().map(|p| di.transform_point3(*p)).collect();
                for (k, p) in patches.iter().enumerate() {
                    xs[k].push(raw_inputs(&patch_depths(&moved, mesh.triangles(), p)));
                    ys[k].push(di.transform_point3(canon_truth[k]) - DVec3::from_array(p.center));
                }
            }
        }
        if used < 10 {
            return Err(LandmarkError::InvalidTraining(format!(
                "{used} faces with a correct pose; the landmark regression needs at least 10"
            )));
        }
        for (k, p) in patches.iter_mut().enumerate() {
            let rows = &mut xs[k];
            let m = rows[0].len();
            // Means (depths over the faces that saw a surface), then centred inputs.
            let mut mean = vec![0.0; m];
            let mut cnt = vec![0usize; m];
            for r in rows.iter() {
                for i in 0..m {
                    if r[i].is_finite() {
                        mean[i] += r[i];
                        cnt[i] += 1;
                    }
                }
            }
            for i in 0..m {
                mean[i] = if cnt[i] > 0 {
                    mean[i] / cnt[i] as f64
                } else {
                    0.0
                };
            }
            for r in rows.iter_mut() {
                for i in 0..m {
                    r[i] = if r[i].is_finite() {
                        r[i] - mean[i]
                    } else {
                        0.0
                    };
                }
            }
            let ymean = ys[k].iter().copied().sum::<DVec3>() / ys[k].len() as f64;
            // Normal equations with a ridge.
            let mut a = vec![0.0; m * m];
            let mut b = vec![[0.0; 3]; m];
            for (r, y) in rows.iter().zip(&ys[k]) {
                let yc = *y - ymean;
                for i in 0..m {
                    if r[i] == 0.0 {
                        continue;
                    }
                    for j in 0..m {
                        a[i * m + j] += r[i] * r[j];
                    }
                    b[i][0] += r[i] * yc.x;
                    b[i][1] += r[i] * yc.y;
                    b[i][2] += r[i] * yc.z;
                }
            }
            let diag = (0..m).map(|i| a[i * m + i]).sum::<f64>() / m as f64;
            let lambda = opt.ridge * diag.max(1e-12);
            for i in 0..m {
                a[i * m + i] += lambda;
            }
            let coef = cholesky_solve(a, m, b).ok_or_else(|| {
                LandmarkError::InvalidTraining("singular landmark regression".into())
            })?;
            p.mean = mean;
            p.coef = coef;
            p.intercept = ymean.to_array();
        }
        Ok(Self {
            n_training: used,
            options: *opt,
            patches,
        })
    }

    /// Checks the internal consistency (5 patches, matching lengths, finite numbers).
    pub fn validate(&self) -> Result<(), LandmarkError> {
        let bad = |m: &str| {
            Err(LandmarkError::InvalidModel(format!(
                "landmark regressor: {m}"
            )))
        };
        if self.patches.len() != 5 {
            return bad("needs 5 patches");
        }
        for p in &self.patches {
            if !(p.radius > 0.0 && p.spacing > 0.0 && p.radius.is_finite() && p.spacing.is_finite())
            {
                return bad("non-positive patch size");
            }
            if p.radius / p.spacing > 200.0 {
                return bad("patch grid too fine");
            }
            let n = grid_cells((p.center[0], p.center[1]), p.radius, p.spacing).len();
            if p.cells.len() != n || p.mean.len() != 2 * n || p.coef.len() != 2 * n {
                return bad("patch sizes do not match");
            }
            let finite = p.center.iter().chain(&p.intercept).all(|x| x.is_finite())
                && p.mean.iter().all(|x| x.is_finite())
                && p.coef.iter().flatten().all(|x| x.is_finite());
            if !finite {
                return bad("non-finite number");
            }
        }
        Ok(())
    }

    /// Predicted landmark positions in the canonical frame, for a mesh (model units) and its
    /// fitted model-to-mesh pose. A patch cell without surface where the training faces (almost)
    /// always had one ([`UNSEEN_RATE`]: a turned head hiding the far eye corner's surroundings,
    /// a dropout, a hole) is outside what the regression learned; its inputs take their
    /// training means, so the landmark is regressed from the cells that were seen. `None` for a
    /// landmark with more than [`UNSEEN_GAP_SHARE`] of its cells unseen (the caller keeps its
    /// template search). Only for a scan (`scan`): on a mesh a cell without surface is shape (an
    /// eye opening), and every landmark is regressed from all its inputs.
    pub(crate) fn predict(
        &self,
        mesh: &TriMesh,
        pose: &DAffine3,
        scan: bool,
    ) -> [Option<DVec3>; 5] {
        use rayon::prelude::*;
        let inv = rigid_inverse(pose);
        let canon: Vec<DVec3> = mesh
            .positions()
            .par_iter()
            .with_min_len(4096)
            .map(|p| inv.transform_point3(*p))
            .collect();
        // The landmarks are independent: in parallel, collected in order.
        let found: Vec<Option<DVec3>> = self
            .patches
            .par_iter()
            .take(5)
            .map(|p| {
                let x = raw_inputs(&patch_depths(&canon, mesh.triangles(), p));
                let n = p.cells.len();
                // Cells without surface where the training faces had one carry no information
                // the regression learned: both their inputs take the training mean.
                let unseen: Vec<bool> = (0..n)
                    .map(|i| scan && !x[i].is_finite() && p.mean[n + i] < UNSEEN_RATE)
                    .collect();
                if unseen.iter().filter(|&&u| u).count() as f64 > UNSEEN_GAP_SHARE * n as f64 {
                    return None;
                }
                let mut off = DVec3::from_array(p.intercept);
                for (i, (&xi, c)) in x.iter().zip(&p.coef).enumerate() {
                    let v = if xi.is_finite() && !unseen[i % n] {
                        xi - p.mean[i]
                    } else {
                        0.0
                    };
                    off += DVec3::from_array(*c) * v;
                }
                Some(DVec3::from_array(p.center) + off)
            })
            .collect();
        let mut out = [None; 5];
        for (o, f) in out.iter_mut().zip(found) {
            *o = f;
        }
        out
    }
}

/// A patch cell counts as unseen in training when fewer than this share of the training faces
/// had no surface there.
const UNSEEN_RATE: f64 = 0.05;

/// Largest share of a patch's cells that may lack the surface the training faces had there
/// before [`LandmarkRegressor::predict`] declines to regress the landmark. Chosen on 30 scanned
/// test faces at yaw 0 and +-35 degrees (0.05, 0.3, 1): see `docs/landmarks.md`.
const UNSEEN_GAP_SHARE: f64 = 0.3;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_known_system() {
        // a = [[4, 2], [2, 3]], x = [[1, 0, -1], [2, 1, 0.5]]
        let a = vec![4.0, 2.0, 2.0, 3.0];
        let b = vec![[8.0, 2.0, -3.0], [8.0, 3.0, -0.5]];
        let x = cholesky_solve(a, 2, b).unwrap();
        for (got, want) in x.iter().zip([[1.0, 0.0, -1.0], [2.0, 1.0, 0.5]]) {
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() < 1e-12, "{got:?} vs {want:?}");
            }
        }
        assert!(cholesky_solve(vec![1.0, 2.0, 2.0, 1.0], 2, vec![[1.0; 3]; 2]).is_none());
    }

    /// A height field in the canonical frame with a Gaussian bump at every landmark of the model,
    /// each moved by `shift`: the landmark is where its bump is (at the model's depth; depths
    /// enter the regression relative to the patch centre).
    fn bumpy(model: &GenericModel, shift: [DVec3; 5]) -> (TriMesh, [DVec3; 5]) {
        let (n, h) = (90usize, 0.14);
        let truth = LandmarkName::ALL.map(|l| model.landmark(l) + shift[l as usize]);
        let mut pos = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (-6.3 + i as f64 * h, -4.0 + j as f64 * h);
                let z: f64 = truth
                    .iter()
                    .map(|c| 0.6 * (-((x - c.x).powi(2) + (y - c.y).powi(2)) / 0.3).exp())
                    .sum();
                pos.push(DVec3::new(x, y, z));
            }
        }
        let mut tri = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
                tri.push([a, b, d]);
                tri.push([a, d, c]);
            }
        }
        (TriMesh::new(pos, tri).unwrap(), truth)
    }

    /// Face `s`'s deterministic landmark shifts in the plane, up to 0.3 model units (3 mm).
    fn shift(s: usize) -> [DVec3; 5] {
        LandmarkName::ALL.map(|l| {
            let a = (s * 7 + l as usize * 3) as f64 * 0.61;
            let r = 0.3 * ((s * 13 + l as usize) % 10) as f64 / 9.0;
            DVec3::new(r * a.cos(), r * a.sin(), 0.0)
        })
    }

    #[test]
    fn regression_learns_where_the_bump_moved() {
        let model = GenericModel::default_model().unwrap();
        let faces: Vec<(TriMesh, [DVec3; 5])> = (0..60).map(|s| bumpy(&model, shift(s))).collect();
        let samples: Vec<(&TriMesh, [DVec3; 5], DAffine3)> = faces[..48]
            .iter()
            .map(|(m, l)| (m, *l, DAffine3::IDENTITY))
            .collect();
        let reg = LandmarkRegressor::train(&model, &samples, &RegressorOptions::default()).unwrap();
        reg.validate().unwrap();
        assert_eq!(reg.n_training, 48);
        // Held-out faces: the regression recovers most of the shift (the mean landmark alone is
        // off by the whole shift).
        let (mut err, mut base) = (0.0, 0.0);
        for (m, l) in &faces[48..] {
            let q = reg
                .predict(m, &DAffine3::IDENTITY, false)
                .map(|p| p.expect("a face like the training faces is regressed"));
            for k in 0..5 {
                let t = DVec3::new(l[k].x, l[k].y, 0.0);
                err += (DVec3::new(q[k].x, q[k].y, 0.0) - t).length();
                let c = model.landmark(LandmarkName::ALL[k]);
                base += (DVec3::new(c.x, c.y, 0.0) - t).length();
            }
        }
        assert!(
            err < 0.1 * base,
            "regression error {err} vs {base} without it"
        );
    }

    /// `m` without the triangles that have a corner with `x > x_min`.
    fn cut(m: &TriMesh, x_min: f64) -> TriMesh {
        let tri: Vec<[u32; 3]> = m
            .triangles()
            .iter()
            .filter(|t| t.iter().all(|&v| m.position(v).x <= x_min))
            .copied()
            .collect();
        TriMesh::new(m.positions().to_vec(), tri).unwrap()
    }

    #[test]
    fn on_a_scan_surface_the_training_faces_had_is_unobserved() {
        let model = GenericModel::default_model().unwrap();
        let faces: Vec<(TriMesh, [DVec3; 5])> = (0..50).map(|s| bumpy(&model, shift(s))).collect();
        let k = LandmarkName::OuterEyeLeft as usize; // the face's outermost landmark (+x)
        let centre = model.landmark(LandmarkName::OuterEyeLeft).x;
        let r = RegressorOptions::default().radius * model.eye_distance();
        // Two of the 48 training faces (under the 5 % of `UNSEEN_RATE`) lack the patch's outer
        // rim, so the regression learns a weight for "no surface there".
        let rimless: Vec<TriMesh> = [0, 24]
            .iter()
            .map(|&s| cut(&faces[s].0, centre + 0.6 * r))
            .collect();
        let samples: Vec<(&TriMesh, [DVec3; 5], DAffine3)> = faces[..48]
            .iter()
            .enumerate()
            .map(|(s, (m, l))| {
                let m = match s {
                    0 => &rimless[0],
                    24 => &rimless[1],
                    _ => m,
                };
                (m, *l, DAffine3::IDENTITY)
            })
            .collect();
        let reg = LandmarkRegressor::train(&model, &samples, &RegressorOptions::default()).unwrap();
        let c = reg.patches[k].center[0];
        assert!((c - centre).abs() < 1e-9 && (reg.patches[k].radius - r).abs() < 1e-9);
        let id = DAffine3::IDENTITY;
        let (mut err_scan, mut err_mesh) = (0.0, 0.0);
        for (m, _) in &faces[48..] {
            let full = reg.predict(m, &id, false);
            // The outer rim of the patch (about a seventh of its disc) is lost, as a turned head
            // loses it: on a scan its inputs take the training mean.
            let part = cut(m, c + 0.6 * r);
            let as_scan = reg.predict(&part, &id, true);
            let as_mesh = reg.predict(&part, &id, false);
            let want = full[k].unwrap();
            err_scan += (as_scan[k].unwrap() - want).length();
            err_mesh += (as_mesh[k].unwrap() - want).length();
            // Patches away from the cut see the same inputs either way.
            for j in [
                LandmarkName::OuterEyeRight as usize,
                LandmarkName::NoseTip as usize,
            ] {
                assert_eq!(as_scan[j], full[j], "landmark {j}");
            }
            // Most of the patch lost: not regressed on a scan (the template search stays).
            let most = cut(m, c - 0.1 * r);
            assert_eq!(reg.predict(&most, &id, true)[k], None);
            assert!(reg.predict(&most, &id, false)[k].is_some());
        }
        assert!(
            err_scan < 0.5 * err_mesh,
            "imputed {err_scan} vs read as shape {err_mesh}"
        );
    }

    #[test]
    fn perturbed_poses_enter_the_training_deterministically() {
        let model = GenericModel::default_model().unwrap();
        let faces: Vec<(TriMesh, [DVec3; 5])> = (0..12)
            .map(|s| {
                let r = 0.02 * s as f64;
                bumpy(&model, [DVec3::new(r, -r, 0.0); 5])
            })
            .collect();
        let samples: Vec<(&TriMesh, [DVec3; 5], DAffine3)> = faces
            .iter()
            .map(|(m, l)| (m, *l, DAffine3::IDENTITY))
            .collect();
        let plain = RegressorOptions::default();
        let perturbed = RegressorOptions {
            perturbations: 2,
            ..plain
        };
        let a = LandmarkRegressor::train(&model, &samples, &plain).unwrap();
        let b = LandmarkRegressor::train(&model, &samples, &perturbed).unwrap();
        let c = LandmarkRegressor::train(&model, &samples, &perturbed).unwrap();
        assert_eq!(a.n_training, b.n_training);
        assert_ne!(a.patches, b.patches, "the perturbed samples change the fit");
        assert_eq!(b, c, "same samples, same regression");
        let p = perturbation(7, 2f64.to_radians(), 0.1);
        assert!((p.matrix3.determinant() - 1.0).abs() < 1e-12);
        assert!(p.translation.length() < 1.0 && p != DAffine3::IDENTITY);
    }

    #[test]
    fn training_rejects_bad_input() {
        let model = GenericModel::default_model().unwrap();
        let (m, l) = bumpy(&model, [DVec3::ZERO; 5]);
        let few = vec![(&m, l, DAffine3::IDENTITY); 3];
        assert!(matches!(
            LandmarkRegressor::train(&model, &few, &RegressorOptions::default()),
            Err(LandmarkError::InvalidTraining(_))
        ));
        let bad = RegressorOptions {
            spacing: 0.0,
            ..Default::default()
        };
        assert!(matches!(
            LandmarkRegressor::train(&model, &few, &bad),
            Err(LandmarkError::InvalidOption(_))
        ));
        // Wrong poses (landmarks far from the mean) are left out.
        let far = l.map(|p| p + DVec3::X * 5.0);
        let wrong = vec![(&m, far, DAffine3::IDENTITY); 20];
        assert!(LandmarkRegressor::train(&model, &wrong, &RegressorOptions::default()).is_err());
    }
}
