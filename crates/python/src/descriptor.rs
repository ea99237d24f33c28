//! `Descriptor`: a bipolar descriptor held in Rust, read as numpy arrays; descriptor files.

use crate::convert::{self, points_out, vec_out};
use crate::errors;
use bipolar::{Descriptor, DescriptorPoint, Key};
use glam::DVec3;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A bipolar descriptor: keyed points on a surface, sorted by key then position.
///
/// Arrays (copies): ``points`` (n, 3), ``keys`` (n,) uint64 (``Key::pack``: pair, levels,
/// side, sign; equal keys correspond across surfaces), ``cos`` (n,) signed cosine of the
/// opening, ``ambiguous`` (n,) bool (several points share the key), ``faces`` (n,) uint32 and
/// ``bary`` (n, 3) (the surface point; ``faces = 2**32 - 1`` and zero barycentrics when read
/// from a CSV file). Metadata: ``step``, ``max_level``, ``reference_distance``,
/// ``references``, ``options``, ``stats``. Picklable (for Dask).
#[pyclass(module = "bipolar._bipolar", name = "Descriptor", frozen)]
#[derive(Debug, Clone)]
pub struct PyDescriptor {
    pub d: Descriptor,
}

fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

descriptor_pymethods! {
    PyDescriptor,
    surface_points {
        keys: packed_keys,
        /// Face of each point, shape (n,), uint32 (2**32 - 1 when unknown).
        faces
    }
    summary {
        "Descriptor", points "points", step = step, max_level = max_level,
        reference_distance = reference_distance
    }
    {
        /// A descriptor from user arrays (e.g. any keyed point set): ``points`` (n, 3), ``keys``
        /// (n,) packed keys (``Descriptor.keys``, ``pack_key``, or any multiple of 16 below 2**26);
        /// ``cos`` (n,) and ``ambiguous`` (n,) default to 0 and False.
        /// Points stay in the given order (distances pair them by key, whatever the order).
        #[staticmethod]
        #[pyo3(signature = (points, keys, cos=None, ambiguous=None))]
        fn from_arrays(
            points: &Bound<'_, PyAny>,
            keys: &Bound<'_, PyAny>,
            cos: Option<&Bound<'_, PyAny>>,
            ambiguous: Option<&Bound<'_, PyAny>>,
        ) -> PyResult<Self> {
            let p = convert::points(points, "points")?;
            let k = convert::u64_vec(keys, "keys")?;
            let n = p.len();
            if k.len() != n {
                return Err(errors::input(format!(
                    "keys has {} entries for {n} points",
                    k.len()
                )));
            }
            if let Some((i, &key)) = k
                .iter()
                .enumerate()
                .find(|(_, &x)| Key::unpack(x).pack() != x)
            {
                return Err(errors::input(format!(
                    "keys[{i}] = {key} is not a packed bipolar key (the side and sign fields, bits \
                     0-3, hold 0, 1 or 2 each; make keys with bipolar.pack_key or use multiples of 16)"
                )));
            }
            if let Some((i, q)) = p.iter().enumerate().find(|(_, q)| !q.is_finite()) {
                return Err(errors::input(format!(
                    "points[{i}] = {:?} is not finite",
                    q.to_array()
                )));
            }
            let c = match cos {
                Some(c) => convert::f64_vec(c, "cos")?,
                None => vec![0.0; n],
            };
            let a: Vec<bool> = match ambiguous {
                Some(a) => convert::bool_vec(a, "ambiguous")?,
                None => vec![false; n],
            };
            if c.len() != n || a.len() != n {
                return Err(errors::input(format!(
                    "cos and ambiguous must have {n} entries, got {} and {}",
                    c.len(),
                    a.len()
                )));
            }
            let pts: Vec<DescriptorPoint> = (0..n)
                .map(|i| DescriptorPoint {
                    position: p[i],
                    key: Key::unpack(k[i]),
                    cos: c[i],
                    face: u32::MAX,
                    bary: DVec3::ZERO,
                    ambiguous: a[i],
                })
                .collect();
            Ok(Self {
                d: Descriptor {
                    points: pts,
                    step: f64::NAN,
                    max_level: 0,
                    reference_distance: f64::NAN,
                    references: Vec::new(),
                    options: bipolar::DescriptorOptions::default(),
                    stats: bipolar::DescriptorStats::default(),
                },
            })
        }

        /// Signed cosine of the opening between the two level curves at each point, shape (n,).
        #[getter]
        fn cos<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
            vec_out(py, self.d.points.iter().map(|p| p.cos).collect())
        }

        /// True where several points share the key, shape (n,), bool.
        #[getter]
        fn ambiguous<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<bool>> {
            vec_out(py, self.d.points.iter().map(|p| p.ambiguous).collect())
        }

        /// The unpacked key fields as a dict of (n,) arrays: ``a``, ``b`` (reference pair), ``i``,
        /// ``j`` (levels, or angle level for the iso-angle rule), ``side``, ``sign``.
        fn key_fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
            let k: Vec<Key> = self.d.points.iter().map(|p| p.key).collect();
            let d = PyDict::new(py);
            d.set_item("a", vec_out(py, k.iter().map(|k| k.a).collect()))?;
            d.set_item("b", vec_out(py, k.iter().map(|k| k.b).collect()))?;
            d.set_item("i", vec_out(py, k.iter().map(|k| k.i).collect()))?;
            d.set_item("j", vec_out(py, k.iter().map(|k| k.j).collect()))?;
            d.set_item("side", vec_out(py, k.iter().map(|k| k.side).collect()))?;
            d.set_item("sign", vec_out(py, k.iter().map(|k| k.sign).collect()))?;
            Ok(d)
        }

        /// Geodesic step between levels (NaN when unknown).
        #[getter]
        fn step(&self) -> f64 {
            self.d.step
        }

        /// Highest level used.
        #[getter]
        fn max_level(&self) -> u32 {
            self.d.max_level
        }

        /// Geodesic distance between the first two reference points (NaN when unknown).
        #[getter]
        fn reference_distance(&self) -> f64 {
            self.d.reference_distance
        }

        /// Reference point positions, shape (r, 3) (empty when unknown).
        #[getter]
        fn references<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
            points_out(py, &self.d.references)
        }

        /// The options the descriptor was built with, as a dict (the JSON file's ``options``).
        #[getter]
        fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
            let s = serde_json::to_string(&self.d.options)
                .map_err(|e| errors::err(errors::Kind::Computation, e.to_string()))?;
            json_to_py(py, &s)
        }

        /// Build counters (intersections, ill-conditioned, tangent fallbacks, ambiguous,
        /// degenerate faces) as a dict.
        #[getter]
        fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
            let s = serde_json::to_string(&self.d.stats)
                .map_err(|e| errors::err(errors::Kind::Computation, e.to_string()))?;
            json_to_py(py, &s)
        }

        /// Writes the descriptor: ``.csv`` (points and keys), ``.json`` (everything, lossless) or
        /// ``.ply`` (points with key fields, for viewers), by extension.
        fn save(&self, py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<()> {
            let p = convert::path(path, "path")?;
            py.detach(|| bipolar::io::write_auto(&p, &self.d))
                .map_err(errors::descriptor)
        }

        /// The JSON text of the descriptor (lossless).
        fn to_json(&self) -> String {
            bipolar::io::to_json_string(&self.d)
        }

        /// Parses the JSON text written by ``to_json`` / ``save(".json")``.
        #[staticmethod]
        fn from_json(text: &str) -> PyResult<Self> {
            let d = bipolar::io::parse_json(text, std::path::Path::new("<string>"))
                .map_err(errors::descriptor)?;
            Ok(Self { d })
        }

        fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
            other
                .cast::<PyDescriptor>()
                .is_ok_and(|o| descriptors_equal(&self.d, &o.get().d))
        }

        fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<convert::Reduced<'py>> {
            let mut meta = self.d.clone();
            meta.points.clear();
            convert::reduced(
                py,
                "_descriptor_from_state",
                [
                    self.points(py).into_any(),
                    self.keys(py).into_any(),
                    self.cos(py).into_any(),
                    self.ambiguous(py).into_any(),
                    self.faces(py).into_any(),
                    self.bary(py).into_any(),
                    bipolar::io::to_json_string(&meta)
                        .into_pyobject(py)?
                        .into_any(),
                ],
            )
        }
    }
}

/// Equality with NaN metadata equal to NaN (descriptors read from CSV have NaN steps).
fn descriptors_equal(a: &Descriptor, b: &Descriptor) -> bool {
    let f = |x: f64, y: f64| x == y || (x.is_nan() && y.is_nan());
    a.points == b.points
        && f(a.step, b.step)
        && a.max_level == b.max_level
        && f(a.reference_distance, b.reference_distance)
        && a.references == b.references
        && a.options == b.options
        && a.stats == b.stats
}

/// Rebuilds a pickled `Descriptor`.
#[pyfunction]
pub fn _descriptor_from_state(
    points: &Bound<'_, PyAny>,
    keys: &Bound<'_, PyAny>,
    cos: &Bound<'_, PyAny>,
    ambiguous: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    bary: &Bound<'_, PyAny>,
    meta: &str,
) -> PyResult<PyDescriptor> {
    let mut d = bipolar::io::parse_json(meta, std::path::Path::new("<pickle>"))
        .map_err(errors::descriptor)?;
    let p = convert::points(points, "points")?;
    let k = convert::u64_vec(keys, "keys")?;
    let c = convert::f64_vec(cos, "cos")?;
    let a = convert::bool_vec(ambiguous, "ambiguous")?;
    let f = convert::u32_vec(faces, "faces")?;
    let b = convert::points(bary, "bary")?;
    let n = p.len();
    if [k.len(), c.len(), a.len(), f.len(), b.len()]
        .iter()
        .any(|&l| l != n)
    {
        return Err(errors::input("inconsistent descriptor state"));
    }
    d.points = (0..n)
        .map(|i| DescriptorPoint {
            position: p[i],
            key: Key::unpack(k[i]),
            cos: c[i],
            face: f[i],
            bary: b[i],
            ambiguous: a[i],
        })
        .collect();
    Ok(PyDescriptor { d })
}

/// Reads a descriptor file (``.csv`` or ``.json``) by extension.
#[pyfunction]
pub fn read_descriptor(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<PyDescriptor> {
    let p = convert::path(path, "path")?;
    let d = py
        .detach(|| bipolar::io::read_auto(&p))
        .map_err(errors::descriptor)?;
    Ok(PyDescriptor { d })
}

/// Packs key fields into the uint64 keys of ``Descriptor.keys`` (``Key::pack``).
#[pyfunction]
pub fn pack_key(a: u8, b: u8, i: u32, j: u32, side: i8, sign: i8) -> PyResult<u64> {
    if i > Key::MAX_LEVEL || j > Key::MAX_LEVEL {
        return Err(errors::input(format!(
            "levels must be at most {}",
            Key::MAX_LEVEL
        )));
    }
    if !(-1..=1).contains(&side) || !(-1..=1).contains(&sign) {
        return Err(errors::input("side and sign must be -1, 0 or 1"));
    }
    Ok(Key {
        a,
        b,
        i,
        j,
        side,
        sign,
    }
    .pack())
}

/// Unpacks a uint64 key into ``(a, b, i, j, side, sign)``.
#[pyfunction]
pub fn unpack_key(key: u64) -> (u8, u8, u32, u32, i8, i8) {
    let k = Key::unpack(key);
    (k.a, k.b, k.i, k.j, k.side, k.sign)
}
