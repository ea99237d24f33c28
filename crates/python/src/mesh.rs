//! `Mesh`, mesh files (every format of mesh-io), landmark files and the generated shapes.

use crate::convert::{self, points_out, rows_out, vec_out};
use crate::errors;
use glam::DVec3;
use mesh_io::{
    Format, LoadedMesh, PlyEncoding, PlyWriteOptions, RepairReport, ScalarField, ScalarType,
};
use meshcore::{FaceLocator, TriMesh};
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use std::path::Path;

/// A triangle mesh (f64 positions, u32 triangles) with the per-vertex extras a file carried.
///
/// ``Mesh(vertices, triangles)`` validates: at least one vertex and one triangle, finite
/// coordinates, indices in range. Degenerate faces and duplicate vertices are allowed and
/// listed in ``warnings``. Meshes are immutable; repairs return a new mesh.
#[pyclass(module = "bipolar._bipolar", name = "Mesh", frozen)]
#[derive(Debug, Clone)]
pub struct PyMesh {
    pub loaded: LoadedMesh,
}

impl PyMesh {
    pub fn mesh(&self) -> &TriMesh {
        &self.loaded.mesh
    }
}

fn summary_dict<'py>(py: Python<'py>, s: RepairReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("welded_vertices", s.welded_vertices)?;
    d.set_item("removed_faces", s.removed_faces)?;
    d.set_item("removed_vertices", s.removed_vertices)?;
    Ok(d)
}

impl PyMesh {
    /// A copy repaired by `repair` with the tolerance `tol` (finite and >= 0, named `name` in
    /// the message), GIL released, and the repair's summary as a dict.
    fn repaired<'py>(
        &self,
        py: Python<'py>,
        (name, tol): (&str, f64),
        repair: fn(&mut LoadedMesh, f64) -> RepairReport,
    ) -> PyResult<(Self, Bound<'py, PyDict>)> {
        if !(tol.is_finite() && tol >= 0.0) {
            return Err(errors::input(format!(
                "{name} must be finite and >= 0, got {tol}"
            )));
        }
        let mut out = self.clone();
        let s = py.detach(|| repair(&mut out.loaded, tol));
        Ok((out, summary_dict(py, s)?))
    }
}

/// Builds a mesh from arrays (the one place a `TriMesh` is made from Python data).
pub fn mesh_from_arrays(
    vertices: &Bound<'_, PyAny>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<TriMesh> {
    let v = convert::points(vertices, "vertices")?;
    let t = convert::triangles(triangles, "triangles")?;
    TriMesh::new(v, t).map_err(errors::mesh)
}

/// A `Mesh` argument (borrowed, not copied) or a mesh read from a path argument.
#[derive(Debug)]
pub enum MeshArg<'py> {
    /// A `bipolar.Mesh` passed by the caller.
    Borrowed(Bound<'py, PyMesh>),
    /// A mesh read from the file the caller named.
    Owned(PyMesh),
}

impl MeshArg<'_> {
    pub fn mesh(&self) -> &TriMesh {
        match self {
            MeshArg::Borrowed(b) => b.get().mesh(),
            MeshArg::Owned(m) => m.mesh(),
        }
    }

    /// `+z` for a range grid's mesh (it has a grid index: read from a `.bnt` or made by
    /// `scan`; the scanner looks down the z axis), `None` for other meshes.
    pub fn toward_scanner(&self) -> Option<meshcore::DVec3> {
        let grid = match self {
            MeshArg::Borrowed(b) => b.get().loaded.grid_index.is_some(),
            MeshArg::Owned(m) => m.loaded.grid_index.is_some(),
        };
        grid.then_some(meshcore::DVec3::Z)
    }
}

/// A `Mesh` argument, or a path to read one from.
pub fn mesh_arg<'py>(obj: &Bound<'py, PyAny>) -> PyResult<MeshArg<'py>> {
    if let Ok(m) = obj.cast::<PyMesh>() {
        return Ok(MeshArg::Borrowed(m.clone()));
    }
    if let Ok(p) = obj.extract::<std::path::PathBuf>() {
        let py = obj.py();
        let loaded = py.detach(|| mesh_io::read_mesh(&p)).map_err(errors::io)?;
        return Ok(MeshArg::Owned(PyMesh { loaded }));
    }
    Err(errors::type_error(
        "mesh must be a bipolar.Mesh or a path to a mesh file",
    ))
}

fn scalar_type(name: &str) -> PyResult<ScalarType> {
    name.parse().map_err(errors::io)
}

/// A format name (`"ply"`, `".obj"`, ...) parsed by mesh-io's own extension rule.
fn format_arg(name: &str) -> PyResult<Format> {
    let ext = name.trim().trim_start_matches('.');
    Format::from_path(Path::new(&format!("mesh.{ext}"))).map_err(errors::io)
}

#[pymethods]
impl PyMesh {
    #[new]
    fn new(vertices: &Bound<'_, PyAny>, triangles: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyMesh {
            loaded: LoadedMesh::new(mesh_from_arrays(vertices, triangles)?),
        })
    }

    /// Vertex positions, shape (n, 3), float64 (a copy).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        points_out(py, self.mesh().positions())
    }

    /// Triangles as vertex indices, shape (m, 3), uint32 (a copy).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<u32>> {
        let flat: Vec<u32> = self.mesh().triangles().iter().flatten().copied().collect();
        rows_out(py, flat, 3)
    }

    /// Number of vertices.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.mesh().n_vertices()
    }

    /// Number of triangles.
    #[getter]
    fn n_faces(&self) -> usize {
        self.mesh().n_faces()
    }

    /// Per-vertex RGBA colours, shape (n, 4), uint8, or None.
    #[getter]
    fn colors<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray2<u8>>> {
        self.loaded
            .colors
            .as_ref()
            .map(|c| rows_out(py, c.iter().flatten().copied().collect(), 4))
    }

    /// Other per-vertex scalar properties the file had (PLY): name -> float64 array.
    #[getter]
    fn scalars<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for s in &self.loaded.scalars {
            d.set_item(&s.name, vec_out(py, s.values.clone()))?;
        }
        Ok(d)
    }

    /// For meshes made from a range grid (BNT): per vertex, its sample index row * ncols + col.
    #[getter]
    fn grid_index<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray1<u32>>> {
        self.loaded
            .grid_index
            .as_ref()
            .map(|g| vec_out(py, g.clone()))
    }

    /// What the reader noticed and did not repair (degenerate faces, duplicate vertices, ...).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.loaded.warnings.clone()
    }

    /// Length of the bounding-box diagonal.
    fn bbox_diagonal(&self) -> f64 {
        self.mesh().bbox().diagonal()
    }

    /// Mean edge length.
    fn mean_edge_length(&self) -> f64 {
        self.mesh().mean_edge_length()
    }

    /// Total surface area.
    fn area(&self) -> f64 {
        self.mesh().area()
    }

    /// Per-vertex unit normals (area-weighted face normals), shape (n, 3).
    fn vertex_normals<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        points_out(py, &self.mesh().vertex_normals())
    }

    /// The nearest surface point to each query point: ``(faces, bary, distances)`` with shapes
    /// (k,), (k, 3), (k,). Exact (uniform-grid accelerated).
    fn nearest<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let q = convert::points(points, "points")?;
        let mesh = self.mesh();
        let found = py.detach(|| {
            let loc = FaceLocator::new(mesh);
            q.iter()
                .map(|&p| loc.nearest(p))
                .collect::<Result<Vec<_>, _>>()
        });
        let found = found.map_err(errors::mesh)?;
        let faces: Vec<u32> = found.iter().map(|(s, _)| s.face).collect();
        let bary: Vec<DVec3> = found.iter().map(|(s, _)| s.bary).collect();
        let dist: Vec<f64> = found.iter().map(|(_, d)| *d).collect();
        PyTuple::new(
            py,
            [
                vec_out(py, faces).into_any(),
                points_out(py, &bary).into_any(),
                vec_out(py, dist).into_any(),
            ],
        )
    }

    /// Positions of surface points given as faces (k,) and barycentric coordinates (k, 3).
    fn surface_positions<'py>(
        &self,
        py: Python<'py>,
        faces: &Bound<'py, PyAny>,
        bary: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let sp = crate::geodesic::surface_points(faces, bary)?;
        let p = sp
            .iter()
            .map(|s| self.mesh().point_position(s))
            .collect::<Result<Vec<_>, _>>()
            .map_err(errors::mesh)?;
        Ok(points_out(py, &p))
    }

    /// A copy with per-vertex extras attached for writing: ``colors`` (n, 4) or (n, 3) uint8
    /// (alpha 255), ``scalars`` a dict name -> (n,) values (stored as float64 unless
    /// ``scalar_type="float32"``). Extras not given are kept.
    #[pyo3(signature = (*, colors=None, scalars=None, scalar_type="float64"))]
    fn with_extras(
        &self,
        colors: Option<&Bound<'_, PyAny>>,
        scalars: Option<&Bound<'_, PyDict>>,
        scalar_type: &str,
    ) -> PyResult<Self> {
        let mut out = self.clone();
        let n = self.mesh().n_vertices();
        if let Some(c) = colors {
            let a = convert::i64_array(c, "colors")?;
            let ro = a
                .try_readonly()
                .map_err(|e| errors::input(format!("colors: {e}")))?;
            let v = ro.as_array();
            let sh = v.shape().to_vec();
            if sh.len() != 2 || sh[0] != n || !(sh[1] == 3 || sh[1] == 4) {
                return Err(errors::input(format!(
                    "colors must have shape ({n}, 3) or ({n}, 4), got {sh:?}"
                )));
            }
            let mut rgba = Vec::with_capacity(n);
            for i in 0..n {
                let mut px = [255u8; 4];
                for k in 0..sh[1] {
                    let x = v[[i, k]];
                    px[k] = u8::try_from(x).map_err(|_| {
                        errors::input(format!("colors[{i}, {k}] = {x} is outside 0..=255"))
                    })?;
                }
                rgba.push(px);
            }
            out.loaded.colors = Some(rgba);
        }
        if let Some(s) = scalars {
            let ty = scalar_type_arg(scalar_type)?;
            for (k, v) in s.iter() {
                let name: String = k
                    .extract()
                    .map_err(|_| errors::type_error("scalar names must be str"))?;
                let values = convert::f64_vec(&v, &format!("scalars[{name:?}]"))?;
                if values.len() != n {
                    return Err(errors::input(format!(
                        "scalars[{name:?}] has {} values for {n} vertices",
                        values.len()
                    )));
                }
                out.loaded.scalars.retain(|f| f.name != name);
                out.loaded.scalars.push(ScalarField { name, values, ty });
            }
        }
        Ok(out)
    }

    /// Merges vertices closer than ``tol`` (absolute; 0 merges exact duplicates), then drops
    /// collapsed faces and unused vertices. Returns ``(new_mesh, summary)``.
    #[pyo3(signature = (tol=0.0))]
    fn weld<'py>(&self, py: Python<'py>, tol: f64) -> PyResult<(Self, Bound<'py, PyDict>)> {
        self.repaired(py, ("tol", tol), LoadedMesh::weld)
    }

    /// Removes faces with a repeated vertex or an area <= ``rel_tol * diagonal^2``, then
    /// unused vertices. Returns ``(new_mesh, summary)``.
    #[pyo3(signature = (rel_tol=0.0))]
    fn drop_degenerate<'py>(
        &self,
        py: Python<'py>,
        rel_tol: f64,
    ) -> PyResult<(Self, Bound<'py, PyDict>)> {
        self.repaired(py, ("rel_tol", rel_tol), LoadedMesh::drop_degenerate)
    }

    /// The bytes of a file of the given format (``"obj"``, ``"ply"`` (binary little endian),
    /// ``"stl"``, ``"off"``, ``"glb"``), with the extras the format can carry.
    fn to_bytes<'py>(&self, py: Python<'py>, format: &str) -> PyResult<Bound<'py, PyBytes>> {
        let f = format_arg(format)?;
        let b = py
            .detach(|| mesh_io::write_mesh_to_bytes(&self.loaded, f))
            .map_err(errors::io)?;
        Ok(PyBytes::new(py, &b))
    }

    fn __len__(&self) -> usize {
        self.mesh().n_vertices()
    }

    fn __repr__(&self) -> String {
        format!(
            "Mesh({} vertices, {} faces)",
            self.mesh().n_vertices(),
            self.mesh().n_faces()
        )
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<convert::Reduced<'py>> {
        let scalars = PyDict::new(py);
        for s in &self.loaded.scalars {
            let ty = match s.ty {
                ScalarType::F32 => "float32",
                ScalarType::F64 => "float64",
            };
            scalars.set_item(&s.name, (vec_out(py, s.values.clone()), ty))?;
        }
        convert::reduced(
            py,
            "_mesh_from_state",
            [
                self.vertices(py).into_any(),
                self.triangles(py).into_any(),
                self.colors(py)
                    .map_or_else(|| py.None().into_bound(py), |c| c.into_any()),
                scalars.into_any(),
            ],
        )
    }
}

fn scalar_type_arg(name: &str) -> PyResult<ScalarType> {
    scalar_type(name)
}

/// Rebuilds a pickled `Mesh`.
#[pyfunction]
pub fn _mesh_from_state(
    vertices: &Bound<'_, PyAny>,
    triangles: &Bound<'_, PyAny>,
    colors: &Bound<'_, PyAny>,
    scalars: &Bound<'_, PyDict>,
) -> PyResult<PyMesh> {
    let mut m = PyMesh {
        loaded: LoadedMesh::new(mesh_from_arrays(vertices, triangles)?),
    };
    if !colors.is_none() {
        m = m.with_extras(Some(colors), None, "float64")?;
    }
    for (k, v) in scalars.iter() {
        let (vals, ty): (Bound<'_, PyAny>, String) = v.extract()?;
        let d = PyDict::new(scalars.py());
        d.set_item(k, vals)?;
        m = m.with_extras(None, Some(&d), &ty)?;
    }
    Ok(m)
}

/// Reads a mesh file; the format comes from the extension (obj, ply, stl, off, gltf, glb, bnt).
#[pyfunction]
pub fn read_mesh(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<PyMesh> {
    let p = convert::path(path, "path")?;
    let loaded = py.detach(|| mesh_io::read_mesh(&p)).map_err(errors::io)?;
    Ok(PyMesh { loaded })
}

/// Reads a mesh from the bytes of a file of the given format (glTF: embedded buffers only).
#[pyfunction]
pub fn read_mesh_bytes(py: Python<'_>, data: &[u8], format: &str) -> PyResult<PyMesh> {
    let f = format_arg(format)?;
    let loaded = py
        .detach(|| mesh_io::read_mesh_from_bytes(data, f))
        .map_err(errors::io)?;
    Ok(PyMesh { loaded })
}

/// Writes a mesh; the format comes from the extension (obj, ply (binary little endian), stl,
/// off, glb). Colours and scalars are written where the format can carry them.
#[pyfunction]
pub fn write_mesh(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    mesh: &Bound<'_, PyMesh>,
) -> PyResult<()> {
    let p = convert::path(path, "path")?;
    let m = mesh.get();
    py.detach(|| mesh_io::write_mesh(&p, &m.loaded))
        .map_err(errors::io)
}

/// Writes a PLY file with an explicit encoding: ``"ascii"``, ``"binary_little_endian"`` or
/// ``"binary_big_endian"`` (the mesh's colours and scalars included).
#[pyfunction]
#[pyo3(signature = (path, mesh, encoding="binary_little_endian"))]
pub fn write_ply(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    mesh: &Bound<'_, PyMesh>,
    encoding: &str,
) -> PyResult<()> {
    let p = convert::path(path, "path")?;
    let encoding: PlyEncoding = encoding.parse().map_err(errors::io)?;
    let m = mesh.get();
    let opts = PlyWriteOptions {
        encoding,
        colors: m.loaded.colors.as_deref(),
        scalars: &m.loaded.scalars,
    };
    py.detach(|| mesh_io::write_ply(&p, &m.loaded.mesh, &opts))
        .map_err(errors::io)
}

/// Reads a Bosphorus ``.bnt`` range grid as a mesh with explicit triangulation options.
#[pyfunction]
#[pyo3(signature = (path, *, max_edge_factor=4.0, largest_component_only=true))]
pub fn read_bnt(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    max_edge_factor: f64,
    largest_component_only: bool,
) -> PyResult<PyMesh> {
    let p = convert::path(path, "path")?;
    let opts = mesh_io::BntOptions {
        max_edge_factor,
        largest_component_only,
    };
    let loaded = py
        .detach(|| mesh_io::read_bnt(&p, &opts))
        .map_err(errors::io)?;
    Ok(PyMesh { loaded })
}

/// `{label: (K,) array}` of labels and their coordinates.
fn labelled<'py, const K: usize>(
    py: Python<'py>,
    labels: impl IntoIterator<Item = String>,
    points: impl IntoIterator<Item = [f64; K]>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (label, p) in labels.into_iter().zip(points) {
        d.set_item(label, vec_out(py, p.to_vec()))?;
    }
    Ok(d)
}

/// The landmark file named by the ``path`` argument, read by `read` into labels and their
/// coordinates, as `{label: (K,) array}`.
fn read_labelled<'py, const K: usize>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
    read: impl FnOnce(&Path) -> Result<(Vec<String>, Vec<[f64; K]>), mesh_io::IoError>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = convert::path(path, "path")?;
    let (labels, points) = read(&p).map_err(errors::io)?;
    labelled(py, labels, points)
}

/// Reads labelled 3D landmarks: Bosphorus ``.lm3`` by extension, otherwise JSON as written by
/// ``bipolar landmarks`` or a flat ``{name: [x, y, z]}`` object. Returns ``{label: (3,) array}``.
#[pyfunction]
pub fn read_landmarks<'py>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    read_labelled(py, path, |p| {
        let lm = mesh_io::read_landmark_file(p, None)?;
        Ok((lm.labels, lm.points.iter().map(|q| q.to_array()).collect()))
    })
}

/// Reads the ICT FaceKit ``landmarks.json`` layout: ``{face: {name: (3,) array}}`` with the five
/// landmark names of ``bipolar.LANDMARK_NAMES``.
#[pyfunction]
pub fn read_ict_landmarks<'py>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = convert::path(path, "path")?;
    let faces = mesh_io::read_ict_landmarks(&p).map_err(errors::io)?;
    let out = PyDict::new(py);
    for (face, lm) in faces {
        let pts = landmarks::io::select_five(&lm, &face).map_err(errors::landmarks)?;
        let labels = landmarks::LandmarkName::ALL
            .iter()
            .map(|n| n.key().to_string());
        out.set_item(face, labelled(py, labels, pts.map(|q| q.to_array()))?)?;
    }
    Ok(out)
}

/// Reads Bosphorus ``.lm2`` 2D landmarks (texture pixel coordinates): ``{label: (2,) array}``.
#[pyfunction]
pub fn read_lm2<'py>(py: Python<'py>, path: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    read_labelled(py, path, |p| {
        let lm = mesh_io::read_lm2(p)?;
        Ok((lm.labels, lm.points))
    })
}

/// Writes labelled 3D landmarks ``{label: (x, y, z)}`` as a Bosphorus ``.lm3`` file.
#[pyfunction]
pub fn write_lm3(path: &Bound<'_, PyAny>, landmarks: &Bound<'_, PyDict>) -> PyResult<()> {
    let p = convert::path(path, "path")?;
    let mut lm = mesh_io::Landmarks3d::default();
    for (k, v) in landmarks.iter() {
        let label: String = k
            .extract()
            .map_err(|_| errors::type_error("landmark labels must be str"))?;
        let q = convert::point(&v, &format!("landmarks[{label:?}]"))?;
        lm.labels.push(label);
        lm.points.push(q);
    }
    mesh_io::write_lm3(&p, &lm).map_err(errors::io)
}

/// A unit icosphere with ``subdivisions`` levels of 4-to-1 subdivision (12, 42, 162, 642, 2562,
/// 10242, 40962, 163842 vertices for 0..7).
#[pyfunction]
pub fn icosphere(py: Python<'_>, subdivisions: u32) -> PyResult<PyMesh> {
    if subdivisions > 9 {
        return Err(errors::input(format!(
            "subdivisions must be at most 9 (2.6M vertices), got {subdivisions}"
        )));
    }
    let m = py.detach(|| meshcore::shapes::icosphere(subdivisions));
    Ok(PyMesh {
        loaded: LoadedMesh::new(m),
    })
}

/// A unit UV sphere with ``n_lat`` latitude bands and ``n_lon`` longitude sectors (poles on z).
#[pyfunction]
pub fn uv_sphere(py: Python<'_>, n_lat: usize, n_lon: usize) -> PyResult<PyMesh> {
    if n_lat.saturating_mul(n_lon) > 10_000_000 {
        return Err(errors::input("n_lat * n_lon must be at most 10 million"));
    }
    let m = py.detach(|| meshcore::shapes::uv_sphere(n_lat, n_lon));
    Ok(PyMesh {
        loaded: LoadedMesh::new(m),
    })
}

/// A square grid of ``n x n`` cells of size ``h`` from ``(x0, x0)`` in the plane z = 0, interior
/// vertices jittered by up to ``jitter * h / 2`` per axis (deterministic in ``seed``).
#[pyfunction]
#[pyo3(signature = (n, h=1.0, x0=0.0, jitter=0.0, seed=0))]
pub fn grid_plane(
    py: Python<'_>,
    n: usize,
    h: f64,
    x0: f64,
    jitter: f64,
    seed: u64,
) -> PyResult<PyMesh> {
    if n == 0 || n > 3000 {
        return Err(errors::input(format!("n must be in 1..=3000, got {n}")));
    }
    if !(h.is_finite() && h > 0.0 && x0.is_finite() && jitter.is_finite() && jitter >= 0.0) {
        return Err(errors::input(
            "h must be positive, x0 and jitter finite (jitter >= 0)",
        ));
    }
    let m = py.detach(|| meshcore::shapes::grid_plane(n, h, x0, jitter, seed, |_| false));
    Ok(PyMesh {
        loaded: LoadedMesh::new(m),
    })
}
