//! Python bindings of the bipolar workspace: the extension module `bipolar._bipolar`.
//!
//! This crate only converts (numpy arrays, Python arguments, library errors as exceptions) and
//! calls the library crates; it has no algorithm of its own. The Python package around it is
//! `python/bipolar` (re-exports, the `gdist` drop-in, Dask helpers, typed stubs).
//!
//! Every call that computes releases the GIL. Nothing panics on user input: arrays are checked
//! for type, dtype, shape and index range here, values by the libraries.

// First: the macros of the modules below.
#[macro_use]
mod wrapper;

mod convert;
mod curves;
mod describe;
mod descriptor;
mod distance;
mod errors;
mod geodesic;
mod landmark;
mod matching;
mod mesh;
mod polar;
mod scan;

use pyo3::prelude::*;

#[pymodule]
fn _bipolar(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("LANDMARK_NAMES", landmark::names())?;
    m.add("VERIFY_THRESHOLD", facematch::VERIFY_THRESHOLD)?;
    m.add_class::<mesh::PyMesh>()?;
    m.add_class::<geodesic::PyGeodesicSolver>()?;
    m.add_class::<descriptor::PyDescriptor>()?;
    m.add_class::<distance::PyDistanceOptions>()?;
    m.add_class::<polar::PyPolarDescriptor>()?;
    m.add_class::<curves::PyFacialCurves>()?;
    m.add_class::<curves::PyIsoCurvatureCurves>()?;
    m.add_function(wrap_pyfunction!(mesh::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_mesh_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::write_ply, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_bnt, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_landmarks, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_ict_landmarks, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_lm2, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::write_lm3, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::icosphere, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::uv_sphere, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::grid_plane, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::_mesh_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(describe::describe, m)?)?;
    m.add_function(wrap_pyfunction!(describe::_describe_profiled, m)?)?;
    m.add_function(wrap_pyfunction!(polar::describe_polar, m)?)?;
    m.add_function(wrap_pyfunction!(polar::polar_distance, m)?)?;
    m.add_function(wrap_pyfunction!(polar::unpack_polar_key, m)?)?;
    m.add_function(wrap_pyfunction!(descriptor::read_descriptor, m)?)?;
    m.add_function(wrap_pyfunction!(descriptor::pack_key, m)?)?;
    m.add_function(wrap_pyfunction!(descriptor::unpack_key, m)?)?;
    m.add_function(wrap_pyfunction!(descriptor::_descriptor_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(distance::distance, m)?)?;
    m.add_function(wrap_pyfunction!(distance::distance_details, m)?)?;
    m.add_function(wrap_pyfunction!(distance::distance_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(distance::cross_distances, m)?)?;
    m.add_function(wrap_pyfunction!(distance::searched_distance, m)?)?;
    m.add_function(wrap_pyfunction!(distance::_distance_options_from_dict, m)?)?;
    m.add_function(wrap_pyfunction!(landmark::detect_landmarks, m)?)?;
    m.add_function(wrap_pyfunction!(scan::scan, m)?)?;
    m.add_function(wrap_pyfunction!(scan::clean, m)?)?;
    m.add_function(wrap_pyfunction!(scan::visible_faces, m)?)?;
    m.add_function(wrap_pyfunction!(curves::facial_curves, m)?)?;
    m.add_function(wrap_pyfunction!(curves::iso_curvature_curves, m)?)?;
    m.add_function(wrap_pyfunction!(curves::facial_curves_distance, m)?)?;
    m.add_function(wrap_pyfunction!(curves::iso_curvature_distance, m)?)?;
    m.add_function(wrap_pyfunction!(curves::elastic_distance, m)?)?;
    matching::register(m)?;
    Ok(())
}
