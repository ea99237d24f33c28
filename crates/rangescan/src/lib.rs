//! A virtual range scanner: renders a triangle mesh from a viewpoint into a range grid (the
//! Bosphorus `.bnt` layout of [`mesh_io::BntGrid`], millimetres) with a switchable, sized
//! artifact model, and projects ground-truth landmarks onto the scan with their visibility.
//!
//! * Geometry ([`ScanOptions`]): the input mesh is converted to mm
//!   ([`ScanOptions::input_mm_per_unit`]), turned by a head rotation ([`HeadPose`]: yaw about
//!   the vertical `y` axis, then pitch about `x`, around the centre of its bounding box) and
//!   seen by a camera on the `+z` side looking along `-z`, with an orthographic or a pinhole
//!   [`Projection`] and a sample pitch in mm. The scan frame is the input frame (`y` up, `z`
//!   towards the scanner) after the rotation, in mm.
//! * Rendering ([`scan`]): every triangle is rasterised into the grid with a z-buffer, so parts
//!   hidden behind nearer surface (the far cheek of a turned head, a box in front of a plane)
//!   leave no samples; each sample is the exact intersection of its ray with the nearest
//!   triangle.
//! * Artifacts ([`Artifacts`]), each off (`None`) or sized: dropouts at grazing incidence,
//!   random holes, a cropped border, Gaussian depth noise, spikes, background outliers and
//!   depth quantisation. Each draws from its own random stream of one `ChaCha8Rng` seed, and
//!   per-sample draws are made for every sample in grid order, so switching one artifact on or
//!   off changes nothing that another one did.
//! * Landmarks ([`ScanOptions`] with [`scan_with_landmarks`]): each labelled point is carried
//!   into the scan frame and classified ([`Visibility`]): visible, occluded (a surface nearer
//!   to the scanner along its ray), in a hole, dropped at a grazing angle, cut by the border,
//!   or outside the grid.
//! * Visibility ([`visible_faces`]): the faces of a mesh a scanner would measure from a given
//!   direction (occlusion and an incidence limit), as a mask of the mesh itself.
//! * Flying pixels ([`add_flying_pixels`]): the depths between a silhouette and its background
//!   that time-of-flight and stereo depth cameras return, added to a scanned grid.
//! * Benchmark settings ([`ScanSettings`]): pitch, noise, quantisation, the structured-light
//!   spikes and holes on or off and the head pose, as [`ScanOptions`]; [`scan_seed`] gives
//!   each scan of a set its own seed.
//!
//! Library code never panics on user input: bad options or meshes the grid cannot hold end in
//! [`ScanError`].

mod artifacts;
mod camera;
mod flying;
mod render;
mod settings;
mod visibility;

pub use artifacts::{
    Artifacts, Border, DepthNoise, GrazingDropout, Holes, Outliers, Quantisation, Spikes,
};
pub use camera::{HeadPose, Projection};
pub use flying::{add_flying_pixels, FlyingPixels};
pub use settings::{random_scanner, scan_seed, ScanSettings, PROBE_NOISE_MM};
pub use visibility::visible_faces;

use camera::Camera;
use mesh_io::BntGrid;
use meshcore::{DAffine3, DVec3, TriMesh};

/// The background sentinel written into `.bnt` grids (the Bosphorus value).
pub const BACKGROUND: f64 = -1e9;

/// Errors of the scanner.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// An option is out of its range (named, with the value and the range).
    #[error("invalid scan option: {0}")]
    InvalidOption(String),
    /// The grid the options ask for is too large (usually the input unit is wrong).
    #[error("{0}")]
    GridTooLarge(String),
    /// No triangle is in view: the grid would hold no sample.
    #[error("the mesh leaves no sample in the range grid (nothing in view)")]
    NothingInView,
    /// A landmark is not finite.
    #[error("landmark {label:?} has a non-finite coordinate")]
    BadLandmark {
        /// Its label.
        label: String,
    },
}

/// Everything that defines a scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanOptions {
    /// Millimetres per input unit (`10` for a mesh in cm, `1` in mm, `1000` in m).
    pub input_mm_per_unit: f64,
    /// Sample pitch in mm (Bosphorus: 0.3-0.8). For the pinhole camera it is the pitch on the
    /// plane through the point of the mesh nearest to the scanner. Allowed: 0.05 to 20.
    pub pitch_mm: f64,
    /// Camera model.
    pub projection: Projection,
    /// Head rotation applied before scanning.
    pub pose: HeadPose,
    /// Background samples kept around the object's silhouette on every side of the grid.
    pub margin: usize,
    /// The artifact model.
    pub artifacts: Artifacts,
    /// Seed of every random choice.
    pub seed: u64,
    /// Name written as the texture image of the `.bnt` file (no texture is written).
    pub image_file: String,
}

impl Default for ScanOptions {
    /// Input in mm, 0.5 mm orthographic grid, frontal, no artifacts, seed 0.
    fn default() -> Self {
        Self {
            input_mm_per_unit: 1.0,
            pitch_mm: 0.5,
            projection: Projection::Orthographic,
            pose: HeadPose::default(),
            margin: 2,
            artifacts: Artifacts::none(),
            seed: 0,
            image_file: String::new(),
        }
    }
}

/// Why a sample holds no measurement, or that it holds one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SampleStatus {
    /// A measurement (possibly noisy, quantised, a spike or an outlier).
    Valid,
    /// No surface along the ray.
    Background,
    /// Dropped: the surface is seen at a grazing angle.
    Grazing,
    /// Dropped: inside a random hole.
    Hole,
    /// Dropped: outside the cropped border.
    Border,
}

/// Where a landmark is on the scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Visibility {
    /// The scanner sees it: the sample at its pixel measures the surface it lies on.
    Visible,
    /// A surface nearer to the scanner along its ray hides it.
    Occluded {
        /// How far in front of the landmark the hiding surface is, in mm.
        in_front_mm: f64,
    },
    /// No measured surface at the point: nothing along its ray within 1 mm of it (the point is
    /// off the mesh), or its sample misses the mesh (the point is on the silhouette, between
    /// samples).
    OffSurface,
    /// Its sample was dropped at a grazing angle.
    Grazing,
    /// Its sample is in a hole.
    InHole,
    /// Its sample is outside the cropped border.
    CroppedBorder,
    /// It projects outside the grid.
    OutsideGrid,
}

impl Visibility {
    /// Whether the scanner sees the landmark.
    pub fn is_visible(&self) -> bool {
        matches!(self, Visibility::Visible)
    }
}

impl std::fmt::Display for Visibility {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Visibility::Visible => f.write_str("visible"),
            Visibility::Occluded { in_front_mm } => write!(
                f,
                "occluded (a surface {in_front_mm:.1} mm nearer to the scanner hides it)"
            ),
            Visibility::OffSurface => f.write_str("off the scanned surface"),
            Visibility::Grazing => f.write_str("dropped out (surface seen at a grazing angle)"),
            Visibility::InHole => f.write_str("in a hole of the scan"),
            Visibility::CroppedBorder => f.write_str("outside the cropped border"),
            Visibility::OutsideGrid => f.write_str("outside the range grid"),
        }
    }
}

/// A ground-truth landmark carried onto the scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScannedLandmark {
    /// Label as given.
    pub label: String,
    /// Position in the scan frame (mm): the true point moved by the scan's pose, not a sample.
    pub position: DVec3,
    /// Its grid sample `(row, column)` (nearest pixel), if it projects into the grid.
    pub sample: Option<(usize, usize)>,
    /// Whether and why not the scanner sees it.
    pub visibility: Visibility,
}

/// Counts of what the artifact model did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ScanStats {
    /// Samples the clean rendering measured.
    pub rendered: usize,
    /// Valid samples in the final grid (outliers included).
    pub valid: usize,
    /// Samples dropped at grazing angles.
    pub grazing: usize,
    /// Samples dropped in holes.
    pub holes: usize,
    /// Samples dropped by the border.
    pub border: usize,
    /// Valid samples displaced as spikes.
    pub spikes: usize,
    /// Background samples turned into outliers.
    pub outliers: usize,
}

/// A range scan.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// The grid (mm, background samples at [`BACKGROUND`] in x, y and z).
    pub grid: BntGrid,
    /// Per sample (`row * ncols + col`, row 0 at the top): measurement or why not.
    pub status: Vec<SampleStatus>,
    /// Maps input coordinates (input units) to the scan frame (mm).
    pub scan_from_input: DAffine3,
    /// The landmarks given to [`scan_with_landmarks`], in their order.
    pub landmarks: Vec<ScannedLandmark>,
    /// What the artifact model did.
    pub stats: ScanStats,
}

impl Scan {
    /// Number of valid samples.
    pub fn n_valid(&self) -> usize {
        self.stats.valid
    }
}

/// Scans a mesh (see the crate documentation).
pub fn scan(mesh: &TriMesh, options: &ScanOptions) -> Result<Scan, ScanError> {
    scan_with_landmarks(mesh, &[], options)
}

/// Scans a mesh and classifies labelled points given in the mesh's units (see
/// [`ScannedLandmark`]).
pub fn scan_with_landmarks(
    mesh: &TriMesh,
    landmarks: &[(String, DVec3)],
    options: &ScanOptions,
) -> Result<Scan, ScanError> {
    validate(options)?;
    if let Some((label, _)) = landmarks.iter().find(|(_, p)| !p.is_finite()) {
        return Err(ScanError::BadLandmark {
            label: label.clone(),
        });
    }
    let to_scan = camera::scan_from_input(mesh, options);
    let pos: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| to_scan.transform_point3(*p))
        .collect();
    let cam = Camera::fit(&pos, options)?;
    let hits = render::render(&pos, mesh.triangles(), &cam);
    let rendered_count = hits.iter().filter(|h| h.is_some()).count();
    if rendered_count == 0 {
        return Err(ScanError::NothingInView);
    }
    let mut status: Vec<SampleStatus> = hits
        .iter()
        .map(|h| {
            if h.is_some() {
                SampleStatus::Valid
            } else {
                SampleStatus::Background
            }
        })
        .collect();
    let mut samples = vec![None; hits.len()];
    let stats = artifacts::apply(
        &options.artifacts,
        options.seed,
        &cam,
        &hits,
        &mut samples,
        &mut status,
    );
    let stats = ScanStats {
        rendered: rendered_count,
        ..stats
    };
    let marks = landmarks
        .iter()
        .map(|(label, p)| {
            let q = to_scan.transform_point3(*p);
            let (sample, visibility) =
                render::classify_landmark(q, &pos, mesh.triangles(), &cam, &status);
            ScannedLandmark {
                label: label.clone(),
                position: q,
                sample,
                visibility,
            }
        })
        .collect();
    let n = cam.nrows * cam.ncols;
    let mut xyz = vec![DVec3::splat(BACKGROUND); n];
    let mut uv = vec![[0.0; 2]; n];
    for i in 0..n {
        let (r, c) = (i / cam.ncols, i % cam.ncols);
        uv[i] = [c as f64 / cam.ncols as f64, r as f64 / cam.nrows as f64];
        if let Some(p) = samples[i] {
            xyz[i] = p;
        }
    }
    Ok(Scan {
        grid: BntGrid {
            nrows: cam.nrows,
            ncols: cam.ncols,
            zmin: BACKGROUND,
            image_file: options.image_file.clone(),
            xyz,
            uv,
        },
        status,
        scan_from_input: to_scan,
        landmarks: marks,
        stats,
    })
}

fn check(name: &str, v: f64, lo: f64, hi: f64) -> Result<(), ScanError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(ScanError::InvalidOption(format!(
            "{name} = {v} (expected {lo} to {hi})"
        )))
    }
}

fn validate(o: &ScanOptions) -> Result<(), ScanError> {
    check("input_mm_per_unit", o.input_mm_per_unit, 1e-6, 1e6)?;
    check("pitch_mm", o.pitch_mm, 0.05, 20.0)?;
    check("pose.yaw_deg", o.pose.yaw_deg, -180.0, 180.0)?;
    check("pose.pitch_deg", o.pose.pitch_deg, -90.0, 90.0)?;
    if let Projection::Pinhole { distance_mm } = o.projection {
        check("projection distance_mm", distance_mm, 10.0, 1e5)?;
    }
    if o.margin > 1000 {
        return Err(ScanError::InvalidOption(format!(
            "margin = {} samples (expected at most 1000)",
            o.margin
        )));
    }
    if o.image_file.len() > u16::MAX as usize {
        return Err(ScanError::InvalidOption("image_file name too long".into()));
    }
    o.artifacts.validate()
}
