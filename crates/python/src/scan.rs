//! `scan` (the virtual range scanner of `rangescan`) and `clean` (scan preparation of
//! `scanprep`).

use crate::convert;
use crate::errors;
use crate::mesh::{mesh_arg, PyMesh};
use glam::DVec3;
use meshcore::units::Units;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rangescan::{Artifacts, HeadPose, Projection, ScanOptions};
use scanprep::{CleanOptions, Crop, Input};

fn units_arg(units: Option<&str>) -> PyResult<Option<Units>> {
    units
        .map(|u| u.parse::<Units>().map_err(|e| errors::input(e.to_string())))
        .transpose()
}

/// Scans a mesh into a Bosphorus-style range grid (mm) and returns it as a mesh (triangulated
/// as ``read_bnt`` does; ``grid_index`` maps vertices to samples), with a dict of what the
/// scanner did.
///
/// ``units`` of the input (``"mm"``, ``"cm"``, ``"m"``; default: recognised from the face
/// size), ``pitch`` sample spacing in mm, ``yaw`` / ``pitch_angle`` head rotation in degrees,
/// ``pinhole`` the distance (mm) of a pinhole camera in front of the face (default:
/// orthographic), ``artifacts`` ``"none"`` or
/// ``"structured-light"`` (noise, quantisation, spikes, outliers, dropouts, holes), ``seed``
/// of every random choice (the same arguments give the same scan).
#[pyfunction]
#[pyo3(signature = (mesh, *, units=None, pitch=0.5, yaw=0.0, pitch_angle=0.0, pinhole=None,
                    artifacts="none", seed=0))]
#[allow(clippy::too_many_arguments)]
pub fn scan<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    units: Option<&str>,
    pitch: f64,
    yaw: f64,
    pitch_angle: f64,
    pinhole: Option<f64>,
    artifacts: &str,
    seed: u64,
) -> PyResult<(PyMesh, Bound<'py, PyDict>)> {
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    let units = match units_arg(units)? {
        Some(u) => u,
        None => {
            meshcore::units::detect_units(mesh)
                .map_err(|e| errors::input(e.to_string()))?
                .units
        }
    };
    let artifacts = match artifacts {
        "none" => Artifacts::none(),
        "structured-light" | "structured_light" => Artifacts::structured_light(),
        o => {
            return Err(errors::input(format!(
                "unknown artifacts {o:?} (expected none or structured-light)"
            )))
        }
    };
    let projection = match pinhole {
        Some(d) => Projection::Pinhole { distance_mm: d },
        None => Projection::Orthographic,
    };
    let opts = ScanOptions {
        input_mm_per_unit: units.mm_per_unit(),
        pitch_mm: pitch,
        projection,
        pose: HeadPose {
            yaw_deg: yaw,
            pitch_deg: pitch_angle,
        },
        artifacts,
        seed,
        ..ScanOptions::default()
    };
    let s = py
        .detach(|| rangescan::scan(mesh, &opts))
        .map_err(errors::scan)?;
    let loaded = py
        .detach(|| mesh_io::bnt_grid_to_mesh(&s.grid, &mesh_io::BntOptions::default()))
        .map_err(errors::io)?;
    let info = PyDict::new(py);
    info.set_item("input_units", units.to_string())?;
    info.set_item("rows", s.grid.nrows)?;
    info.set_item("cols", s.grid.ncols)?;
    info.set_item("valid_samples", s.n_valid())?;
    info.set_item("stats", format!("{:?}", s.stats))?;
    Ok((PyMesh { loaded }, info))
}

/// Prepares a scan mesh (``scanprep::clean``): spikes, small components, holes up to
/// ``max_hole`` mm, optional crop to a sphere of ``crop_radius`` mm around ``crop_center``
/// (input units and frame, e.g. the nose tip), ``smooth`` Taubin iterations, optional
/// decimation to ``target_edge`` mm. ``units`` of the input (default: recognised from the face
/// size). Returns the clean mesh in mm and a report dict (``units``, ``summary`` lines,
/// ``holes_filled``, ``output_vertices``, ``mean_edge_mm``).
#[pyfunction]
#[pyo3(signature = (mesh, *, units=None, crop_center=None, crop_radius=100.0, max_hole=10.0,
                    smooth=0, target_edge=None))]
#[allow(clippy::too_many_arguments)]
pub fn clean<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    units: Option<&str>,
    crop_center: Option<&Bound<'py, PyAny>>,
    crop_radius: f64,
    max_hole: f64,
    smooth: usize,
    target_edge: Option<f64>,
) -> PyResult<(PyMesh, Bound<'py, PyDict>)> {
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    let crop = match crop_center {
        Some(c) => {
            let centre: DVec3 = convert::point(c, "crop_center")?;
            Some(Crop {
                centre,
                radius_mm: crop_radius,
            })
        }
        None => None,
    };
    let opts = CleanOptions {
        units: units_arg(units)?,
        max_hole_diameter_mm: (max_hole > 0.0).then_some(max_hole),
        crop,
        smoothing_iterations: smooth,
        target_edge_mm: target_edge,
        ..CleanOptions::default()
    };
    let c = py
        .detach(|| scanprep::clean(Input::Mesh(mesh), &opts))
        .map_err(errors::scanprep)?;
    let report = PyDict::new(py);
    report.set_item("units", c.report.units.used.to_string())?;
    report.set_item("summary", c.report.summary())?;
    report.set_item("holes_filled", c.report.holes_filled())?;
    report.set_item("output_vertices", c.report.output.0)?;
    report.set_item("mean_edge_mm", c.report.mean_edge_mm)?;
    let loaded = mesh_io::LoadedMesh::new(c.mesh);
    Ok((PyMesh { loaded }, report))
}

/// Which faces of ``mesh`` a range scanner looking from ``toward_viewer`` (the direction from
/// the surface to the scanner, in the mesh's frame; parallel rays) would measure: a face whose
/// normal is within ``max_incidence`` degrees of that direction and none of whose vertices is
/// hidden behind nearer surface (``rangescan::visible_faces``). ``pitch`` is the sample spacing
/// of the occlusion z-buffer in mesh units (default: a third of the mean edge length). Returns a
/// bool array, one entry per face: ``mesh.faces[mask]`` is the part such a scan would hold.
/// Used to compare a probe scan with a gallery face as the probe's scanner would have seen it
/// (docs/scans.md, "View matching").
#[pyfunction]
#[pyo3(signature = (mesh, toward_viewer, *, pitch=None, max_incidence=75.0))]
pub fn visible_faces<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    toward_viewer: &Bound<'py, PyAny>,
    pitch: Option<f64>,
    max_incidence: f64,
) -> PyResult<Bound<'py, numpy::PyArray1<bool>>> {
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    let toward: DVec3 = convert::point(toward_viewer, "toward_viewer")?;
    let pitch = pitch.unwrap_or_else(|| mesh.mean_edge_length() / 3.0);
    let seen = py
        .detach(|| rangescan::visible_faces(mesh, toward, pitch, max_incidence))
        .map_err(errors::scan)?;
    Ok(convert::vec_out(py, seen))
}
