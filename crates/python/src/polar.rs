//! `describe_polar`: the single-pole (geodesic polar) descriptor of `bipolar::polar`, and its
//! keyed distance.

use crate::convert::{self, vec_out};
use crate::describe::{given_landmarks, references};
use crate::errors;
use crate::geodesic::{PyGeodesicSolver, SolverChoice};
use crate::mesh::mesh_arg;
use bipolar::{PolarDescriptor, PolarKey, PolarOptions, Source};
use geodesic::{SolveOptions, Walker};
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::time::Duration;

/// A single-pole descriptor: points at geodesic radius ``level * step`` from the pole on
/// ``sectors`` straightest-geodesic rays.
///
/// Arrays (copies): ``points`` (n, 3), ``keys`` (n,) uint64 (``PolarKey`` packing, never equal
/// to a bipolar key), ``levels`` (n,) and ``sectors`` (n,) uint32, ``faces`` (n,) uint32 and
/// ``bary`` (n, 3). Metadata: ``step``, ``n_levels``, ``n_sectors``.
#[pyclass(module = "bipolar._bipolar", name = "PolarDescriptor", frozen)]
#[derive(Debug, Clone)]
pub struct PyPolarDescriptor {
    pub d: PolarDescriptor,
}

descriptor_pymethods! {
    PyPolarDescriptor,
    surface_points {
        keys: keys,
        /// Face of each point, shape (n,), uint32.
        faces
    }
    levels {
        /// Geodesic step between radius levels.
        step,
        /// Number of radius levels asked for.
        n_levels
    }
    summary {
        "PolarDescriptor", points "points", step = options.step, levels = options.levels,
        sectors = options.sectors
    }
    {
        /// Radius level of each point (1-based), shape (n,), uint32.
        #[getter]
        fn levels<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<u32>> {
            vec_out(py, self.d.points.iter().map(|p| p.key.level).collect())
        }

        /// Angular sector of each point, shape (n,), uint32.
        #[getter]
        fn sectors<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<u32>> {
            vec_out(py, self.d.points.iter().map(|p| p.key.sector).collect())
        }

        /// Number of rays.
        #[getter]
        fn n_sectors(&self) -> u32 {
            self.d.options.sectors
        }
    }
}

/// The single-pole descriptor of a mesh (``bipolar::describe_polar``).
///
/// ``pole``: a vertex index, an ``(x, y, z)`` point (snapped to the surface) or a landmark name
/// (``"nose-tip"``, from ``landmarks`` or detected), as the references of ``describe``.
/// ``towards`` fixes the angular origin: a vertex index or landmark name (its position), or an
/// ``(x, y, z)`` point used as given, not snapped (for faces the midpoint of the outer eye
/// corners). ``step`` (positive) between radius
/// levels, ``levels`` of them, on ``sectors`` rays. Geodesic ``method`` or a prepared ``solver``
/// for this mesh. The GIL is released while it runs. No ray reaching level 1 is an error.
#[pyfunction]
#[pyo3(signature = (mesh, pole, towards, *, step, levels=10, sectors=16, method="exact",
                    landmarks=None, solver=None))]
#[allow(clippy::too_many_arguments)]
pub fn describe_polar(
    py: Python<'_>,
    mesh: &Bound<'_, PyAny>,
    pole: &Bound<'_, PyAny>,
    towards: &Bound<'_, PyAny>,
    step: f64,
    levels: u32,
    sectors: u32,
    method: &str,
    landmarks: Option<&Bound<'_, PyAny>>,
    solver: Option<&Bound<'_, PyGeodesicSolver>>,
) -> PyResult<PyPolarDescriptor> {
    let m = mesh_arg(mesh)?;
    let mesh = m.mesh();
    let given = landmarks.map(given_landmarks).transpose()?;
    let mut in_library = Duration::ZERO;
    let mut resolve = |what: &str, spec: &Bound<'_, PyAny>| {
        let one = [(what.to_string(), spec.clone())];
        references(
            py,
            mesh,
            m.toward_scanner(),
            &one,
            given.as_deref(),
            &mut in_library,
        )
        .map(|s| s[0])
    };
    let pole = resolve("pole", pole)?;
    // The angular origin is only a direction: a point is used as given (the eye-corner midpoint
    // of a face lies off the surface); a vertex or a landmark name gives its position.
    let towards = if towards.is_instance_of::<PyString>() || towards.extract::<i64>().is_ok() {
        match resolve("towards", towards)? {
            Source::Vertex(v) => mesh.try_position(v).map_err(errors::mesh)?,
            Source::Point(sp) => mesh.point_position(&sp).map_err(errors::mesh)?,
        }
    } else {
        convert::point(towards, "towards")?
    };
    let opts = PolarOptions {
        step,
        levels,
        sectors,
    };
    let choice = SolverChoice::of(method, solver)?;
    let d = py.detach(|| {
        choice.run(mesh, |solver| {
            let field = solver.distances(&[pole], &SolveOptions::default())?;
            let walker = Walker::new(mesh);
            bipolar::describe_polar(&walker, &field, pole, towards, &opts)
        })
    });
    Ok(PyPolarDescriptor {
        d: d.map_err(errors::descriptor)?,
    })
}

/// Normalised keyed distance between two single-pole descriptors in [0, 1]: points paired by
/// ``(level, sector)``, optimal rotation in closed form (``shapedist.keyed_distance`` with the
/// default options, as the experiments compare them).
#[pyfunction]
pub fn polar_distance(
    py: Python<'_>,
    a: &Bound<'_, PyPolarDescriptor>,
    b: &Bound<'_, PyPolarDescriptor>,
) -> PyResult<f64> {
    let (da, db) = (&a.get().d, &b.get().d);
    py.detach(|| {
        shapedist::keyed_distance(
            &da.keys(),
            &da.positions(),
            &db.keys(),
            &db.positions(),
            &shapedist::KeyedOptions::default(),
        )
    })
    .map(|k| k.distance)
    .map_err(errors::shapedist)
}

/// `(level, sector)` of a packed polar key.
#[pyfunction]
pub fn unpack_polar_key(key: u64) -> PyResult<(u32, u32)> {
    let k = PolarKey::unpack(key);
    if k.pack() != key {
        return Err(errors::input(format!("{key} is not a packed polar key")));
    }
    Ok((k.level, k.sector))
}
