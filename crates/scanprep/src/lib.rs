//! Scan preparation: turns a raw range grid ([`mesh_io::BntGrid`]) or a scanned mesh into a
//! clean face mesh in millimetres, and reports what each step did.
//!
//! [`clean`] runs, in this order (each step also public on its own):
//!
//! 1. **Units** ([`meshcore::units`]): detected from the face size unless given, reported;
//!    everything after works in mm and the output is in mm.
//! 2. Grid input: **checks** ([`check_grid`]: NaN, sentinel-like values outside the background
//!    rule, empty or mostly-holes grids are errors), **spikes and isolated outliers**
//!    ([`remove_grid_spikes`]: depth jumps against the median of the 5 x 5 neighbours), **small
//!    holes filled** in the grid ([`fill_grid_holes`]: quadratic fit of the rim), then the
//!    grid is **triangulated** ([`mesh_io::bnt_grid_to_mesh`]: long edges across depth jumps
//!    dropped, largest component kept).
//!    Mesh input: **spikes** ([`remove_mesh_spikes`]), **small components**
//!    ([`remove_small_components`]), **small holes filled** ([`fill_mesh_holes`]).
//! 3. **Crop** to a sphere around a given point ([`crop_sphere`]; the usual 3D-face protocol:
//!    100 mm around the nose tip, which the caller gives), then small components again.
//! 4. Optional **smoothing** ([`taubin_smooth`]) and **decimation** to a target edge length
//!    ([`decimate`]).
//!
//! [`remesh`] carries a mesh to another topology of a given edge length (subdivided, then
//! decimated): test faces whose vertices are not a model's.
//!
//! Holes larger than the limit are left and reported ([`Hole::filled`] false). Every step is
//! deterministic (decisions taken on the step's input, fixed orders, ties to smaller indices);
//! only [`CleanReport::timings`] varies between runs. Nothing panics on user input: errors are
//! [`ScanPrepError`].

mod decimate;
mod grid;
mod mesh;
mod remesh;

pub use decimate::{decimate, DecimationReport, COLLAPSE_BELOW, MAX_NEW_EDGE};
pub use grid::{
    check_grid, fill_grid_holes, grid_spacing, remove_grid_spikes, GridCheck, SpikeCounts,
    SpikeOptions, MAX_COORDINATE_MM,
};
pub use mesh::{
    close_mesh_gaps, compact, crop_sphere, fill_mesh_holes, incidence_mask, incidence_masks,
    remove_mesh_spikes, remove_small_components, surviving_vertices, taubin_smooth,
};
pub use remesh::{remesh, MAX_SUBDIVISIONS};

use mesh_io::{BntGrid, BntOptions};
use meshcore::units::{Units, UnitsDetection, UnitsError};
use meshcore::{DVec3, MeshError, TriMesh};
use std::time::{Duration, Instant};

/// Errors of scan preparation.
#[derive(Debug, thiserror::Error)]
pub enum ScanPrepError {
    /// The input is malformed (grid sizes that do not match, a non-finite sentinel).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A grid sample holds NaN or infinity (background samples must hold the sentinel).
    #[error("sample at row {row}, column {col} is not finite (NaN or infinite); background samples must hold the sentinel zmin")]
    NonFinite {
        /// Row (0 at the top).
        row: usize,
        /// Column.
        col: usize,
    },
    /// A sample is not background by the rule (no coordinate equals `zmin`) yet holds a value
    /// no scanner measures: a sentinel the file's `zmin` does not declare.
    #[error("sample at row {row}, column {col} holds {value:e} mm, not a measurement: a background sentinel other than the file's zmin = {zmin:e}?")]
    SentinelLike {
        /// Row.
        row: usize,
        /// Column.
        col: usize,
        /// Its largest absolute coordinate.
        value: f64,
        /// The grid's background sentinel.
        zmin: f64,
    },
    /// Nothing to clean.
    #[error("empty input: {0}")]
    Empty(String),
    /// The scan is mostly holes.
    #[error("the scan is mostly holes: valid samples cover {:.0} % of its silhouette (at least {:.0} % needed)", 100.0 * coverage, 100.0 * min)]
    MostlyHoles {
        /// Valid samples over samples inside the silhouette.
        coverage: f64,
        /// The required coverage.
        min: f64,
    },
    /// A step removed every face.
    #[error("nothing left after {0}")]
    NothingLeft(String),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Units could not be parsed or detected.
    #[error(transparent)]
    Units(#[from] UnitsError),
    /// A mesh could not be built.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The grid could not be triangulated.
    #[error("triangulating the grid: {0}")]
    Triangulation(#[from] mesh_io::IoError),
}

/// A hole found by [`fill_grid_holes`] or [`fill_mesh_holes`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hole {
    /// Grid: missing samples; mesh: vertices of its boundary loop.
    pub size: usize,
    /// Diameter in mm: the largest distance between two samples of its rim (grid) or two
    /// vertices of its boundary loop (mesh).
    pub diameter_mm: f64,
    /// Mean position of its rim (mm).
    pub centre: DVec3,
    /// Whether it was filled.
    pub filled: bool,
}

/// The input of [`clean`].
#[derive(Debug, Clone, Copy)]
pub enum Input<'a> {
    /// A range grid (`.bnt`).
    Grid(&'a BntGrid),
    /// A mesh (any format).
    Mesh(&'a TriMesh),
}

/// A sphere to crop to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crop {
    /// Centre, in the input's units and frame (e.g. the nose tip as the landmarks give it).
    pub centre: DVec3,
    /// Radius in mm.
    pub radius_mm: f64,
}

/// The usual 3D-face protocol's crop radius around the nose tip, mm.
pub const DEFAULT_CROP_RADIUS_MM: f64 = 100.0;

impl Crop {
    /// The protocol's crop: [`DEFAULT_CROP_RADIUS_MM`] around `centre` (input units).
    pub fn around(centre: DVec3) -> Self {
        Self {
            centre,
            radius_mm: DEFAULT_CROP_RADIUS_MM,
        }
    }
}

/// Options of [`clean`]; every step can be switched off.
#[derive(Debug, Clone, PartialEq)]
pub struct CleanOptions {
    /// Units of the input; `None` detects them ([`meshcore::units::detect_units`]).
    pub units: Option<Units>,
    /// Grid input: least coverage of the silhouette by valid samples (default 0.5).
    pub min_coverage: f64,
    /// Grid input: spike and outlier removal (default on).
    pub spikes: Option<SpikeOptions>,
    /// Mesh input: spike factor of [`remove_mesh_spikes`] (default `Some(3.0)`).
    pub mesh_spike_factor: Option<f64>,
    /// Components smaller than this fraction of the largest are removed (default `Some(0.2)`).
    pub min_component_ratio: Option<f64>,
    /// Holes up to this diameter (mm) are filled (default `Some(10.0)`; larger ones are
    /// reported).
    pub max_hole_diameter_mm: Option<f64>,
    /// Crop sphere (default none: the centre comes from the caller).
    pub crop: Option<Crop>,
    /// Taubin smoothing iterations (default 0).
    pub smoothing_iterations: usize,
    /// Target edge length in mm for [`decimate`] (default none).
    pub target_edge_mm: Option<f64>,
}

impl Default for CleanOptions {
    fn default() -> Self {
        Self {
            units: None,
            min_coverage: 0.5,
            spikes: Some(SpikeOptions::default()),
            mesh_spike_factor: Some(3.0),
            min_component_ratio: Some(0.2),
            max_hole_diameter_mm: Some(10.0),
            crop: None,
            smoothing_iterations: 0,
            target_edge_mm: None,
        }
    }
}

/// The units used by [`clean`] and how they were found.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitsReport {
    /// The units the input was read in.
    pub used: Units,
    /// The detection (`Err` with its message when it failed; only possible when the units were
    /// given, which then win).
    pub detected: Result<UnitsDetection, UnitsError>,
    /// Whether the caller gave the units.
    pub overridden: bool,
}

/// What [`clean`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct CleanReport {
    /// Units.
    pub units: UnitsReport,
    /// Grid input: what the checks found.
    pub grid: Option<GridCheck>,
    /// Grid input: spikes and isolated samples removed.
    pub grid_spikes: SpikeCounts,
    /// Mesh input: spike vertices removed.
    pub mesh_spikes: usize,
    /// Small components removed and their vertices.
    pub small_components: (usize, usize),
    /// Every hole found, filled or not.
    pub holes: Vec<Hole>,
    /// Grid input: gaps the triangulation left among valid samples (cells dropped by its
    /// long-edge rule on depth noise), closed by [`close_mesh_gaps`] up to the hole diameter.
    pub gaps_closed: usize,
    /// Vertices removed by the crop.
    pub cropped_vertices: usize,
    /// Smoothing iterations run.
    pub smoothing_iterations: usize,
    /// The decimation, if asked for.
    pub decimation: Option<DecimationReport>,
    /// Vertices and faces of the result.
    pub output: (usize, usize),
    /// Mean edge length of the result (mm).
    pub mean_edge_mm: f64,
    /// Wall time of each step run, in order (the only field that varies between runs).
    pub timings: Vec<(&'static str, Duration)>,
}

impl CleanReport {
    /// Holes filled.
    pub fn holes_filled(&self) -> usize {
        self.holes.iter().filter(|h| h.filled).count()
    }

    /// One line per thing done, for people.
    pub fn summary(&self) -> Vec<String> {
        let mut out = Vec::new();
        let u = &self.units;
        out.push(match (&u.detected, u.overridden) {
            (Ok(d), false) => format!(
                "units: {} (detected: face size {:.4} {} = {:.0} mm); output in mm",
                u.used,
                d.size,
                d.units,
                d.size * d.units.mm_per_unit()
            ),
            (Ok(d), true) => format!(
                "units: {} (given; detection says {} from a face size of {:.4}); output in mm",
                u.used, d.units, d.size
            ),
            (Err(e), _) => format!(
                "units: {} (given; detection failed: {e}); output in mm",
                u.used
            ),
        });
        if let Some(g) = &self.grid {
            out.push(format!(
                "grid: {} samples, {} valid, coverage {:.1} %, spacing {}",
                g.samples,
                g.valid,
                100.0 * g.coverage,
                g.spacing.map_or("-".into(), |s| format!("{s:.3} mm"))
            ));
            out.push(format!(
                "spikes removed: {} (plus {} isolated samples)",
                self.grid_spikes.spikes, self.grid_spikes.isolated
            ));
        } else {
            out.push(format!("spike vertices removed: {}", self.mesh_spikes));
        }
        out.push(format!(
            "small components removed: {} ({} vertices)",
            self.small_components.0, self.small_components.1
        ));
        let left: Vec<String> = self
            .holes
            .iter()
            .filter(|h| !h.filled)
            .map(|h| {
                format!(
                    "{:.1} mm at ({:.1}, {:.1}, {:.1})",
                    h.diameter_mm, h.centre.x, h.centre.y, h.centre.z
                )
            })
            .collect();
        out.push(format!(
            "holes: {} filled, {} left{}",
            self.holes_filled(),
            left.len(),
            if left.is_empty() {
                String::new()
            } else {
                format!(" ({})", left.join("; "))
            }
        ));
        if self.grid.is_some() {
            out.push(format!("triangulation gaps closed: {}", self.gaps_closed));
        }
        out.push(format!("vertices cropped: {}", self.cropped_vertices));
        out.push(format!(
            "smoothing iterations: {}",
            self.smoothing_iterations
        ));
        if let Some(d) = &self.decimation {
            out.push(format!(
                "decimation to {:.3} mm: {} -> {} vertices, mean edge {:.3} -> {:.3} mm",
                d.target_edge,
                d.vertices_before,
                d.vertices_after,
                d.mean_edge_before,
                d.mean_edge_after
            ));
        }
        out.push(format!(
            "result: {} vertices, {} faces, mean edge {:.3} mm",
            self.output.0, self.output.1, self.mean_edge_mm
        ));
        out
    }
}

/// The result of [`clean`].
#[derive(Debug, Clone, PartialEq)]
pub struct Cleaned {
    /// The clean mesh, mm.
    pub mesh: TriMesh,
    /// For grid input: per vertex, its sample `row * ncols + col` (filled samples included);
    /// `None` for mesh input or once decimation moved vertices.
    pub grid_index: Option<Vec<u32>>,
    /// What was done.
    pub report: CleanReport,
}

fn timed<T>(
    timings: &mut Vec<(&'static str, Duration)>,
    name: &'static str,
    f: impl FnOnce() -> T,
) -> T {
    let t = Instant::now();
    let r = f();
    timings.push((name, t.elapsed()));
    r
}

/// Points of a grid's valid samples.
fn valid_points(g: &BntGrid) -> Vec<DVec3> {
    (0..g.xyz.len().min(g.nrows * g.ncols))
        .filter(|&i| g.is_valid(i))
        .map(|i| g.xyz[i])
        .collect()
}

/// Runs the preparation (see the crate docs) on a grid or a mesh: [`clean_uncropped`], then
/// [`Uncropped::finish`] with `o.crop`.
pub fn clean(input: Input<'_>, o: &CleanOptions) -> Result<Cleaned, ScanPrepError> {
    if let Some(c) = &o.crop {
        crop_sphere_check(c)?;
    }
    clean_uncropped(input, o)?.finish(o.crop)
}

/// A scan cleaned up to the crop: units read, spikes removed, holes filled, triangulated,
/// small components removed. [`Uncropped::finish`] crops, smooths and decimates it; one
/// `Uncropped` can be finished with several crops (each result equals [`clean`] with that
/// crop, bit for bit) without repeating the steps before the crop.
#[derive(Debug, Clone)]
pub struct Uncropped {
    mesh: TriMesh,
    grid_index: Option<Vec<u32>>,
    report: CleanReport,
    options: CleanOptions,
}

/// The steps of [`clean`] before the crop (`o.crop` is not used; give the crop to
/// [`Uncropped::finish`]).
pub fn clean_uncropped(input: Input<'_>, o: &CleanOptions) -> Result<Uncropped, ScanPrepError> {
    let mut timings = Vec::new();
    if !(o.min_coverage.is_finite() && (0.0..=1.0).contains(&o.min_coverage)) {
        return Err(ScanPrepError::InvalidOption(format!(
            "min coverage {} (expected 0 to 1)",
            o.min_coverage
        )));
    }
    let mut report = CleanReport {
        units: UnitsReport {
            used: Units::Millimetre,
            detected: Err(UnitsError::NoSize(0.0)),
            overridden: o.units.is_some(),
        },
        grid: None,
        grid_spikes: SpikeCounts::default(),
        mesh_spikes: 0,
        small_components: (0, 0),
        holes: Vec::new(),
        gaps_closed: 0,
        cropped_vertices: 0,
        smoothing_iterations: 0,
        decimation: None,
        output: (0, 0),
        mean_edge_mm: 0.0,
        timings: Vec::new(),
    };
    let resolve = |size: f64, report: &mut CleanReport| -> Result<Units, ScanPrepError> {
        let det = Units::from_face_size(size).map(|units| UnitsDetection { units, size });
        report.units.detected = det.clone();
        let used = match (o.units, det) {
            (Some(u), _) => u,
            (None, Ok(d)) => d.units,
            (None, Err(e)) => return Err(e.into()),
        };
        report.units.used = used;
        Ok(used)
    };
    let (mut mesh, mut grid_index) = match input {
        Input::Grid(g) => {
            let check = timed(&mut timings, "check", || check_grid(g, o.min_coverage))?;
            report.grid = Some(check);
            let size = meshcore::units::robust_diagonal(&valid_points(g));
            let units = resolve(size, &mut report)?;
            let mut g = g.clone();
            let f = units.mm_per_unit();
            if f != 1.0 {
                for i in 0..g.xyz.len() {
                    if g.is_valid(i) {
                        g.xyz[i] *= f;
                    }
                }
                report.grid = Some(check_grid(&g, o.min_coverage)?);
            }
            if let Some(s) = &o.spikes {
                report.grid_spikes =
                    timed(&mut timings, "spikes", || remove_grid_spikes(&mut g, s))?;
            }
            if let Some(d) = o.max_hole_diameter_mm {
                report.holes = timed(&mut timings, "holes", || fill_grid_holes(&mut g, d))?;
            }
            let loaded = timed(&mut timings, "triangulate", || {
                mesh_io::bnt_grid_to_mesh(
                    &g,
                    &BntOptions {
                        largest_component_only: false,
                        ..BntOptions::default()
                    },
                )
            })?;
            (loaded.mesh, loaded.grid_index)
        }
        Input::Mesh(m) => {
            let size = timed(&mut timings, "units", || meshcore::units::face_size(m));
            let units = resolve(size, &mut report)?;
            let f = units.mm_per_unit();
            let mut mesh = if f != 1.0 {
                TriMesh::new(
                    m.positions().iter().map(|p| *p * f).collect(),
                    m.triangles().to_vec(),
                )?
            } else {
                m.clone()
            };
            if let Some(k) = o.mesh_spike_factor {
                let (mm, n) = timed(&mut timings, "spikes", || remove_mesh_spikes(&mesh, k))?;
                mesh = mm;
                report.mesh_spikes = n;
            }
            (mesh, None)
        }
    };
    let is_mesh_input = matches!(input, Input::Mesh(_));
    if let Some(r) = o.min_component_ratio {
        let (m, c, v) = timed(&mut timings, "components", || {
            remove_small_components(&mesh, r)
        })?;
        track_grid_index(&mut grid_index, &mesh, &m);
        mesh = m;
        report.small_components = (c, v);
    }
    if let Some(d) = o.max_hole_diameter_mm {
        if is_mesh_input {
            let (m, holes) = timed(&mut timings, "holes", || fill_mesh_holes(&mesh, d))?;
            mesh = m;
            report.holes = holes;
        } else {
            // The grid's holes are filled; what is left open among valid samples are the cells
            // the triangulation's long-edge rule dropped (depth noise), closed from the same
            // vertices so that the grid index stays.
            let (m, gaps) = timed(&mut timings, "gaps", || close_mesh_gaps(&mesh, d))?;
            mesh = m;
            report.gaps_closed = gaps.iter().filter(|h| h.filled).count();
        }
    }
    report.timings = timings;
    Ok(Uncropped {
        mesh,
        grid_index,
        report,
        options: CleanOptions {
            crop: None,
            ..o.clone()
        },
    })
}

impl Uncropped {
    /// The mesh before the crop (mm).
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The units the input was read in.
    pub fn units(&self) -> Units {
        self.report.units.used
    }

    /// The rest of [`clean`]: the crop (when given; its centre in the input's units), the
    /// small components again after it, smoothing and decimation, with the options given to
    /// [`clean_uncropped`]. The report covers every step, those before the crop included.
    pub fn finish(&self, crop: Option<Crop>) -> Result<Cleaned, ScanPrepError> {
        let o = &self.options;
        let mut report = self.report.clone();
        let mut timings = std::mem::take(&mut report.timings);
        let mut grid_index = self.grid_index.clone();
        let mut mesh = self.mesh.clone();
        if let Some(c) = &crop {
            crop_sphere_check(c)?;
            let centre = c.centre * report.units.used.mm_per_unit();
            let (m, n) = timed(&mut timings, "crop", || {
                crop_sphere(&mesh, centre, c.radius_mm)
            })?;
            track_grid_index(&mut grid_index, &mesh, &m);
            mesh = m;
            report.cropped_vertices = n;
            if let Some(r) = o.min_component_ratio {
                let (m, c, v) = remove_small_components(&mesh, r)?;
                track_grid_index(&mut grid_index, &mesh, &m);
                mesh = m;
                report.small_components.0 += c;
                report.small_components.1 += v;
            }
        }
        if o.smoothing_iterations > 0 {
            mesh = timed(&mut timings, "smooth", || {
                taubin_smooth(&mesh, o.smoothing_iterations)
            })?;
            report.smoothing_iterations = o.smoothing_iterations;
        }
        if let Some(t) = o.target_edge_mm {
            let (m, d) = timed(&mut timings, "decimate", || decimate(&mesh, t))?;
            if d.collapses > 0 {
                grid_index = None;
            }
            mesh = m;
            report.decimation = Some(d);
        }
        report.output = (mesh.n_vertices(), mesh.n_faces());
        report.mean_edge_mm = mesh.mean_edge_length();
        report.timings = timings;
        Ok(Cleaned {
            mesh,
            grid_index,
            report,
        })
    }
}

/// Keeps the grid sample of each vertex that survives a step that only drops vertices
/// ([`surviving_vertices`]). Forgets the index when a vertex cannot be matched.
fn track_grid_index(grid_index: &mut Option<Vec<u32>>, before: &TriMesh, after: &TriMesh) {
    if let Some(gi) = grid_index.take() {
        *grid_index = surviving_vertices(before, after)
            .map(|kept| kept.iter().map(|&k| gi[k as usize]).collect());
    }
}

fn crop_sphere_check(c: &Crop) -> Result<(), ScanPrepError> {
    if !(c.centre.is_finite() && c.radius_mm.is_finite() && c.radius_mm > 0.0) {
        return Err(ScanPrepError::InvalidOption(format!(
            "crop sphere centre {:?}, radius {} mm (expected finite, radius > 0)",
            c.centre.to_array(),
            c.radius_mm
        )));
    }
    Ok(())
}
