//! The section-6 curve representations of `facecurves`: facial curves (level curves of the
//! geodesic distance from the nose tip, compared by the elastic SRVF distance) and
//! iso-curvature curves (level sets of the principal curvatures, compared by ICP).

use crate::convert::{self, points_out};
use crate::describe::{given_landmarks, references};
use crate::errors;
use crate::geodesic::{PyGeodesicSolver, SolverChoice};
use crate::mesh::{mesh_arg, MeshArg};
use facecurves::{
    Aggregate, ElasticOptions, FacialCurvesDescriptor, FacialCurvesOptions, IsoCurvatureDescriptor,
    IsoCurvatureOptions, IsoLevels, Resampling,
};
use geodesic::SolveOptions;
use glam::DVec3;
use meshcore::Surface;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::time::Duration;

/// Facial curves of a face: one curve per level ``i`` at geodesic distance ``i * step`` from
/// the nose tip (the longest piece of the level set).
///
/// ``curves``: a list of dicts ``{"pieces", "level", "closed", "points" (k, 3)}``; ``step`` and
/// ``n_levels`` are the options.
#[pyclass(module = "bipolar._bipolar", name = "FacialCurves", frozen)]
#[derive(Debug, Clone)]
pub struct PyFacialCurves {
    pub d: FacialCurvesDescriptor,
}

descriptor_pymethods! {
    PyFacialCurves,
    levels {
        /// Geodesic distance between consecutive curves.
        step,
        /// Number of levels asked for.
        n_levels
    }
    summary {
        "FacialCurves", curves "curves", step = options.step, levels = options.levels
    }
    {
        /// The curves, sorted by level.
        #[getter]
        fn curves<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
            curve_dicts(py, &self.d.curves, "pieces", |c| {
                (c.pieces, c.level, c.closed, &c.points)
            })
        }
    }
}

/// The iso-curvature network of a surface: level curves of the principal curvatures.
///
/// ``curves``: a list of dicts ``{"field" ("k1" or "k2"), "level", "closed", "points" (k, 3)}``;
/// ``levels_k1``, ``levels_k2``: the levels used; ``k1``, ``k2``: per-vertex curvatures (NaN
/// outside the region).
#[pyclass(module = "bipolar._bipolar", name = "IsoCurvatureCurves", frozen)]
#[derive(Debug, Clone)]
pub struct PyIsoCurvatureCurves {
    pub d: IsoCurvatureDescriptor,
}

#[pymethods]
impl PyIsoCurvatureCurves {
    /// The curves: k1 levels first, then k2.
    #[getter]
    fn curves<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        curve_dicts(py, &self.d.curves, "field", |c| {
            (
                meshcore::Choice::name(c.field),
                c.level,
                c.closed,
                &c.points,
            )
        })
    }

    /// Levels of k1 used.
    #[getter]
    fn levels_k1(&self) -> Vec<f64> {
        self.d.levels_k1.clone()
    }

    /// Levels of k2 used.
    #[getter]
    fn levels_k2(&self) -> Vec<f64> {
        self.d.levels_k2.clone()
    }

    /// Per-vertex maximum principal curvature, shape (n,).
    #[getter]
    fn k1<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        convert::vec_out(py, self.d.k1.clone())
    }

    /// Per-vertex minimum principal curvature, shape (n,).
    #[getter]
    fn k2<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        convert::vec_out(py, self.d.k2.clone())
    }

    fn __len__(&self) -> usize {
        self.d.curves.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "IsoCurvatureCurves({} curves, {} + {} levels)",
            self.d.curves.len(),
            self.d.levels_k1.len(),
            self.d.levels_k2.len()
        )
    }
}

/// The curves of a set as dicts: the entry of their kind (``kind``: the value `parts` gives
/// first), then ``level``, ``closed`` and ``points`` (k, 3).
fn curve_dicts<'py, C, V: IntoPyObject<'py>, L: IntoPyObject<'py>>(
    py: Python<'py>,
    curves: &[C],
    kind: &str,
    parts: impl Fn(&C) -> (V, L, bool, &Vec<DVec3>),
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    curves
        .iter()
        .map(|c| {
            let (value, level, closed, points) = parts(c);
            let d = PyDict::new(py);
            d.set_item(kind, value)?;
            d.set_item("level", level)?;
            d.set_item("closed", closed)?;
            d.set_item("points", points_out(py, points))?;
            Ok(d)
        })
        .collect()
}

/// The geodesic distance field from `centre` (a reference as in ``describe``), cut off just
/// beyond `radius`.
fn centre_field(
    py: Python<'_>,
    m: &MeshArg<'_>,
    centre: &Bound<'_, PyAny>,
    radius: f64,
    method: &str,
    landmarks: Option<&Bound<'_, PyAny>>,
    solver: Option<&Bound<'_, PyGeodesicSolver>>,
) -> PyResult<Vec<f64>> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(errors::input(format!(
            "radius must be positive and finite, got {radius}"
        )));
    }
    let given = landmarks.map(given_landmarks).transpose()?;
    let mut in_library = Duration::ZERO;
    let mesh = m.mesh();
    let src = references(
        py,
        mesh,
        m.toward_scanner(),
        &[("nose".to_string(), centre.clone())],
        given.as_deref(),
        &mut in_library,
    )?[0];
    let choice = SolverChoice::of(method, solver)?;
    let longest = mesh.longest_edge();
    py.detach(|| {
        choice.run(mesh, |solver| {
            solver.distances(
                &[src],
                &SolveOptions {
                    max_distance: Some(radius + longest),
                },
            )
        })
    })
    .map_err(errors::geodesic)
}

/// Facial curves of a face (``facecurves::describe_facial_curves``): ``levels`` level curves
/// of the geodesic distance from ``nose`` (a vertex index, an ``(x, y, z)`` point or a
/// landmark name), the outermost at ``radius``. Geodesic ``method`` or a prepared ``solver``.
#[pyfunction]
#[pyo3(signature = (mesh, nose, *, radius, levels=8, method="exact", landmarks=None, solver=None))]
#[allow(clippy::too_many_arguments)]
pub fn facial_curves(
    py: Python<'_>,
    mesh: &Bound<'_, PyAny>,
    nose: &Bound<'_, PyAny>,
    radius: f64,
    levels: u32,
    method: &str,
    landmarks: Option<&Bound<'_, PyAny>>,
    solver: Option<&Bound<'_, PyGeodesicSolver>>,
) -> PyResult<PyFacialCurves> {
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    if levels == 0 {
        return Err(errors::input("levels must be at least 1"));
    }
    let field = centre_field(py, &m, nose, radius, method, landmarks, solver)?;
    let opts = FacialCurvesOptions {
        step: radius / f64::from(levels),
        levels,
    };
    let d = py.detach(|| {
        let surface = Surface::new(mesh.clone());
        facecurves::describe_facial_curves(&surface, &field, &opts)
    });
    Ok(PyFacialCurves {
        d: d.map_err(errors::facecurves)?,
    })
}

/// The iso-curvature network of a surface (``facecurves::describe_iso_curvature``): level
/// curves of the principal curvatures at ``k1_levels`` / ``k2_levels`` (1 / mesh units), or
/// ``levels`` per field between the 5 % and 95 % quantiles. With ``centre`` and ``radius``,
/// only the vertices within that geodesic distance of ``centre`` are kept. Curvature fits
/// over ``curvature_radius`` mean edge lengths.
#[pyfunction]
#[pyo3(signature = (mesh, *, levels=6, k1_levels=None, k2_levels=None, centre=None,
                    radius=None, curvature_radius=3.0, method="exact", landmarks=None,
                    solver=None))]
#[allow(clippy::too_many_arguments)]
pub fn iso_curvature_curves(
    py: Python<'_>,
    mesh: &Bound<'_, PyAny>,
    levels: usize,
    k1_levels: Option<&Bound<'_, PyAny>>,
    k2_levels: Option<&Bound<'_, PyAny>>,
    centre: Option<&Bound<'_, PyAny>>,
    radius: Option<f64>,
    curvature_radius: f64,
    method: &str,
    landmarks: Option<&Bound<'_, PyAny>>,
    solver: Option<&Bound<'_, PyGeodesicSolver>>,
) -> PyResult<PyIsoCurvatureCurves> {
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    let levels = match (k1_levels, k2_levels) {
        (None, None) => IsoLevels::Quantiles {
            count: levels,
            low: 0.05,
            high: 0.95,
        },
        (a, b) => IsoLevels::Explicit {
            k1: a
                .map(|x| convert::f64_vec(x, "k1_levels"))
                .transpose()?
                .unwrap_or_default(),
            k2: b
                .map(|x| convert::f64_vec(x, "k2_levels"))
                .transpose()?
                .unwrap_or_default(),
        },
    };
    let mask = match (centre, radius) {
        (Some(c), Some(r)) => {
            let u = centre_field(py, &m, c, r, method, landmarks, solver)?;
            Some(u.iter().map(|&d| d <= r).collect::<Vec<bool>>())
        }
        (None, None) => None,
        _ => return Err(errors::input("centre and radius must be given together")),
    };
    let opts = IsoCurvatureOptions {
        radius_edges: curvature_radius,
        levels,
        ..Default::default()
    };
    let d = py.detach(|| {
        let surface = Surface::new(mesh.clone());
        facecurves::describe_iso_curvature(&surface, mask.as_deref(), &opts)
    });
    Ok(PyIsoCurvatureCurves {
        d: d.map_err(errors::facecurves)?,
    })
}

/// Distance of two faces by their facial curves: the elastic (SRVF) distance of each shared
/// level, combined by ``aggregate`` (``"rss"``: root of the sum of squares; ``"sum"``).
/// ``samples`` segments per resampled curve, ``scale`` removes the size of each curve.
#[pyfunction]
#[pyo3(signature = (a, b, *, aggregate="rss", samples=100, scale=false))]
pub fn facial_curves_distance(
    py: Python<'_>,
    a: &Bound<'_, PyFacialCurves>,
    b: &Bound<'_, PyFacialCurves>,
    aggregate: &str,
    samples: usize,
    scale: bool,
) -> PyResult<f64> {
    let agg: Aggregate = aggregate.parse().map_err(errors::facecurves)?;
    let opts = ElasticOptions {
        samples,
        scale,
        ..Default::default()
    };
    let (x, y) = (&a.get().d, &b.get().d);
    py.detach(|| facecurves::facial_curves_distance(x, y, agg, &opts))
        .map(|d| d.distance)
        .map_err(errors::facecurves)
}

/// Distance of two iso-curvature networks: normalised RMS closest-point distance after a
/// global ICP alignment, in [0, 1].
#[pyfunction]
pub fn iso_curvature_distance(
    py: Python<'_>,
    a: &Bound<'_, PyIsoCurvatureCurves>,
    b: &Bound<'_, PyIsoCurvatureCurves>,
) -> PyResult<f64> {
    let (x, y) = (&a.get().d, &b.get().d);
    py.detach(|| facecurves::iso_curvature_distance(x, y, &Default::default()))
        .map(|d| d.stats.rms_normalised)
        .map_err(errors::facecurves)
}

/// Elastic (SRVF) distance between two 3D curves given as (k, 3) arrays, invariant to
/// translation, rotation, reparametrisation (and scale with ``scale``); ``closed`` curves do
/// not repeat their first point. ``resampling``: ``"arc-length"`` or ``"parameter"``.
#[pyfunction]
#[pyo3(signature = (a, b, *, a_closed=false, b_closed=false, samples=100, scale=false,
                    resampling="arc-length"))]
#[allow(clippy::too_many_arguments)]
pub fn elastic_distance(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    a_closed: bool,
    b_closed: bool,
    samples: usize,
    scale: bool,
    resampling: &str,
) -> PyResult<f64> {
    let pa = convert::points(a, "a")?;
    let pb = convert::points(b, "b")?;
    let resampling: Resampling = resampling.parse().map_err(errors::facecurves)?;
    let opts = ElasticOptions {
        samples,
        scale,
        resampling,
        ..Default::default()
    };
    py.detach(|| facecurves::elastic_distance(&pa, a_closed, &pb, b_closed, &opts))
        .map(|m| m.distance)
        .map_err(errors::facecurves)
}
