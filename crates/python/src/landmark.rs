//! Automatic landmarks (outer and inner eye corners, nose tip).

use crate::convert::{self, rows_out, vec_out};
use crate::errors;
use crate::mesh::mesh_arg;
use landmarks::{DetectOptions, GenericModel, LandmarkName};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The five landmark names, in the library's order.
pub fn names() -> Vec<&'static str> {
    LandmarkName::ALL.iter().map(|n| n.key()).collect()
}

/// Detects the outer and inner eye corners and the nose tip of a face mesh.
///
/// ``model``: a generic face model JSON path (default: the model shipped with the library,
/// trained on ICT FaceKit faces in cm); ``scale``: mesh units per model unit (10 for a scan in
/// mm with the default model; default: recognised from the size of the face, mm, cm or m); ``min_confidence``: overall confidence below which detection
/// fails (default: the library's); ``toward_viewer``: for a range scan, the direction toward
/// the scanner (3 numbers), so that what the scanner did not see (grazing dropouts, the far
/// side of a turned head) counts as unobserved rather than as a mismatch (default: ``+z`` for
/// a range grid's mesh, from a ``.bnt`` file or ``scan``; none for other meshes). Returns a dict: one entry per placed landmark
/// (``{"vertex", "position", "confidence"}``) under ``"landmarks"``; under ``"unseen"`` the
/// landmarks the scanner did not see (hidden, in a hole), each with the reason, when the face
/// was found without them (``landmarks::detect_visible``); and ``confidence``,
/// ``fit_rms``, ``inlier_fraction``, ``symmetry``, ``model_to_mesh`` (4 x 4 rigid motion).
/// Raises ``LandmarksNotFoundError`` when the mesh does not fit a face.
#[pyfunction]
#[pyo3(signature = (mesh, *, model=None, scale=None, min_confidence=None, toward_viewer=None))]
pub fn detect_landmarks<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    model: Option<&Bound<'py, PyAny>>,
    scale: Option<f64>,
    min_confidence: Option<f64>,
    toward_viewer: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = mesh_arg(mesh)?;
    let toward_viewer = match toward_viewer {
        Some(v) => Some(convert::point(v, "toward_viewer")?),
        None => m.toward_scanner(),
    };
    let mesh = m.mesh();
    let model = match model {
        Some(p) => GenericModel::load(&convert::path(p, "model")?),
        None => GenericModel::default_model(),
    }
    .map_err(errors::landmarks)?;
    let scale = match scale {
        Some(s) => s,
        None => landmarks::mesh_units_per_model_unit(mesh, &model).map_err(errors::landmarks)?,
    };
    let opts = DetectOptions {
        mesh_units_per_model_unit: scale,
        min_confidence: min_confidence.unwrap_or(DetectOptions::default().min_confidence),
        toward_viewer,
        ..DetectOptions::default()
    };
    let lm = py
        .detach(|| landmarks::detect_visible(mesh, &model, &opts))
        .map_err(errors::landmarks)?;
    let out = PyDict::new(py);
    let each = PyDict::new(py);
    let unseen = PyDict::new(py);
    for n in LandmarkName::ALL {
        match lm.get(n) {
            Ok(l) => {
                let d = PyDict::new(py);
                d.set_item("vertex", l.vertex)?;
                d.set_item("position", vec_out(py, l.position.to_array().to_vec()))?;
                d.set_item("confidence", l.confidence)?;
                each.set_item(n.key(), d)?;
            }
            Err(u) => unseen.set_item(n.key(), u.to_string())?,
        }
    }
    out.set_item("landmarks", each)?;
    out.set_item("unseen", unseen)?;
    out.set_item("confidence", lm.confidence)?;
    out.set_item("fit_rms", lm.fit_rms)?;
    out.set_item("inlier_fraction", lm.inlier_fraction)?;
    out.set_item("symmetry", lm.symmetry)?;
    let a = lm.model_to_mesh;
    let (x, y, z, t) = (
        a.matrix3.x_axis,
        a.matrix3.y_axis,
        a.matrix3.z_axis,
        a.translation,
    );
    let flat = vec![
        x.x, y.x, z.x, t.x, x.y, y.y, z.y, t.y, x.z, y.z, z.z, t.z, 0.0, 0.0, 0.0, 1.0,
    ];
    out.set_item("model_to_mesh", rows_out(py, flat, 4))?;
    Ok(out)
}
