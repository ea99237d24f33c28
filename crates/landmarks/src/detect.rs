//! Landmark detection: curvature candidates, pose hypotheses from (nose tip, inner eye corner)
//! configurations, verification and refinement of the pose by fitting the generic face surface,
//! then local template search around each predicted landmark.

#![allow(clippy::needless_range_loop)] // Dense small linear algebra reads best with indices.

use crate::curvature::{
    curvatures_at, curvatures_at_thinned, CubeThinning, CurvatureOptions, VertexAdjacency,
};
use crate::geom::{icp, score, FitScore, SurfaceIndex};
use crate::model::GenericModel;
use crate::{Landmark, LandmarkError, LandmarkName, Landmarks, Unseen, VisibleLandmarks};
use meshcore::linalg::{fit_rigid, rigid_inverse};
use meshcore::{DAffine3, DMat3, DQuat, DVec3, TriMesh};
use rayon::prelude::*;

/// Options of [`detect_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectOptions {
    /// Mesh units per model unit (e.g. `10.0` for a scan in mm with the default model in cm).
    pub mesh_units_per_model_unit: f64,
    /// Overall confidence below which detection fails with [`LandmarkError::NotFound`].
    pub min_confidence: f64,
    /// Maximum number of nose-tip candidates.
    pub max_nose_candidates: usize,
    /// Maximum number of eye-corner candidates.
    pub max_eye_candidates: usize,
    /// Mirror-symmetry score (see [`crate::Landmarks::symmetry`]) below which a fitted pose is
    /// rejected; calibrated on training faces (see `docs/landmarks.md`). `0` disables the check.
    pub min_symmetry: f64,
    /// Weakest local template agreement (see [`crate::Landmark::confidence`]: the landmark's
    /// confidence divided by the fit confidence) below which a fitted pose is rejected;
    /// calibrated on training faces. `0` disables the check.
    pub min_local_agreement: f64,
    /// Place the landmarks with the model's learned regression (when it has one, see
    /// [`crate::LandmarkRegressor`]) instead of the local template search alone.
    pub use_regressor: bool,
    /// Least share of a landmark's local template (the mean surface around it, turned by the
    /// fitted pose and placed at the reported point) that must find the input surface within
    /// the inlier distance; below it the landmark is not on the input (occluded, in a hole or outside the
    /// scan) and the fitted pose is rejected naming the landmark. `0` disables the check.
    pub min_landmark_coverage: f64,
    /// For a range scan: the direction from the surface toward the scanner, in the mesh's
    /// frame (any length). The rims of what the scanner did not see (holes and borders whose
    /// vertices face away from it by more than [`GRAZING_RIM_DEG`]: grazing dropouts, the far
    /// side of a turned head; and those with surface in front of them: the cheek hidden by the
    /// nose) then bound unobserved surface, and the local template search scores a landmark on
    /// the part of its template that is observed instead of counting the rest as mismatch.
    /// `None` (a mesh, not a scan): every point counts. The rims of the eye openings face the
    /// scanner and are not affected. With a direction the learned regression also reads
    /// surface missing where the training faces had it as unobserved rather than as shape.
    pub toward_viewer: Option<DVec3>,
    /// Fit confidence below which a detection's evidence is weak
    /// ([`crate::Weakness::Fit`]); also the confidence below which a second round of
    /// candidates runs.
    pub strong_confidence: f64,
    /// Mirror symmetry below which a detection's evidence is weak
    /// ([`crate::Weakness::Asymmetric`]).
    pub strong_symmetry: f64,
    /// Weakest local template agreement below which a fitted pose is refused. Between it and
    /// [`DetectOptions::min_local_agreement`] the landmarks are returned graded: their
    /// confidences are low and [`crate::VisibleLandmarks::weak_evidence`] names the landmark;
    /// among the fits comparable to the best ([`DetectOptions::comparable_fit_cost`]) one
    /// whose every landmark agrees is preferred. Only a strong fit
    /// ([`DetectOptions::strong_confidence`], [`DetectOptions::strong_symmetry`]) with every
    /// landmark placed is graded (weak agreement and unseen landmarks together are refused),
    /// and a weak landmark whose template finds less than
    /// [`DetectOptions::graded_coverage`] of its surface
    /// (beside a hole or the edge of a scan) refuses the fit (it would be returned on the
    /// hole's rim). The default 0.75 was chosen on the tuning seeds of `landmarks-eval
    /// --beyond` (true faces refused at 0.82-0.85). Equal to `min_local_agreement`, nothing is
    /// graded (the former default, 0.85).
    pub refuse_local_agreement: f64,
    /// Least share of a weakly agreeing landmark's template (agreement between
    /// [`DetectOptions::refuse_local_agreement`] and [`DetectOptions::min_local_agreement`])
    /// that must find the input surface within the inlier distance for the fit to be graded
    /// rather than refused; default [`GRADED_COVERAGE`]. `0` disables the check.
    pub graded_coverage: f64,
    /// Fits costing more than this multiple of the best fit's cost (the best among those that
    /// pass [`DetectOptions::min_confidence`] and [`DetectOptions::min_symmetry`]) are tried
    /// only after every pass over the better fits failed, so that a much worse fit whose
    /// landmarks all agree is not preferred to the best fit graded. `f64::INFINITY`: every fit
    /// in one tier (fits in order of cost within each pass).
    pub comparable_fit_cost: f64,
    /// Print the detector's trace (candidates, hypotheses, fits, per-landmark refinement, with
    /// timings) to standard error.
    pub trace: bool,
}

/// Least angle (degrees) between a rim vertex's normal and the direction toward the scanner
/// for [`DetectOptions::toward_viewer`] to take the rim as the edge of unobserved surface (the
/// structured-light scanners of `rangescan` start dropping samples at 70 degrees).
pub const GRAZING_RIM_DEG: f64 = 65.0;

/// Per vertex: whether it is on a rim of surface the scanner did not see (all `false` without a
/// direction): a boundary vertex that faces away from `toward_viewer` by more than
/// [`GRAZING_RIM_DEG`] (a grazing dropout, the far side of a turned head), or one with surface
/// in front of it, that is a vertex within two of its mean edge lengths across the viewing
/// direction and nearer to the scanner by more than `depth_gap` (the cheek beside the nose of a
/// turned head, hidden by the nose).
fn unseen_rims(
    mesh: &TriMesh,
    idx: &SurfaceIndex,
    toward_viewer: Option<DVec3>,
    depth_gap: f64,
) -> Result<Vec<bool>, LandmarkError> {
    let nrm = &idx.nrm;
    let mut out = vec![false; nrm.len()];
    let Some(v) = toward_viewer else {
        return Ok(out);
    };
    let v = v.try_normalize().ok_or_else(|| {
        LandmarkError::InvalidOption(format!(
            "toward_viewer must be a finite non-zero direction, got {v}"
        ))
    })?;
    let cos = GRAZING_RIM_DEG.to_radians().cos();
    let topo = meshcore::Topology::new(mesh);
    let mut rim = vec![false; nrm.len()];
    for e in topo.edges().iter().filter(|e| e.is_boundary()) {
        for k in e.v {
            rim[k as usize] = true;
            out[k as usize] = nrm[k as usize].dot(v) < cos;
        }
    }
    // Occlusion rims: the depth map's discontinuities seen from the scanner.
    let (e1, e2) = v.any_orthonormal_pair();
    let flat: Vec<[f64; 2]> = idx.pos.iter().map(|p| [p.dot(e1), p.dot(e2)]).collect();
    let tree: kiddo::ImmutableKdTree<f64, 2> = kiddo::ImmutableKdTree::new_from_slice(&flat);
    for b in 0..rim.len() {
        if !rim[b] || out[b] {
            continue;
        }
        let r = 4.0 * idx.reach[b];
        let depth = idx.pos[b].dot(v);
        out[b] = tree
            .within_unsorted::<kiddo::SquaredEuclidean>(&flat[b], r * r)
            .iter()
            .any(|n| idx.pos[n.item as usize].dot(v) > depth + depth_gap);
    }
    Ok(out)
}

/// Whether a vertex on an unseen rim ([`unseen_rims`]) lies within `reach` of `p`.
fn near_unseen_rim(idx: &SurfaceIndex, p: DVec3, reach: f64) -> bool {
    let r2 = reach * reach;
    idx.unseen_rim
        .iter()
        .zip(&idx.pos)
        .any(|(&rim, q)| rim && (*q - p).length_squared() <= r2)
}

impl Default for DetectOptions {
    fn default() -> Self {
        Self {
            mesh_units_per_model_unit: 1.0,
            min_confidence: 0.55,
            max_nose_candidates: 8,
            max_eye_candidates: 10,
            min_symmetry: 0.5,
            min_local_agreement: 0.85,
            use_regressor: true,
            min_landmark_coverage: 0.5,
            toward_viewer: None,
            strong_confidence: 0.85,
            strong_symmetry: 0.75,
            refuse_local_agreement: 0.75,
            graded_coverage: GRADED_COVERAGE,
            comparable_fit_cost: 1.5,
            trace: false,
        }
    }
}

/// Vertex normals, per-vertex reach and the k-d tree of a mesh (no unseen rims).
pub(crate) fn surface_index(mesh: &TriMesh) -> SurfaceIndex {
    let pos = mesh.positions().to_vec();
    let nrm = mesh.vertex_normals();
    let mut sum = vec![0.0; pos.len()];
    let mut cnt = vec![0u32; pos.len()];
    for t in mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let l = (pos[a] - pos[b]).length();
            sum[a] += l;
            sum[b] += l;
            cnt[a] += 1;
            cnt[b] += 1;
        }
    }
    let reach = sum
        .iter()
        .zip(&cnt)
        .map(|(s, &c)| if c > 0 { 0.5 * s / c as f64 } else { 0.0 })
        .collect();
    SurfaceIndex::new(pos, nrm, reach)
}

/// The thinning of a mesh denser than `spacing` (mean edge shorter) to one vertex per cube of
/// side `spacing`; `None` for a mesh as coarse as the training faces (every vertex is used).
fn dense_thinning(mesh: &TriMesh, spacing: f64) -> Option<CubeThinning> {
    (spacing > 0.0 && spacing.is_finite() && mesh.mean_edge_length() < spacing)
        .then(|| CubeThinning::new(mesh.positions(), spacing))
}

/// Greedy non-maximum suppression: vertices sorted by decreasing score (ties by index), kept
/// when no kept vertex lies within `radius`.
fn nms(idx: &SurfaceIndex, mut cand: Vec<(f64, u32)>, radius: f64, max: usize) -> Vec<u32> {
    cand.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut kept: Vec<u32> = Vec::new();
    for (_, v) in cand {
        let p = idx.pos[v as usize];
        if kept
            .iter()
            .all(|&k| (idx.pos[k as usize] - p).length() > radius)
        {
            kept.push(v);
            if kept.len() >= max {
                break;
            }
        }
    }
    kept
}

/// Search radius of the nose-tip refinement, in units of the model's search radius. The pose
/// predicts the nose tip less well than the eye corners that dominate the fit: with `1.0` the
/// nose tip was more than 10 mm off on 5 % of 600 test faces instead of 1 %.
const NOSE_SEARCH: f64 = 2.0;

/// A pose hypothesis (model -> mesh) with its fit.
#[derive(Debug, Clone, Copy)]
struct Hypothesis {
    t: DAffine3,
    fit: FitScore,
}

/// The input vertices matched by the generic face `face` (points with normals) moved by the
/// pose `t`: each point's nearest vertex when it is within `tau` and the normals agree (within
/// 60 degrees); sorted, without repeats.
fn matched_vertices(
    idx: &SurfaceIndex,
    face: &[(DVec3, DVec3)],
    t: &DAffine3,
    tau: f64,
) -> Vec<u32> {
    let tau2 = tau * tau;
    let mut verts: Vec<u32> = face
        .iter()
        .filter_map(|(p, n)| {
            let h = idx.query(t.transform_point3(*p));
            (h.d2 < tau2 && idx.nrm[h.vertex as usize].dot(t.transform_vector3(*n)) > 0.5)
                .then_some(h.vertex)
        })
        .collect();
    verts.sort_unstable();
    verts.dedup();
    verts
}

/// Most iterations of the ICP that refines the mirror plane ([`mirror_of_input`]).
const MIRROR_ICP_ITERATIONS: usize = 20;

/// The reflection (input to input) across the input's own mid-sagittal plane: the fitted
/// pose's plane (`x = 0` of the canonical frame, moved by `t`), refined by a point-to-plane
/// ICP (band `tau`) of the mirrored matched vertices ([`matched_vertices`]) onto the input.
/// On a head turned away from the scanner the generic face is fitted mostly to the seen half
/// and its plane can be several mm off the face's; the part of the face seen on both sides of
/// the midline (nose, brows, the near side of the far cheek) places the plane. Without enough
/// pairs for the ICP the fitted plane stays.
fn mirror_of_input(
    idx: &SurfaceIndex,
    face: &[(DVec3, DVec3)],
    t: &DAffine3,
    tau: f64,
) -> DAffine3 {
    let fitted = *t * DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)) * rigid_inverse(t);
    let mirrored: Vec<(DVec3, DVec3)> = matched_vertices(idx, face, t, tau)
        .iter()
        .map(|&v| {
            (
                fitted.transform_point3(idx.pos[v as usize]),
                fitted.transform_vector3(idx.nrm[v as usize]),
            )
        })
        .collect();
    icp(
        idx,
        &mirrored,
        &DAffine3::IDENTITY,
        MIRROR_ICP_ITERATIONS,
        tau,
        0.5,
    ) * fitted
}

/// Mirror-symmetry check of a fitted pose: the input vertices matched by the generic face are
/// mirrored across the model's mid-sagittal plane (`x = 0` of the canonical frame, moved by the
/// pose) and must land on the input surface again with agreeing normals. A face is nearly
/// mirror-symmetric about that plane only when the pose is right; a pose rotated about the nose
/// or fitted on a cheek, a chin or a non-face maps the matched region onto empty space or onto
/// a differently oriented surface. Returns the share of mirrored vertices that are inliers
/// (distance below `tau`, normals within 60 degrees), in `[0, 1]`.
fn symmetry(idx: &SurfaceIndex, face: &[(DVec3, DVec3)], t: &DAffine3, tau: f64) -> f64 {
    let tau2 = tau * tau;
    let verts = matched_vertices(idx, face, t, tau);
    if verts.is_empty() {
        return 0.0;
    }
    let inv = rigid_inverse(t);
    let mirror = |v: DVec3| DVec3::new(-v.x, v.y, v.z);
    let ok = verts
        .iter()
        .filter(|&&v| {
            let q = t.transform_point3(mirror(inv.transform_point3(idx.pos[v as usize])));
            let nq = t.transform_vector3(mirror(inv.transform_vector3(idx.nrm[v as usize])));
            let h = idx.query(q);
            h.d2 < tau2 && idx.nrm[h.vertex as usize].dot(nq) > 0.5
        })
        .count();
    ok as f64 / verts.len() as f64
}

/// Keeps the best `max` hypotheses (sorted by cost) whose predicted nose tip and outer eye
/// corners are not all within `radius` of those of an already kept one: the coarse scores of
/// near-duplicate poses (one pose reached from several eye-candidate pairs) would otherwise
/// fill the list and push out the right pose.
fn diverse(sorted: Vec<Hypothesis>, keys: [DVec3; 3], radius: f64, max: usize) -> Vec<Hypothesis> {
    let mut kept: Vec<(Hypothesis, [DVec3; 3])> = Vec::new();
    for h in sorted {
        let k = keys.map(|p| h.t.transform_point3(p));
        let dup = kept
            .iter()
            .any(|(_, o)| (0..3).all(|i| (o[i] - k[i]).length() < radius));
        if !dup {
            kept.push((h, k));
            if kept.len() >= max {
                break;
            }
        }
    }
    kept.into_iter().map(|(h, _)| h).collect()
}

/// A finely fitted pose with its confidence, symmetry and (once computed) its refined landmarks
/// with their local agreements.
#[derive(Debug, Clone, Copy)]
struct Verified {
    h: Hypothesis,
    conf: f64,
    sym: f64,
    refined: Option<([Landmark; 5], [f64; 5])>,
}

/// Detects the five landmarks with the default options, the mesh in any of mm, cm or m: its
/// units are recognised from the size of the face ([`mesh_units_per_model_unit`]). Positions
/// are returned in the mesh's own units.
pub fn detect(mesh: &TriMesh, model: &GenericModel) -> Result<Landmarks, LandmarkError> {
    detect_with(mesh, model, &default_options(mesh, model, None)?)
}

/// [`detect_visible`] with the default options (units as [`detect`]) on a range scan seen
/// from `toward_viewer` (the direction toward the scanner, [`DetectOptions::toward_viewer`];
/// `None`: a mesh, whose landmarks can still be unseen for want of surface).
pub fn detect_seen_from(
    mesh: &TriMesh,
    model: &GenericModel,
    toward_viewer: Option<DVec3>,
) -> Result<VisibleLandmarks, LandmarkError> {
    detect_visible(mesh, model, &default_options(mesh, model, toward_viewer)?)
}

/// The default options with the mesh's units and a viewing direction.
fn default_options(
    mesh: &TriMesh,
    model: &GenericModel,
    toward_viewer: Option<DVec3>,
) -> Result<DetectOptions, LandmarkError> {
    Ok(DetectOptions {
        mesh_units_per_model_unit: mesh_units_per_model_unit(mesh, model)?,
        toward_viewer,
        ..DetectOptions::default()
    })
}

/// Mesh units per model unit for a face-sized `mesh`: the mesh's units recognised from its size
/// ([`meshcore::units::detect_units`]), the model's from its `units` label (`mm`, `cm` or `m`).
/// A model whose label names no unit (one trained by [`GenericModel::train`], labelled
/// `unknown`) is refused ([`LandmarkError::InvalidModel`]): its units are never assumed; give
/// [`DetectOptions::mesh_units_per_model_unit`] to [`detect_with`] instead. Errors too when the
/// mesh's size fits no unit.
pub fn mesh_units_per_model_unit(
    mesh: &TriMesh,
    model: &GenericModel,
) -> Result<f64, LandmarkError> {
    let model_units = model
        .units
        .trim()
        .parse::<meshcore::units::Units>()
        .map_err(|e| {
            LandmarkError::InvalidModel(format!(
                "the generic model's units label {:?} names no unit ({e}); give the mesh units per model unit explicitly (DetectOptions::mesh_units_per_model_unit, CLI --scale)",
                model.units
            ))
        })?;
    let mesh_units = meshcore::units::detect_units(mesh)?.units;
    Ok(model_units.factor_to(mesh_units))
}

/// Detects the five landmarks.
///
/// Invariant to rigid motions of the input. Fails with [`LandmarkError::NotFound`] (naming the
/// best score) when no configuration of candidates fits the generic face well enough: meshes
/// that are not faces, faces with inverted normals (seen from behind), or faces in other units
/// than `options.mesh_units_per_model_unit` says.
pub fn detect_with(
    mesh: &TriMesh,
    model: &GenericModel,
    options: &DetectOptions,
) -> Result<Landmarks, LandmarkError> {
    detect_impl(mesh, model, options, false)?.complete()
}

/// Least local template agreement of a landmark beside unseen surface for [`detect_visible`]
/// to place it when the face has unseen landmarks. At 45 degrees of yaw, the far outer eye
/// corners placed 13-18 mm off had agreements of 0.855-0.877 (above the 0.85 of
/// [`DetectOptions::min_local_agreement`]).
pub const RIM_AGREEMENT: f64 = 0.9;

/// The default of [`DetectOptions::graded_coverage`]: least share of a weakly agreeing
/// landmark's template (below [`DetectOptions::min_local_agreement`]) that must find the input
/// surface for the landmark to be returned graded: a landmark beside a hole of 12 mm agrees weakly and its template
/// finds the rim (`landmarks/tests/detect.rs`). An outer corner near the border of a mesh
/// cut close around the eyes (the ICT face area) can find as little as 80 % and is refused.
pub const GRADED_COVERAGE: f64 = 0.9;

/// Least number of landmarks [`detect_visible`] must place (the nose tip among them).
pub const MIN_PLACED: usize = 3;

/// Detects the landmarks of a face the scanner may not have seen whole. A fitted face that
/// places all five is taken first, as [`detect_with`] takes it (same points). Only when there
/// is none, a landmark that is not on the input is reported as [`Unseen`] (with the reason)
/// instead of rejecting the fit, which must still place the nose tip and at least
/// [`MIN_PLACED`] landmarks, each agreeing with its template. A landmark is unseen when it
/// borders surface the scanner did not see (an unseen rim within its template's reach; only
/// with [`DetectOptions::toward_viewer`]: the far inner eye corner behind the nose of a turned
/// head) and agrees with its template less than [`RIM_AGREEMENT`] ([`Unseen::Unobserved`]),
/// or when too little of the surface expected around it is on the input
/// ([`DetectOptions::min_landmark_coverage`]: a hole, the border of the scan; [`Unseen::Bare`]).
pub fn detect_visible(
    mesh: &TriMesh,
    model: &GenericModel,
    options: &DetectOptions,
) -> Result<VisibleLandmarks, LandmarkError> {
    detect_impl(mesh, model, options, true)
}

/// `mesh` in model units, `s` mesh units per model unit (borrowed when `s` is 1); an error
/// when `s` is not positive and finite.
pub(crate) fn in_model_units(
    mesh: &TriMesh,
    s: f64,
) -> Result<std::borrow::Cow<'_, TriMesh>, LandmarkError> {
    if !(s.is_finite() && s > 0.0) {
        return Err(LandmarkError::InvalidOption(format!(
            "mesh_units_per_model_unit must be positive and finite, got {s}"
        )));
    }
    if s == 1.0 {
        return Ok(std::borrow::Cow::Borrowed(mesh));
    }
    Ok(std::borrow::Cow::Owned(TriMesh::new(
        mesh.positions().iter().map(|p| *p / s).collect(),
        mesh.triangles().to_vec(),
    )?))
}

/// [`detect_with`] (`partial` false: every landmark must be placed) or [`detect_visible`].
fn detect_impl(
    mesh: &TriMesh,
    model: &GenericModel,
    options: &DetectOptions,
    partial: bool,
) -> Result<VisibleLandmarks, LandmarkError> {
    model.validate()?;
    let s = options.mesh_units_per_model_unit;
    // Work in model units.
    let in_model = in_model_units(mesh, s)?;
    let mesh_m: &TriMesh = &in_model;
    let p = &model.params;
    let debug = options.trace;
    let clock = std::time::Instant::now();
    // The index, the adjacency and the vertices to fit are independent, and so are the rims
    // of unseen surface, the far marks and the curvature fits: each group in parallel.
    let spacing = p.curvature_radius / 6.0;
    let ((mut idx, adj), thin) = rayon::join(
        || rayon::join(|| surface_index(mesh_m), || VertexAdjacency::new(mesh_m)),
        // Candidates come from the curvature at vertices about a sixth of the curvature radius
        // apart: every vertex of a mesh as coarse as the training faces, one vertex per cube of
        // that side on a denser mesh. On a mesh at least twice as dense (a raw scan), the fits
        // use those vertices only, so that a fit costs about as much as on a training face
        // whatever the density; between the two (a scan decimated to about 1.5 mm, as
        // `facematch` prepares it) thinned fits would save little and move the candidates
        // (one probe of the scan benchmark's seed 7 was then not found), so they use every
        // vertex.
        || dense_thinning(mesh_m, spacing),
    );
    let thin_fits = thin.is_some() && mesh_m.mean_edge_length() < 0.5 * spacing;
    let at: Vec<u32> = match &thin {
        Some(t) => t.kept().to_vec(),
        None => (0..mesh_m.n_vertices() as u32).collect(),
    };
    if debug {
        eprintln!(
            "[{:.1} ms] index and adjacency built; curvature at {} of {} vertices",
            clock.elapsed().as_secs_f64() * 1e3,
            at.len(),
            mesh_m.n_vertices()
        );
    }
    let (marks, curv) = rayon::join(
        || {
            unseen_rims(mesh_m, &idx, options.toward_viewer, p.inlier_distance).map(|rims| {
                // The widest inlier band of the fits: the coarse scores of the pose
                // hypotheses.
                (rims, idx.far_grid(3.0 * p.inlier_distance))
            })
        },
        || {
            let copt = CurvatureOptions::with_radius(p.curvature_radius);
            match &thin {
                Some(t) if thin_fits => {
                    curvatures_at_thinned(mesh_m, &idx.nrm, &adj, &copt, &at, t)
                }
                _ => curvatures_at(mesh_m, &idx.nrm, &adj, &copt, &at),
            }
        },
    );
    (idx.unseen_rim, idx.far) = marks?;
    use LandmarkName as L;
    let mut n_noses = 0;
    let mut n_eyes = 0;
    let face = model.face.pairs();
    let tau = p.inlier_distance;
    let d = model.eye_distance();
    let keys = [
        model.landmark(L::NoseTip),
        model.landmark(L::OuterEyeRight),
        model.landmark(L::OuterEyeLeft),
    ];
    // Every finely fitted pose of every round, verified.
    let mut fits: Vec<Verified> = Vec::new();
    // Round 0 with the nominal candidates; round 1, only when round 0 found no convincing face
    // (expressions can blur the curvature signatures), with three times more nose candidates
    // and a looser signature gate.
    for round in 0..2 {
        let (max_noses, gate) = if round == 0 {
            (options.max_nose_candidates, 9.0)
        } else {
            (3 * options.max_nose_candidates, 16.0)
        };
        // Candidates.
        let mut nose_c = Vec::new();
        let mut eye_c = Vec::new();
        for (&v, c) in at.iter().zip(&curv) {
            let (si, cv) = (c.shape_index(), c.curvedness());
            // Candidates resemble the learned curvature signatures (within 3 sd on each axis).
            let dn = p.nose.distance2(si, cv);
            if dn < gate && si > 0.0 {
                nose_c.push((-dn, v));
            }
            let de = p.eye.distance2(si, cv);
            if de < gate && si < 0.0 {
                eye_c.push((-de, v));
            }
        }
        let noses = nms(&idx, nose_c, p.candidate_radius, max_noses);
        let eyes = nms(&idx, eye_c, p.candidate_radius, options.max_eye_candidates);
        n_noses = n_noses.max(noses.len());
        n_eyes = n_eyes.max(eyes.len());
        if debug {
            eprintln!(
                "[{:.1} ms] candidates: noses {noses:?} eyes {eyes:?}",
                clock.elapsed().as_secs_f64() * 1e3
            );
        }
        if noses.is_empty() {
            continue;
        }
        // Pose hypotheses.
        let m_nose = model.landmark(L::NoseTip);
        let m_nn = DVec3::from_array(model.nose_normal);
        let m_ir = model.landmark(L::InnerEyeRight);
        let m_il = model.landmark(L::InnerEyeLeft);
        let d_nr = (m_ir - m_nose).length();
        let d_nl = (m_il - m_nose).length();
        let mut hyps: Vec<DAffine3> = Vec::new();
        for &n in &noses {
            let pn = idx.pos[n as usize];
            let nn = at
                .binary_search(&n)
                .map_or(idx.nrm[n as usize], |k| curv[k].normal);
            let src_base = [m_nose, m_nose + m_nn * d];
            let dst_base = [pn, pn + nn * d];
            for (i, &ei) in eyes.iter().enumerate() {
                let pi = idx.pos[ei as usize];
                let di = (pi - pn).length();
                let _ = di;
                // Triplets: both inner corners.
                for &ej in &eyes[i + 1..] {
                    let pj = idx.pos[ej as usize];
                    let dj = (pj - pn).length();
                    let dij = (pj - pi).length();
                    if (dij - d).abs() > 0.35 * d {
                        continue;
                    }
                    for (a, b, da, db) in [(pi, pj, di, dj), (pj, pi, dj, di)] {
                        if (da - d_nr).abs() > 0.35 * d_nr || (db - d_nl).abs() > 0.35 * d_nl {
                            continue;
                        }
                        let src = [src_base[0], src_base[1], m_ir, m_il];
                        let dst = [dst_base[0], dst_base[1], a, b];
                        if let Some(t) = fit_rigid(&src, &dst, Some(&[1.0, 0.5, 1.0, 1.0])) {
                            hyps.push(t);
                        }
                    }
                }
            }
            // Rotations about the nose normal: pose hypotheses that need no eye candidate (eye
            // corners are weak features under expressions).
            // The base pose puts the model's nose on the candidate and turns its normal onto
            // the candidate's by the shortest arc; the spins then cover the angle about the
            // normal (a rigid fit of the two base points alone leaves that angle to the solver).
            let (mu, nu) = (m_nn.normalize_or_zero(), nn.normalize_or_zero());
            if mu != DVec3::ZERO && nu != DVec3::ZERO {
                let r0 = DQuat::from_rotation_arc(mu, nu);
                let b = DAffine3::from_rotation_translation(r0, pn - r0 * m_nose);
                for k in 0..16 {
                    let ang = k as f64 * std::f64::consts::TAU / 16.0;
                    let r = DMat3::from_axis_angle(nn, ang);
                    let spin = DAffine3::from_mat3_translation(r, pn - r * pn);
                    hyps.push(spin * b);
                }
            }
        }
        let coarse: Vec<(DVec3, DVec3)> = face.iter().step_by(3).copied().collect();
        // Hypotheses, coarse fits and fine fits are independent: in parallel, collected in
        // order (the same results on any number of threads).
        let mut scored: Vec<Hypothesis> = hyps
            .par_iter()
            .map(|t| Hypothesis {
                t: *t,
                fit: score(&idx, &coarse, t, 3.0 * tau, 0.3),
            })
            .collect();
        scored.sort_by(|a, b| a.fit.cost.total_cmp(&b.fit.cost));
        if debug {
            eprintln!(
                "[{:.1} ms] {} hypotheses, best coarse costs {:?}",
                clock.elapsed().as_secs_f64() * 1e3,
                scored.len(),
                scored
                    .iter()
                    .take(6)
                    .map(|h| h.fit.cost)
                    .collect::<Vec<_>>()
            );
        }
        let scored = diverse(scored, keys, 0.25 * d, 12);
        // Coarse ICP of the best hypotheses with a wide inlier band, then the nominal band on the
        // best three.
        let mut coarse_fits: Vec<Hypothesis> = scored
            .par_iter()
            .map(|h| {
                let t = icp(&idx, &coarse, &h.t, 8, 3.0 * tau, 0.3);
                Hypothesis {
                    t,
                    fit: score(&idx, &coarse, &t, tau, 0.5),
                }
            })
            .collect();
        coarse_fits.sort_by(|a, b| a.fit.cost.total_cmp(&b.fit.cost));
        let coarse_fits = diverse(coarse_fits, keys, 0.25 * d, 3);
        let fine: Vec<Verified> = coarse_fits
            .par_iter()
            .map(|h| {
                let t2 = icp(&idx, &face, &h.t, 12, tau, 0.5);
                let fit = score(&idx, &face, &t2, tau, 0.5);
                Verified {
                    h: Hypothesis { t: t2, fit },
                    conf: fit_confidence(&fit, p.typical_rms, p.typical_inliers),
                    sym: symmetry(&idx, &face, &t2, tau),
                    refined: None,
                }
            })
            .collect();
        fits.extend(fine);
        fits.sort_by(|a, b| a.h.fit.cost.total_cmp(&b.h.fit.cost));
        if debug {
            eprintln!(
                "[{:.1} ms] coarse and fine fits done",
                clock.elapsed().as_secs_f64() * 1e3
            );
            for f in &fits {
                eprintln!(
                    "fit cost {:.4} confidence {:.3} symmetry {:.3} nose at {:?}",
                    f.h.fit.cost,
                    f.conf,
                    f.sym,
                    f.h.t.transform_point3(keys[0])
                );
            }
        }
        // The best-fitting pose decides; a second round only when it is weak or not symmetric.
        if let Some(f) = fits.first_mut() {
            if f.conf >= options.strong_confidence && f.sym >= options.min_symmetry {
                let r = *f
                    .refined
                    .get_or_insert_with(|| refine_all(&idx, model, &f.h.t, f.conf, debug));
                if weakest(&r.1, &[None; 5]) >= options.min_local_agreement {
                    break;
                }
            }
        }
    }
    if fits.is_empty() {
        return Err(LandmarkError::NotFound {
            reason: if n_noses == 0 {
                "no convex cap (nose-tip candidate) on the surface".into()
            } else {
                format!(
                    "{n_noses} nose-tip and {n_eyes} eye-corner candidates form no face-like configuration"
                )
            },
            best_score: 0.0,
        });
    }
    // The best-fitting pose that passes the three checks (fit confidence, mirror symmetry, local
    // template agreement at every landmark), in increasing order of fit cost.
    // Per fit, why it was refused in the last pass that tried it (the most lenient); the
    // reason of the best-fitting refused fit is the error's.
    let mut rejected: Vec<Option<(String, f64)>> = vec![None; fits.len()];
    // A partial detection takes the first fit that places every landmark, as `detect_with`
    // does, and only when there is none the first that places enough of them.
    // Then, when no fit's landmarks all agree with their templates, the first whose weakest
    // agreement is at least `refuse_local_agreement`, graded (low confidences, a reason), with
    // every landmark placed: weak agreement and unseen landmarks together are refused.
    let passes: &[(bool, bool)] = if partial {
        &[(false, false), (true, false), (false, true)]
    } else {
        &[(false, false), (false, true)]
    };
    // The fits comparable to the best one that passes the fit-confidence and symmetry checks
    // (cost at most `comparable_fit_cost` times its cost) go through every pass before any
    // worse fit: a worse-fitting pose whose landmarks all agree (a face turned upside down on a
    // coarse scan) is not preferred to the best pose with one weakly agreeing landmark.
    let best_cost = fits
        .iter()
        .find(|f| f.conf >= options.min_confidence && f.sym >= options.min_symmetry)
        .map(|f| f.h.fit.cost);
    let near =
        |f: &Verified| best_cost.is_none_or(|c| f.h.fit.cost <= options.comparable_fit_cost * c);
    let tiers: [Vec<usize>; 2] = [
        (0..fits.len()).filter(|&k| near(&fits[k])).collect(),
        (0..fits.len()).filter(|&k| !near(&fits[k])).collect(),
    ];
    let order: Vec<(bool, bool, usize)> = tiers
        .iter()
        .flat_map(|tier| {
            passes
                .iter()
                .flat_map(move |&(u, g)| tier.iter().map(move |&k| (u, g, k)))
        })
        .collect();
    for (allow_unseen, graded, fi) in order {
        let f = &mut fits[fi];
        let why = if f.conf < options.min_confidence {
            Some(format!(
                "the best fit of the generic face covers {} % of it (rms {} model units; confidence {} < {})",
                100.0 * f.h.fit.inlier_fraction,
                f.h.fit.rms,
                f.conf,
                options.min_confidence
            ))
        } else if f.sym < options.min_symmetry {
            Some(format!(
                "the best fit of the generic face is not mirror-symmetric (symmetry {} < {})",
                f.sym, options.min_symmetry
            ))
        } else {
            None
        };
        if let Some(why) = why {
            rejected[fi] = Some((why, f.conf * f.sym));
            continue;
        }
        let (out, agreement) = *f
            .refined
            .get_or_insert_with(|| refine_all(&idx, model, &f.h.t, f.conf, debug));
        let predicted = L::ALL.map(|n| f.h.t.transform_point3(model.landmark(n)));
        // Partial detection: a landmark that borders surface the scanner did not see (an unseen
        // rim within its template's reach) and agrees with its template less than
        // [`RIM_AGREEMENT`] is unseen, not a mismatch of the pose.
        let mut unseen: [Option<Unseen>; 5] = [None; 5];
        if allow_unseen {
            for k in 0..5 {
                if agreement[k] < RIM_AGREEMENT.max(options.min_local_agreement)
                    && near_unseen_rim(&idx, out[k].position, model.patches[k].reach())
                {
                    unseen[k] = Some(Unseen::Unobserved {
                        agreement: agreement[k],
                    });
                }
            }
        }
        // Graded: only one kind of evidence may be weak. The fit itself must be strong, and a
        // weakly agreeing landmark must find the surface expected around it (at least
        // `graded_coverage` of its template): one beside a hole or the edge of a scan is most
        // likely not on the surface (its template finds the rim), and the fit is refused,
        // never returning it on the rim.
        if graded
            && options.refuse_local_agreement < options.min_local_agreement
            && weakest(&agreement, &unseen) < options.min_local_agreement
        {
            if f.conf < options.strong_confidence || f.sym < options.strong_symmetry {
                rejected[fi] = Some((
                    format!(
                        "the best fit's landmarks agree weakly with their templates (agreement {}) and the fit itself is weak (confidence {}, symmetry {}; at least {} and {} to grade the landmarks)",
                        weakest(&agreement, &unseen),
                        f.conf,
                        f.sym,
                        options.strong_confidence,
                        options.strong_symmetry
                    ),
                    f.conf * weakest(&agreement, &unseen),
                ));
                continue;
            }
            let mut bare = None;
            for name in L::ALL {
                let k = name as usize;
                if unseen[k].is_some() || agreement[k] >= options.min_local_agreement {
                    continue;
                }
                let c = coverage(&idx, &model.patches[k], &f.h.t, out[k].position, tau);
                if c < options.graded_coverage {
                    bare = bare.or(Some((name, agreement[k], c)));
                }
            }
            if let Some((name, a, c)) = bare {
                rejected[fi] = Some((
                    format!(
                        "the surface around the landmarks predicted by the best fit does not match their templates: {name} agrees weakly (agreement {a} < {}) and only {} % of the surface expected around it was found (at least {} % to grade it), it is in a hole or outside the input",
                        options.min_local_agreement,
                        100.0 * c,
                        100.0 * options.graded_coverage
                    ),
                    f.conf * a,
                ));
                continue;
            }
        }
        let local = weakest(&agreement, &unseen);
        let need = if graded {
            options.refuse_local_agreement
        } else {
            options.min_local_agreement
        };
        if local < need {
            rejected[fi] = Some((
                format!(
                    "the surface around the landmarks predicted by the best fit does not match their templates (agreement {local} < {need})"
                ),
                f.conf * local,
            ));
            continue;
        }
        let best = f.h;
        let out = match &model.regressor {
            Some(reg) if options.use_regressor => regressed(
                &idx,
                mesh_m,
                model,
                reg,
                &best.t,
                &out,
                options.toward_viewer.is_some(),
                debug,
            ),
            _ => out,
        };
        // Every landmark must sit on the input: one the fitted face puts where the input has
        // no surface (occluded, in a hole, cropped) lands on the nearest rim vertex, a silent
        // wrong point; the template around a reported point then finds little surface.
        // In the pass that allows unseen landmarks such a landmark is unseen; otherwise the
        // pose is rejected.
        let mut bare = None;
        if options.min_landmark_coverage > 0.0 {
            for name in L::ALL {
                let k = name as usize;
                if unseen[k].is_some() {
                    continue;
                }
                let c = coverage(&idx, &model.patches[k], &best.t, out[k].position, tau);
                if c < options.min_landmark_coverage {
                    unseen[k] = Some(Unseen::Bare { coverage: c });
                    bare = bare.or(Some((name, c)));
                }
            }
        }
        if let (false, Some((name, c))) = (allow_unseen, bare) {
            rejected[fi] = Some((
                format!(
                    "{name} is not on the surface: only {} % of the surface expected around it was found (at least {} % needed); it is occluded, in a hole or outside the scan",
                    100.0 * c,
                    100.0 * options.min_landmark_coverage
                ),
                f.conf * c,
            ));
            continue;
        }
        let placed = unseen.iter().filter(|u| u.is_none()).count();
        if let Some(u) = unseen[L::NoseTip as usize] {
            rejected[fi] = Some((format!("nose_tip is not on the surface: {u}"), 0.0));
            continue;
        }
        if placed < MIN_PLACED {
            rejected[fi] = Some((
                format!("only {placed} of the 5 landmarks are on the surface (at least {MIN_PLACED} needed)"),
                0.0,
            ));
            continue;
        }
        let pose = DAffine3::from_mat3_translation(best.t.matrix3, best.t.translation * s);
        if debug {
            eprintln!(
                "[{:.1} ms] landmarks placed and checked; unseen {unseen:?}",
                clock.elapsed().as_secs_f64() * 1e3
            );
        }
        let landmarks = std::array::from_fn(|k| match unseen[k] {
            Some(u) => Err(u),
            None => Ok(Landmark {
                position: mesh.position(out[k].vertex),
                ..out[k]
            }),
        });
        let mirror = || mirror_of_input(&idx, &face, &best.t, tau);
        let predicted = mirrored_predictions(model, &best.t, mirror, &out, &unseen, predicted);
        return Ok(VisibleLandmarks {
            landmarks,
            predicted: predicted.map(|p| p * s),
            confidence: f.conf,
            fit_rms: best.fit.rms * s,
            inlier_fraction: best.fit.inlier_fraction,
            symmetry: f.sym,
            model_to_mesh: pose,
        });
    }
    let (reason, best_score) = rejected.into_iter().flatten().next().unwrap_or_default();
    Err(LandmarkError::NotFound { reason, best_score })
}

/// The predictions of the unseen landmarks whose mirror partner (the other side's same
/// corner) is placed: the partner mirrored across the input's own mid-sagittal plane
/// (`mirror`, [`mirror_of_input`]), plus the generic face's own asymmetry (its mean landmark
/// minus its mirrored partner's, turned by the pose `t`). A face's identity and expression move
/// both corners of a pair alike, so the placed partner predicts an unseen corner better than
/// the rigid generic face alone; the others keep `rigid`, the fitted face's prediction. Model
/// units.
fn mirrored_predictions(
    model: &GenericModel,
    t: &DAffine3,
    mirror: impl Fn() -> DAffine3,
    placed: &[Landmark; 5],
    unseen: &[Option<Unseen>; 5],
    rigid: [DVec3; 5],
) -> [DVec3; 5] {
    use LandmarkName as L;
    let partner = |n: L| match n {
        L::OuterEyeRight => Some(L::OuterEyeLeft),
        L::OuterEyeLeft => Some(L::OuterEyeRight),
        L::InnerEyeRight => Some(L::InnerEyeLeft),
        L::InnerEyeLeft => Some(L::InnerEyeRight),
        L::NoseTip => None,
    };
    let flip = |v: DVec3| DVec3::new(-v.x, v.y, v.z);
    let mut reflection = None;
    let mut out = rigid;
    for n in L::ALL {
        let (k, Some(m)) = (n as usize, partner(n)) else {
            continue;
        };
        if unseen[k].is_none() || unseen[m as usize].is_some() {
            continue;
        }
        let r: &DAffine3 = reflection.get_or_insert_with(&mirror);
        let own = model.landmark(n) - flip(model.landmark(m));
        out[k] = r.transform_point3(placed[m as usize].position) + t.transform_vector3(own);
    }
    out
}

/// Local template refinement of the five landmarks predicted by the pose `t`: the landmarks
/// (positions in model units, confidences `conf_fit` times the local agreement) and each one's
/// local agreement.
fn refine_all(
    idx: &SurfaceIndex,
    model: &GenericModel,
    t: &DAffine3,
    conf_fit: f64,
    debug: bool,
) -> ([Landmark; 5], [f64; 5]) {
    use LandmarkName as L;
    let p = &model.params;
    let mut out = [Landmark {
        vertex: 0,
        position: DVec3::ZERO,
        confidence: 0.0,
    }; 5];
    let mut agreement = [0.0; 5];
    // The five searches are independent: in parallel, reported in order.
    let found: Vec<(DVec3, u32, f64)> = L::ALL
        .par_iter()
        .map(|&name| {
            let pred = t.transform_point3(model.landmark(name));
            let tpl = model.patches[name as usize].pairs();
            // The nose tip is a strong feature but far from the eyes that dominate the pose:
            // wider search.
            let radius = if name == L::NoseTip {
                NOSE_SEARCH * p.search_radius
            } else {
                p.search_radius
            };
            let (v, cost) = refine(idx, &tpl, t, pred, radius, p.inlier_distance);
            (pred, v, cost)
        })
        .collect();
    for (name, (pred, v, cost)) in L::ALL.into_iter().zip(found) {
        let c_local = (-(cost / (p.typical_rms * p.typical_rms)) * 0.1).exp();
        if debug {
            eprintln!(
                "{name}: predicted at {:?} (vertex {}), refined to vertex {v} (cost {cost:.2e}, local agreement {:.3})",
                pred,
                idx.query(pred).vertex,
                c_local
            );
        }
        agreement[name as usize] = c_local;
        out[name as usize] = Landmark {
            vertex: v,
            position: idx.pos[v as usize],
            confidence: (conf_fit * c_local).clamp(0.0, 1.0),
        };
    }
    (out, agreement)
}

/// The weakest of the local agreements of the landmarks not marked in `skip`.
fn weakest(agreement: &[f64; 5], skip: &[Option<Unseen>; 5]) -> f64 {
    agreement
        .iter()
        .zip(skip)
        .filter(|(_, u)| u.is_none())
        .fold(1.0_f64, |w, (a, _)| w.min(*a))
}

/// Landmarks placed by the learned regression of the model for the accepted pose `t`: the
/// eye corners at the mesh vertex nearest to the regressed point; the nose tip, a strong
/// feature, keeps its template search `tpl` (on 300 faces of a training stream the regression
/// placed it within 5 mm less often: 96.7 % against 98.3 %). Confidences are those of the
/// template search. On a `scan` (a viewing direction given) surface the training faces had
/// and the input lacks is unobserved (see `LandmarkRegressor::predict`).
#[allow(clippy::too_many_arguments)]
fn regressed(
    idx: &SurfaceIndex,
    mesh: &TriMesh,
    model: &GenericModel,
    reg: &crate::LandmarkRegressor,
    t: &DAffine3,
    tpl: &[Landmark; 5],
    scan: bool,
    debug: bool,
) -> [Landmark; 5] {
    let q = reg.predict(mesh, t, scan);
    let mut out = *tpl;
    for name in LandmarkName::ALL {
        if name == LandmarkName::NoseTip {
            continue;
        }
        let k = name as usize;
        // A patch lacking surface the training faces had: the template search stays.
        let Some(qk) = q[k] else {
            if debug {
                eprintln!("{name}: not regressed (surface missing around it)");
            }
            continue;
        };
        // An offset beyond what the training faces showed (their poses were kept within half
        // the inner-eye distance of the truth) is an input the regression has not learned:
        // the template search stays.
        let off = qk - model.landmark(name);
        if !(off.is_finite() && off.length() <= 0.5 * model.eye_distance()) {
            continue;
        }
        let v = idx.query(t.transform_point3(qk)).vertex;
        if debug {
            eprintln!(
                "{name}: regressed to vertex {v} (template search gave {})",
                tpl[k].vertex
            );
        }
        out[k].vertex = v;
        out[k].position = idx.pos[v as usize];
    }
    out
}

/// Share of the points of a landmark template (offsets from the landmark, turned by the pose
/// `t`), placed at `at`, whose nearest input vertex is within `tau`.
pub(crate) fn coverage(
    idx: &SurfaceIndex,
    tpl: &crate::Template,
    t: &DAffine3,
    at: DVec3,
    tau: f64,
) -> f64 {
    let tau2 = tau * tau;
    let n = tpl.points.len();
    let hit = tpl
        .points
        .iter()
        .filter(|p| {
            let q = at + t.transform_vector3(DVec3::new(p[0], p[1], p[2]));
            idx.query(q).d2 < tau2
        })
        .count();
    hit as f64 / n.max(1) as f64
}

/// Confidence in `[0, 1]` of a face fit from its inlier share and inlier RMS, relative to the
/// typical values on training faces.
fn fit_confidence(f: &FitScore, typical_rms: f64, typical_inliers: f64) -> f64 {
    if !f.rms.is_finite() {
        return 0.0;
    }
    let a = (f.inlier_fraction / typical_inliers.max(1e-6)).min(1.0);
    let r = f.rms / typical_rms;
    let b = if r <= 1.5 {
        1.0
    } else {
        (-(r - 1.5).powi(2) / 2.0).exp()
    };
    (a * a * b).clamp(0.0, 1.0)
}

/// Least share of a landmark template that must be observed (on the input or off it where
/// the input has surface) for [`refine`] to score it on the observed points alone.
const MIN_OBSERVED: f64 = 0.5;

/// Template search around `pred`: the vertex minimising the truncated mean squared distance of
/// the template (rotated by the face pose) placed at the vertex, plus a weak prior on the
/// distance to the prediction. A template point beyond an unseen rim (its nearest vertex
/// flagged in [`SurfaceIndex::unseen_rim`], and farther than `tau`) is unobserved, not a mismatch:
/// when at least [`MIN_OBSERVED`] of the template is observed the mean runs over the observed
/// points alone. Returns the vertex and its cost.
fn refine(
    idx: &SurfaceIndex,
    tpl: &[(DVec3, DVec3)],
    pose: &DAffine3,
    pred: DVec3,
    radius: f64,
    tau: f64,
) -> (u32, f64) {
    let tau2 = tau * tau;
    let rotated: Vec<DVec3> = tpl
        .iter()
        .map(|(q, _)| pose.transform_vector3(*q))
        .collect();
    // The template's cost at `c` over the points `pts` (`count` of them) plus `prior`, or
    // `None` as soon as it is certain to exceed `bound`: every term is non-negative and the
    // mean runs over at most `count` points, so the running sum over `count` plus the prior
    // (each operation monotone in floating point) never exceeds the final cost.
    let eval = |c: DVec3,
                pts: &mut dyn Iterator<Item = &DVec3>,
                count: usize,
                prior: f64,
                bound: f64|
     -> Option<f64> {
        let (mut s, mut n, mut unseen) = (0.0, 0usize, 0usize);
        let whole = count.max(1) as f64;
        for q in pts {
            let h = idx.query(c + *q);
            if h.d2 < tau2 {
                s += h.d2;
            } else if idx.unseen_rim[h.vertex as usize] {
                unseen += 1;
            } else {
                s += tau2;
            }
            n += 1;
            if s / whole + prior > bound {
                return None;
            }
        }
        let seen = n - unseen;
        let mean = if seen as f64 >= MIN_OBSERVED * n as f64 {
            s / seen.max(1) as f64
        } else {
            (s + unseen as f64 * tau2) / n.max(1) as f64
        };
        Some(mean + prior)
    };
    let prior = |c: DVec3| 0.02 * tau2 * (c - pred).length_squared() / (radius * radius);
    let mut cands = idx.within(pred, radius);
    let pv = idx.query(pred).vertex;
    if !cands.contains(&pv) {
        cands.push(pv);
    }
    // Coarse pass on a subsample, then the full template on the best few (`KEEP`, least cost,
    // ties by vertex). The candidates nearest the prediction go first; the cost of the
    // `KEEP`-th best of them bounds the others, whose evaluation stops once they are certain
    // to exceed it (they could not be among the best few).
    const KEEP: usize = 8;
    let n_coarse = rotated.len().div_ceil(5);
    let coarse_cost = |v: u32, bound: f64| {
        let c = idx.pos[v as usize];
        eval(c, &mut rotated.iter().step_by(5), n_coarse, prior(c), bound).map(|cost| (cost, v))
    };
    let mut by_distance: Vec<(f64, u32)> = cands
        .iter()
        .map(|&v| ((idx.pos[v as usize] - pred).length_squared(), v))
        .collect();
    by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let (first, rest) = by_distance.split_at(by_distance.len().min(4 * KEEP));
    let mut coarse: Vec<(f64, u32)> = first
        .iter()
        .filter_map(|&(_, v)| coarse_cost(v, f64::INFINITY))
        .collect();
    coarse.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let bound = coarse.get(KEEP - 1).map_or(f64::INFINITY, |c| c.0);
    coarse.extend(
        rest.par_iter()
            .with_min_len(64)
            .filter_map(|&(_, v)| coarse_cost(v, bound))
            .collect::<Vec<_>>(),
    );
    coarse.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    coarse.truncate(KEEP);
    let mut best = (f64::INFINITY, pv);
    for &(_, v) in &coarse {
        let c = idx.pos[v as usize];
        let cost = eval(
            c,
            &mut rotated.iter(),
            rotated.len(),
            prior(c),
            f64::INFINITY,
        )
        .unwrap_or(f64::INFINITY);
        if cost < best.0 || (cost == best.0 && v < best.1) {
            best = (cost, v);
        }
    }
    (best.1, best.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshcore::{shapes, Topology};

    /// What a scanner along +z measures of a plate hovering 5 units over a plane: the plane
    /// over [0, 20]^2 with the plate's shadow [8, 12]^2 cut out, and the plate (its vertices
    /// after the plane's `n` ones).
    fn plate_over_shadowed_plane() -> (TriMesh, usize) {
        let inside = |x: f64, y: f64| (x - 10.0).abs() < 2.0 && (y - 10.0).abs() < 2.0;
        let plane = shapes::grid_plane(20, 1.0, 0.0, 0.0, 0, |c| inside(c.x, c.y));
        let plate = shapes::grid_plane(4, 1.0, 8.0, 0.0, 0, |_| false);
        let n = plane.n_vertices();
        let mut pos = plane.positions().to_vec();
        pos.extend(plate.positions().iter().map(|p| *p + DVec3::Z * 5.0));
        let mut tris = plane.triangles().to_vec();
        tris.extend(plate.triangles().iter().map(|t| t.map(|v| v + n as u32)));
        (TriMesh::new(pos, tris).unwrap(), n)
    }

    #[test]
    fn rims_with_surface_in_front_of_them_are_unseen() {
        let (mesh, n) = plate_over_shadowed_plane();
        let idx = surface_index(&mesh);
        let rims = unseen_rims(&mesh, &idx, Some(DVec3::Z), 1.0).unwrap();
        let topo = Topology::new(&mesh);
        let mut boundary: Vec<u32> = topo
            .edges()
            .iter()
            .filter(|e| e.is_boundary())
            .flat_map(|e| e.v)
            .collect();
        boundary.sort_unstable();
        boundary.dedup();
        let mut shadow_rim = 0;
        for &b in &boundary {
            let p = mesh.position(b);
            // The rim of the plate's shadow on the plane has the plate in front of it; the
            // plane's outer border and the plate's own border have nothing in front.
            let expected =
                (b as usize) < n && (p.x - 10.0).abs() <= 2.0 && (p.y - 10.0).abs() <= 2.0;
            assert_eq!(rims[b as usize], expected, "boundary vertex {b} at {p:?}");
            shadow_rim += usize::from(expected);
        }
        assert_eq!(shadow_rim, 16);
        // Interior vertices are never rims; without a direction nothing is.
        assert_eq!(rims.iter().filter(|&&r| r).count(), 16);
        assert!(unseen_rims(&mesh, &idx, None, 1.0)
            .unwrap()
            .iter()
            .all(|&r| !r));
        // A depth gap larger than the plate's height: the shadow's rim is an ordinary border.
        assert!(unseen_rims(&mesh, &idx, Some(DVec3::Z), 6.0)
            .unwrap()
            .iter()
            .all(|&r| !r));
    }
}
