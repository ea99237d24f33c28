//! A scan prepared for matching: cleaned, cropped around the detected nose tip, its landmarks.

use crate::{Description, MatchError, MatchOptions, Poles, PrepareOptions, GRID_SCANNER};
use landmarks::{DetectOptions, GenericModel, LandmarkName, VisibleLandmarks};
use mesh_io::BntGrid;
use meshcore::units::Units;
use meshcore::{DVec3, TriMesh};
use scanprep::{CleanOptions, Crop, Input};
use std::time::{Duration, Instant};

/// What a face is prepared from.
#[derive(Debug, Clone, Copy)]
pub enum ScanInput<'a> {
    /// A range grid (`.bnt`, mm): the scanner looks down its z axis ([`GRID_SCANNER`]).
    Grid(&'a BntGrid),
    /// A mesh in any units (`None`: recognised from the face's size) with the direction toward
    /// its scanner where known (`None`: `+z` is taken, and the prepared scan says so).
    Mesh {
        /// The mesh.
        mesh: &'a TriMesh,
        /// Its units.
        units: Option<Units>,
        /// The direction toward its scanner.
        scanner: Option<DVec3>,
    },
}

/// Wall time of each step of [`prepare`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepTimes {
    /// The first cleaning (no crop).
    pub clean: Duration,
    /// Detection on it.
    pub detect: Duration,
    /// The crop around the detected nose tip and the rest of the cleaning after it
    /// ([`scanprep::Uncropped::finish`]).
    pub crop_clean: Duration,
    /// Detection on the cropped scan (zero when the crop left the cleaned scan as it was and
    /// the first detection stands).
    pub crop_detect: Duration,
}

/// A scan ready to be described: cleaned (mm), cropped around its detected nose tip, and the
/// landmarks detected on the cropped scan.
#[derive(Debug, Clone)]
pub struct PreparedScan {
    /// The cleaned, cropped scan (mm, the input's frame scaled).
    pub mesh: TriMesh,
    /// The direction toward the scanner (unit).
    pub scanner: DVec3,
    /// The units the input was read in.
    pub units: Units,
    /// The landmarks detected on `mesh` (those the scanner did not see reported unseen).
    pub detected: VisibleLandmarks,
    /// What was assumed or substituted (a default scanner direction, no crop possible, ...).
    pub notes: Vec<String>,
    /// Step times.
    pub times: StepTimes,
}

/// [`prepare_with`] with the default generic landmark model.
pub fn prepare(input: ScanInput<'_>, options: &MatchOptions) -> Result<PreparedScan, MatchError> {
    let generic = GenericModel::default_model()
        .map_err(|e| MatchError::Landmarks(format!("the generic model: {e}")))?;
    prepare_with(input, &generic, options)
}

/// Prepares a scan: cleans it (`options.prepare.clean`, no crop), detects the landmarks seen
/// from the scanner, cleans the input again with a crop of `options.prepare.crop_radius_mm`
/// around the detected nose tip and detects again on the cropped scan. When no face is found
/// on the uncropped scan, the first detection is repeated on a crop around the point nearest
/// the scanner, and the notes say so. Errors: the cleaning's, and [`MatchError::NoFace`] with
/// the detector's reasons when no face is found.
pub fn prepare_with(
    input: ScanInput<'_>,
    generic: &GenericModel,
    options: &MatchOptions,
) -> Result<PreparedScan, MatchError> {
    options.validate()?;
    let p = &options.prepare;
    let mut notes = Vec::new();
    let (scan_input, units, scanner) = match input {
        ScanInput::Grid(g) => (Input::Grid(g), Some(Units::Millimetre), GRID_SCANNER),
        ScanInput::Mesh {
            mesh,
            units,
            scanner,
        } => {
            let s = match scanner.map(DVec3::normalize_or_zero) {
                Some(s) if s.is_finite() && s != DVec3::ZERO => s,
                Some(s) => {
                    return Err(MatchError::InvalidOption(format!(
                        "scanner direction {s:?} (a finite, non-zero vector)"
                    )))
                }
                None => {
                    notes.push(
                        "no scanner direction given: +z taken (the direction toward the scanner decides what counts as seen)"
                            .to_string(),
                    );
                    DVec3::Z
                }
            };
            (Input::Mesh(mesh), units, s)
        }
    };
    let clean_opts = CleanOptions {
        units: units.or(p.clean.units),
        crop: None,
        ..p.clean.clone()
    };
    let t0 = Instant::now();
    // The steps before the crop run once; each crop below finishes them (bit for bit what a
    // whole `scanprep::clean` with that crop gives).
    let staged = scanprep::clean_uncropped(scan_input, &clean_opts)?;
    let first = staged.finish(None)?;
    let used = staged.units();
    let t1 = Instant::now();
    let first_found = detect(&first.mesh, generic, scanner, p);
    let (found, found_on) = match (first_found, p.crop_radius_mm) {
        (Ok(f), _) => (f, first.mesh),
        (Err(MatchError::NoFace(why)), Some(radius_mm)) => {
            // A wide scan (shoulders, hair, a second head) can hide the face from the
            // detector: crop around the point nearest the scanner (on a face seen from the
            // front, at or near the nose) and look again. Said in the notes.
            let near = first
                .mesh
                .positions()
                .iter()
                .copied()
                .max_by(|a, b| a.dot(scanner).total_cmp(&b.dot(scanner)))
                .ok_or_else(|| MatchError::NoFace("the cleaned scan is empty".into()))?;
            let around = staged.finish(Some(Crop {
                centre: near / used.mm_per_unit(),
                radius_mm,
            }))?;
            let f = detect(&around.mesh, generic, scanner, p).map_err(|e| {
                MatchError::NoFace(format!(
                    "{why}; cropped around the point nearest the scanner: {}",
                    match e {
                        MatchError::NoFace(w) => w,
                        e => e.to_string(),
                    }
                ))
            })?;
            notes.push(format!(
                "no face found on the uncropped scan ({why}): found after a crop of {radius_mm} mm around the point nearest the scanner"
            ));
            (f, around.mesh)
        }
        (Err(e), _) => return Err(e),
    };
    let t2 = Instant::now();
    let done = |mesh, detected, crop_clean, crop_detect| PreparedScan {
        mesh,
        scanner,
        units: used,
        detected,
        notes,
        times: StepTimes {
            clean: t1 - t0,
            detect: t2 - t1,
            crop_clean,
            crop_detect,
        },
    };
    let Some(radius_mm) = p.crop_radius_mm else {
        return Ok(done(found_on, found, Duration::ZERO, Duration::ZERO));
    };
    // The crop's centre in the input's units and frame.
    let nose_mm = found_on.position(
        found
            .get(LandmarkName::NoseTip)
            .map_err(|u| MatchError::NoFace(format!("the nose tip is {u}")))?
            .vertex,
    );
    if p.crop_keeps_detection {
        let (mesh, detected) = crop_keeping(&found_on, found, nose_mm, radius_mm, &p.clean)?;
        return Ok(done(mesh, detected, t2.elapsed(), Duration::ZERO));
    }
    let centre = nose_mm / used.mm_per_unit();
    let cropped = staged.finish(Some(Crop { centre, radius_mm }))?;
    let t3 = Instant::now();
    // A crop that changed nothing (a scan already cut to the face) gives the mesh the first
    // detection ran on, and detection is deterministic: its landmarks stand.
    let (detected, crop_detect) = if cropped.mesh == found_on {
        (found, Duration::ZERO)
    } else {
        (detect(&cropped.mesh, generic, scanner, p)?, t3.elapsed())
    };
    Ok(done(cropped.mesh, detected, t3 - t2, crop_detect))
}

/// `mesh` cropped to `radius_mm` around `centre` (mm) and cleared of the small components the
/// crop leaves (`clean.min_component_ratio`), with `found`'s landmarks carried to the kept
/// vertices. A placed landmark the crop removes is [`MatchError::Landmarks`] naming it.
fn crop_keeping(
    mesh: &TriMesh,
    mut found: VisibleLandmarks,
    centre: DVec3,
    radius_mm: f64,
    clean: &CleanOptions,
) -> Result<(TriMesh, VisibleLandmarks), MatchError> {
    let (mut cropped, _) = scanprep::crop_sphere(mesh, centre, radius_mm)?;
    if let Some(r) = clean.min_component_ratio {
        cropped = scanprep::remove_small_components(&cropped, r)?.0;
    }
    // Both steps only drop vertices: each kept one is found in `mesh`.
    let mut new_of = vec![None; mesh.n_vertices()];
    let kept = scanprep::surviving_vertices(mesh, &cropped).ok_or_else(|| {
        MatchError::Landmarks("the crop is not a subset of the cleaned scan".into())
    })?;
    for (new, &old) in kept.iter().enumerate() {
        new_of[old as usize] = Some(new as u32);
    }
    for (name, l) in LandmarkName::ALL.iter().zip(found.landmarks.iter_mut()) {
        if let Ok(l) = l {
            l.vertex = new_of[l.vertex as usize].ok_or_else(|| {
                MatchError::Landmarks(format!(
                    "the {name} is outside the crop of {radius_mm} mm around the nose tip"
                ))
            })?;
        }
    }
    Ok((cropped, found))
}

/// The landmarks seen from `scanner` on `mesh` (mm), as [`detect_landmarks`] finds them with
/// `p`'s detection options and smoothing.
fn detect(
    mesh: &TriMesh,
    generic: &GenericModel,
    scanner: DVec3,
    p: &PrepareOptions,
) -> Result<VisibleLandmarks, MatchError> {
    let options = DetectOptions {
        toward_viewer: Some(scanner),
        ..p.detect
    };
    detect_landmarks(mesh, generic, &options, p.detect_smoothing)
}

/// The landmarks of `mesh` as [`prepare`] detects them: [`landmarks::detect_visible`] with
/// `options` at the scale recognised from the face's size
/// ([`landmarks::mesh_units_per_model_unit`]), on a copy of `mesh` smoothed by `smoothing`
/// Taubin iterations (0: on `mesh` itself), each landmark placed at its vertex of `mesh`.
/// Errors: the smoothing's, and [`MatchError::NoFace`] with the detector's reason.
pub fn detect_landmarks(
    mesh: &TriMesh,
    generic: &GenericModel,
    options: &DetectOptions,
    smoothing: usize,
) -> Result<VisibleLandmarks, MatchError> {
    let smoothed = match smoothing {
        0 => None,
        k => Some(scanprep::taubin_smooth(mesh, k)?),
    };
    let seen = smoothed.as_ref().unwrap_or(mesh);
    let scale = landmarks::mesh_units_per_model_unit(seen, generic)
        .map_err(|e| MatchError::NoFace(e.to_string()))?;
    let mut found = landmarks::detect_visible(
        seen,
        generic,
        &DetectOptions {
            mesh_units_per_model_unit: scale,
            ..*options
        },
    )
    .map_err(|e| MatchError::NoFace(e.to_string()))?;
    for l in found.landmarks.iter_mut().flatten() {
        l.position = mesh.position(l.vertex);
    }
    Ok(found)
}

impl PreparedScan {
    /// The poles from the detected landmarks ([`Poles::from_detected`]: with side pairs on, an
    /// unseen outer corner is lost; with `predicted_corners`, placed at its prediction when
    /// within `snap_mm`).
    pub fn poles(&self, options: &MatchOptions) -> Result<Poles, MatchError> {
        Poles::from_detected(
            &self.mesh,
            &self.detected,
            options.side_pair_deg.is_some(),
            options.predicted_corners,
            options.snap_mm,
        )
        .map_err(MatchError::Landmarks)
    }

    /// The scan's descriptions from its detected poles ([`crate::describe`]; with `search`, the
    /// probe's reference-point search).
    pub fn describe(
        &self,
        options: &MatchOptions,
        search: bool,
    ) -> Result<Description, MatchError> {
        let poles = self.poles(options)?;
        crate::describe(&self.mesh, poles, self.scanner, options, search)
    }
}
