//! One face of the scan benchmark: scanned, cleaned, its landmarks detected and described with
//! both landmark sets.

use super::super::compare::icp_points;
use super::super::describe::{describe_face, DescribeOptions, Described};
use super::super::Lm;
use crate::report::par_map;
use crate::scans::{
    clean_scan, detection_errors, scan_raw, FaceSpec, ScanSetOptions, ScannedFace, MAX_SNAP_MM,
    SCANNER_SIDE,
};
use crate::walk::Walker;
use facemodel::FaceModel;
use geodesic::Method;
use landmarks::GenericModel;
use meshcore::{DVec3, TriMesh};
use std::time::Instant;

/// One scanned and described face.
pub(in super::super) struct Face {
    pub(in super::super) name: String,
    pub(in super::super) identity: usize,
    /// Per landmark set, the cleaned scan, kept for gallery faces (ICP target): for the ground
    /// truth cropped around the true nose tip, for the detected landmarks the scan
    /// `facematch::prepare` made (cropped around the detected nose tip).
    pub(super) mesh: [Option<TriMesh>; 2],
    /// Its ground-truth landmark vertices, when on the scan.
    pub(super) gt_lm: Option<Lm>,
    /// Per landmark set, the ICP probe points (of that set's scan).
    pub(in super::super) pts: [Vec<DVec3>; 2],
    /// Per landmark set: the description or why there is none.
    pub(in super::super) desc: [Result<Described, String>; 2],
    /// Detected minus true position of the outer eye corners and the nose tip (mm), when
    /// detected and on the scan.
    pub(super) det_err: Option<[f64; 3]>,
    /// What `facematch::prepare` assumed or substituted on the way to the detected landmarks
    /// (a crop around the point nearest the scanner where no face was found uncropped).
    pub(super) prepare_notes: Vec<String>,
    pub(super) valid_samples: usize,
    pub(super) vertices: usize,
    /// Wall seconds: scan, clean (ground truth's), prepare (the detected path's cleanings and
    /// detections), describe.
    pub(super) secs: [f64; 4],
}

impl Face {
    /// A face not yet described: no meshes, points, descriptions or times.
    pub(in super::super) fn new(name: &str, identity: usize) -> Self {
        Face {
            name: name.to_string(),
            identity,
            mesh: [None, None],
            gt_lm: None,
            pts: [Vec::new(), Vec::new()],
            desc: [Err(String::new()), Err(String::new())],
            det_err: None,
            prepare_notes: Vec::new(),
            valid_samples: 0,
            vertices: 0,
            secs: [0.0; 4],
        }
    }
}

/// What describing a face needs: the model, the landmark model, the geodesic method, the
/// description, scan and preparation settings, the ICP points per probe and the folder
/// `--save-scans` writes the raw scans to.
#[derive(Clone, Copy)]
pub(super) struct Pipeline<'a> {
    pub(super) model: &'a FaceModel,
    pub(super) generic: &'a GenericModel,
    pub(super) method: Method,
    pub(super) dopt: &'a DescribeOptions,
    pub(super) scan_opts: &'a ScanSetOptions,
    pub(super) prep: &'a facematch::MatchOptions,
    pub(super) icp_n: usize,
    pub(super) save: Option<&'a std::path::Path>,
}

impl Pipeline<'_> {
    /// Scans, cleans, detects and describes every face (in parallel, in order); gallery faces
    /// (`keep_mesh`) keep their meshes.
    pub(super) fn process(&self, specs: &[FaceSpec], keep_mesh: bool, msg: &str) -> Vec<Face> {
        par_map(specs, msg, |spec| self.describe_spec(spec, keep_mesh))
    }

    /// Scans the face of `spec`; cleans it for the ground-truth landmarks (crop around the true
    /// nose tip) and prepares it as a user would for the detected ones
    /// ([`facematch::prepare_with`]: crop around the detected nose tip, no ground truth);
    /// describes both.
    fn describe_spec(&self, spec: &FaceSpec, keep_mesh: bool) -> Face {
        let Pipeline {
            model,
            generic,
            method,
            dopt,
            scan_opts,
            prep,
            icp_n,
            save,
        } = *self;
        let mut face = Face::new(&spec.name, spec.identity);
        let gt_opts = ScanSetOptions {
            detect: None,
            ..scan_opts.clone()
        };
        let scanned = scan_raw(model, spec).and_then(|(raw, t_scan)| {
            let s = clean_scan(&raw, t_scan, generic, &gt_opts)?;
            Ok((raw, s))
        });
        let saved = |raw: &rangescan::Scan| match save {
            Some(dir) => mesh_io::write_bnt(dir.join(format!("{}.bnt", spec.name)), &raw.grid)
                .map_err(anyhow::Error::from),
            None => Ok(()),
        };
        let (raw, s) = match scanned.and_then(|(raw, s)| saved(&raw).map(|()| (raw, s))) {
            Ok(x) => x,
            Err(e) => {
                let e = format!("scan, cleaning or saving: {e:#}");
                face.desc = [Err(e.clone()), Err(e)];
                return face;
            }
        };
        let t = Instant::now();
        let prepared =
            facematch::prepare_with(facematch::ScanInput::Grid(&raw.grid), generic, prep)
                .map_err(|e| format!("prepare: {e}"));
        face.secs[2] = t.elapsed().as_secs_f64();
        face.valid_samples = s.valid_samples;
        face.vertices = s.mesh.n_vertices();
        face.secs[0] = s.times.scan.as_secs_f64();
        face.secs[1] = s.times.clean.as_secs_f64();
        if let Ok(p) = &prepared {
            // An unseen landmark counts as infinitely far off; none when the truth is off the scan.
            face.det_err = s.truth_vertices().is_ok().then(|| {
                detection_errors(&raw.landmarks, &p.detected).map(|e| e.unwrap_or(f64::INFINITY))
            });
            face.prepare_notes = p.notes.clone();
        }
        drop(raw);
        // The reference-point search is the probes' (the gallery keeps its one description).
        let gallery_opts = dopt.without_search();
        let dopt = if keep_mesh { &gallery_opts } else { dopt };
        let allow_lost = dopt.matching.side_pair_deg.is_some();
        let t = Instant::now();
        let lms = [
            truth_lm(&s, allow_lost),
            prepared.as_ref().map_err(Clone::clone).and_then(|p| {
                Lm::from_detected(
                    &p.mesh,
                    &p.detected,
                    allow_lost,
                    dopt.matching.predicted_corners,
                    MAX_SNAP_MM,
                )
            }),
        ];
        face.gt_lm = lms[0].as_ref().ok().copied();
        let meshes: [Result<TriMesh, String>; 2] = [Ok(s.mesh), prepared.map(|p| p.mesh)];
        for k in 0..2 {
            let (Ok(mesh), Ok(lm)) = (&meshes[k], &lms[k]) else {
                face.desc[k] = Err(lms[k].clone().err().unwrap_or_default());
                continue;
            };
            face.pts[k] = icp_points(mesh, icp_n);
            face.desc[k] = geodesic::new_solver(mesh, method)
                .map_err(|e| format!("geodesic solver: {e}"))
                .and_then(|solver| {
                    describe_face(mesh, solver.as_ref(), &Walker::new(mesh), *lm, dopt)
                });
            if let (true, Some(view), Ok(d)) = (keep_mesh, &dopt.matching.view, &mut face.desc[k]) {
                // The gallery face's template views (facematch's, computed once).
                let matching = facematch::MatchOptions {
                    method,
                    ..dopt.matching.clone()
                };
                let views = facematch::views_of(mesh, *lm, SCANNER_SIDE, &matching, view);
                d.views = Some((views, view.clone()));
            }
        }
        face.secs[3] = t.elapsed().as_secs_f64();
        if keep_mesh {
            face.mesh = meshes.map(Result::ok);
        }
        face
    }
}

/// The ground-truth landmarks of a scan ([`Lm::from_parts`]; a corner off the cleaned scan,
/// see [`ScannedFace::truth_vertices`], may be lost).
fn truth_lm(s: &ScannedFace, allow_lost: bool) -> Result<Lm, String> {
    use landmarks::LandmarkName as L;
    let v = |n: L| s.truth_vertex(n);
    let at = |n: L| s.truth[n as usize].position;
    Lm::from_parts(
        [v(L::OuterEyeRight), v(L::OuterEyeLeft), v(L::NoseTip)],
        [at(L::OuterEyeRight), at(L::OuterEyeLeft)],
        allow_lost,
    )
}
