//! `GeodesicSolver`: one solver prepared per mesh, distance fields with the GIL released.

use crate::convert::{self, rows_out, vec_out};
use crate::errors;
use geodesic::{GeodesicSolver, Method, SolveOptions, Source};
use meshcore::SurfacePoint;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// Surface points from faces (k,) and barycentric coordinates (k, 3).
pub fn surface_points(
    faces: &Bound<'_, PyAny>,
    bary: &Bound<'_, PyAny>,
) -> PyResult<Vec<SurfacePoint>> {
    let f = convert::u32_vec(faces, "faces")?;
    let b = convert::points(bary, "bary")?;
    if f.len() != b.len() {
        return Err(errors::input(format!(
            "faces has {} entries but bary has {} rows",
            f.len(),
            b.len()
        )));
    }
    Ok(f.into_iter()
        .zip(b)
        .map(|(face, bary)| SurfacePoint { face, bary })
        .collect())
}

/// The cut-off argument: None, +inf and values >= 1e100 (tvb-gdist's "infinity") mean none.
pub fn cutoff(max_distance: Option<f64>) -> SolveOptions {
    SolveOptions {
        // NaN is kept: the library rejects it with its own message.
        max_distance: max_distance.filter(|c| c.is_nan() || *c < 1e100),
    }
}

/// Sources: vertex ids (int or 1-D integer array) and/or surface points (faces + bary).
fn sources_arg(
    vertices: Option<&Bound<'_, PyAny>>,
    faces: Option<&Bound<'_, PyAny>>,
    bary: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Source>> {
    let mut out = Vec::new();
    if let Some(v) = vertices {
        if !v.is_none() {
            out.extend(
                convert::u32_vec(v, "sources")?
                    .into_iter()
                    .map(Source::Vertex),
            );
        }
    }
    match (faces, bary) {
        (Some(f), Some(b)) => out.extend(surface_points(f, b)?.into_iter().map(Source::Point)),
        (None, None) => {}
        _ => return Err(errors::input("faces and bary must be given together")),
    }
    Ok(out)
}

/// A geodesic distance solver prepared once for one mesh.
///
/// ``GeodesicSolver(mesh, method="exact")`` with method ``"exact"`` (polyhedral distance,
/// window propagation), ``"fmm"`` (fast marching), ``"heat"`` (heat method, factorisation
/// reused) or ``"dijkstra"`` (edge graph). The solver owns its data; calls release the GIL, so
/// several Python threads can use one solver at once.
#[pyclass(module = "bipolar._bipolar", name = "GeodesicSolver", frozen)]
#[derive(Debug)]
pub struct PyGeodesicSolver {
    pub solver: Box<dyn GeodesicSolver>,
    pub method: Method,
}

#[pymethods]
impl PyGeodesicSolver {
    #[new]
    #[pyo3(signature = (mesh, method="exact"))]
    fn new(py: Python<'_>, mesh: &Bound<'_, PyAny>, method: &str) -> PyResult<Self> {
        let m = crate::mesh::mesh_arg(mesh)?;
        let mesh = m.mesh();
        let method: Method = method.parse().map_err(errors::geodesic)?;
        let solver = py
            .detach(|| geodesic::new_solver(mesh, method))
            .map_err(errors::geodesic)?;
        Ok(Self { solver, method })
    }

    /// The method name (``"exact"``, ``"fmm"``, ``"heat"`` or ``"dijkstra"``).
    #[getter]
    fn method(&self) -> &'static str {
        self.method.name()
    }

    /// Number of vertices of the mesh the solver was prepared for.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.solver.n_vertices()
    }

    /// Distance from the nearest of the sources to every vertex, shape (n,), float64; ``inf``
    /// where unreachable or beyond ``max_distance`` (a cut-off never changes a value it keeps).
    ///
    /// Sources: ``sources`` vertex ids (an int or a 1-D integer array) and/or surface points
    /// ``faces`` (k,) with barycentric coordinates ``bary`` (k, 3).
    #[pyo3(signature = (sources=None, *, faces=None, bary=None, max_distance=None))]
    fn distances<'py>(
        &self,
        py: Python<'py>,
        sources: Option<&Bound<'py, PyAny>>,
        faces: Option<&Bound<'py, PyAny>>,
        bary: Option<&Bound<'py, PyAny>>,
        max_distance: Option<f64>,
    ) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let src = sources_arg(sources, faces, bary)?;
        let opts = cutoff(max_distance);
        let d = py
            .detach(|| self.solver.distances(&src, &opts))
            .map_err(errors::geodesic)?;
        Ok(vec_out(py, d))
    }

    /// One field per entry of ``sources`` (each an int or a sequence of vertex ids), computed
    /// in parallel; shape (k, n).
    #[pyo3(signature = (sources, *, max_distance=None, threads=None))]
    fn distances_many<'py>(
        &self,
        py: Python<'py>,
        sources: &Bound<'py, PyAny>,
        max_distance: Option<f64>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let sets = source_sets(sources)?;
        let n = self.solver.n_vertices();
        let mut flat = Vec::with_capacity(sets.len() * n);
        self.for_each_field(py, &sets, max_distance, threads, |f| flat.extend(f))?;
        Ok(rows_out(py, flat, n))
    }

    /// For each source vertex, the finite non-zero distances within ``max_distance``, as CSR
    /// arrays ``(indptr, indices, data)`` of a (k, n) sparse matrix (row r = source r). Fields
    /// are computed in parallel, a bounded number at a time.
    #[pyo3(signature = (sources, *, max_distance=None, threads=None))]
    fn sparse_distances<'py>(
        &self,
        py: Python<'py>,
        sources: &Bound<'py, PyAny>,
        max_distance: Option<f64>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let sets: Vec<Vec<Source>> = convert::u32_vec(sources, "sources")?
            .into_iter()
            .map(|v| vec![Source::Vertex(v)])
            .collect();
        let limit = cutoff(max_distance).max_distance.unwrap_or(f64::INFINITY);
        let mut indptr = vec![0i64];
        let mut indices: Vec<i64> = Vec::new();
        let mut data: Vec<f64> = Vec::new();
        self.for_each_field(py, &sets, max_distance, threads, |f| {
            for (j, d) in f.into_iter().enumerate() {
                if d.is_finite() && d > 0.0 && d <= limit {
                    indices.push(j as i64);
                    data.push(d);
                }
            }
            indptr.push(indices.len() as i64);
        })?;
        PyTuple::new(
            py,
            [
                vec_out(py, indptr).into_any(),
                vec_out(py, indices).into_any(),
                vec_out(py, data).into_any(),
            ],
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "GeodesicSolver(method={:?}, n_vertices={})",
            self.method.name(),
            self.solver.n_vertices()
        )
    }
}

impl PyGeodesicSolver {
    /// Calls `f` on the field of each of `sets`, in order; the fields are computed in parallel
    /// (`threads` rayon threads, default one per core, GIL released), 256 at a time.
    fn for_each_field(
        &self,
        py: Python<'_>,
        sets: &[Vec<Source>],
        max_distance: Option<f64>,
        threads: Option<usize>,
        mut f: impl FnMut(Vec<f64>) + Send,
    ) -> PyResult<()> {
        let opts = cutoff(max_distance);
        py.detach(|| {
            convert::with_threads(threads, || {
                for chunk in sets.chunks(256) {
                    for field in geodesic::distances_many(self.solver.as_ref(), chunk, &opts)? {
                        f(field);
                    }
                }
                Ok::<_, geodesic::GeodesicError>(())
            })
        })
        .map_err(errors::input)?
        .map_err(errors::geodesic)
    }
}

/// A list of source sets: each entry an int or a sequence of vertex ids.
fn source_sets(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<Source>>> {
    let list = obj
        .try_iter()
        .map_err(|_| errors::type_error("sources must be a sequence of source sets"))?;
    let mut out = Vec::new();
    for (k, item) in list.enumerate() {
        let item = item?;
        let ids = convert::u32_vec(&item, &format!("sources[{k}]"))?;
        out.push(ids.into_iter().map(Source::Vertex).collect());
    }
    Ok(out)
}

/// The solver a binding call computes with: a prepared ``solver`` argument, or else a new solver
/// of the ``method`` argument, built when [`SolverChoice::run`] runs (inside `py.detach`).
#[derive(Debug, Clone, Copy)]
pub(crate) enum SolverChoice<'a> {
    /// The caller's prepared solver (its method wins; the ``method`` argument is not read).
    Prepared(&'a dyn GeodesicSolver),
    /// A solver of this method, built for the call.
    New(Method),
}

impl<'a> SolverChoice<'a> {
    /// Reads the ``method`` / ``solver`` argument pair of a binding (``method`` is parsed only
    /// when no solver is given).
    pub(crate) fn of(
        method: &str,
        solver: Option<&'a Bound<'_, PyGeodesicSolver>>,
    ) -> PyResult<Self> {
        Ok(match solver {
            Some(s) => SolverChoice::Prepared(s.get().solver.as_ref()),
            None => SolverChoice::New(method.parse().map_err(errors::geodesic)?),
        })
    }

    /// Calls `f` with the chosen solver for `mesh` (building it first when it is new).
    pub(crate) fn run<T, E: From<geodesic::GeodesicError>>(
        self,
        mesh: &meshcore::TriMesh,
        f: impl FnOnce(&dyn GeodesicSolver) -> Result<T, E>,
    ) -> Result<T, E> {
        match self {
            SolverChoice::Prepared(s) => f(s),
            SolverChoice::New(method) => f(geodesic::new_solver(mesh, method)?.as_ref()),
        }
    }
}
