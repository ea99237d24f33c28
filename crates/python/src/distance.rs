//! Shape distances between descriptors: keyed closed form, ICP, Hausdorff; matrices.
//!
//! The option names and their mapping are those of `bipolar distance` / `bipolar matrix`.

use crate::convert::{self, rows_out};
use crate::descriptor::PyDescriptor;
use crate::errors;
use glam::{DMat3, DVec3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rayon::prelude::*;
use serde_json::json;
use shapedist::{
    GlobalOptions, IcpOptions, IcpVariant, KeyedOptions, PrepareOptions, PreparedSet, RobustLoss,
    RotationMethod, ShapeDistError, Which,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Keys,
    Icp,
    Hausdorff,
}
meshcore::choice!(Mode, "mode", meshcore::UnknownChoice {
    Keys = "keys",
    Icp = "icp",
    Hausdorff = "hausdorff",
});

/// How two descriptors are compared (the flags of ``bipolar distance``).
///
/// ``mode``: ``"keys"`` (points paired by key, closed-form rotation: normalised L2 distance),
/// ``"icp"`` (global ICP without keys: normalised mean closest-point distance) or
/// ``"hausdorff"`` (same alignment: normalised symmetric Hausdorff distance). Keys mode:
/// ``solver`` ``"kabsch"`` | ``"horn"``, ``robust`` None | ``"huber"`` | ``"tukey"``, ``gate``
/// (drop pairs whose residual exceeds it), ``keep_ambiguous`` (also use points flagged
/// ambiguous). ICP modes: ``variant`` ``"point"`` | ``"plane"``, ``trim`` (fraction of worst
/// pairs rejected), ``iterations``, ``global_search`` (multi-start; False = plain ICP from the
/// identity).
#[pyclass(module = "bipolar._bipolar", name = "DistanceOptions", frozen)]
#[derive(Debug, Clone)]
pub struct PyDistanceOptions {
    mode: Mode,
    solver: String,
    robust: Option<String>,
    gate: Option<f64>,
    keep_ambiguous: bool,
    variant: String,
    trim: f64,
    iterations: usize,
    global_search: bool,
    keyed: KeyedOptions,
    global: GlobalOptions,
}

#[pymethods]
impl PyDistanceOptions {
    #[new]
    #[pyo3(signature = (*, mode="keys", solver="kabsch", robust=None, gate=None,
                        keep_ambiguous=false, variant="point", trim=0.0, iterations=100,
                        global_search=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        mode: &str,
        solver: &str,
        robust: Option<&str>,
        gate: Option<f64>,
        keep_ambiguous: bool,
        variant: &str,
        trim: f64,
        iterations: usize,
        global_search: bool,
    ) -> PyResult<Self> {
        let m: Mode = mode.parse().map_err(|e| errors::input(format!("{e}")))?;
        let method: RotationMethod = solver.parse().map_err(errors::shapedist)?;
        let robust_loss = match robust {
            None => None,
            Some("huber") => Some(RobustLoss::Huber(1.345)),
            Some("tukey") => Some(RobustLoss::Tukey(4.685)),
            Some(o) => {
                return Err(errors::input(format!(
                    "unknown robust weights {o:?} (expected huber, tukey or None)"
                )))
            }
        };
        let icp_variant: IcpVariant = variant.parse().map_err(errors::shapedist)?;
        let keyed = KeyedOptions {
            method,
            robust: robust_loss,
            irls_iterations: 5,
            gate,
        };
        let global = GlobalOptions {
            grid: global_search,
            refine: IcpOptions {
                variant: icp_variant,
                max_iterations: iterations.max(1),
                trim,
                ..IcpOptions::default()
            },
            ..GlobalOptions::default()
        };
        Ok(Self {
            mode: m,
            solver: solver.into(),
            robust: robust.map(Into::into),
            gate,
            keep_ambiguous,
            variant: variant.into(),
            trim,
            iterations,
            global_search,
            keyed,
            global,
        })
    }

    /// ``"keys"``, ``"icp"`` or ``"hausdorff"``.
    #[getter]
    fn mode(&self) -> &'static str {
        match self.mode {
            Mode::Keys => "keys",
            Mode::Icp => "icp",
            Mode::Hausdorff => "hausdorff",
        }
    }

    /// The options as keyword arguments of the constructor.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("mode", self.mode())?;
        d.set_item("solver", &self.solver)?;
        d.set_item("robust", &self.robust)?;
        d.set_item("gate", self.gate)?;
        d.set_item("keep_ambiguous", self.keep_ambiguous)?;
        d.set_item("variant", &self.variant)?;
        d.set_item("trim", self.trim)?;
        d.set_item("iterations", self.iterations)?;
        d.set_item("global_search", self.global_search)?;
        Ok(d)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("DistanceOptions(**{})", self.as_dict(py)?.repr()?))
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let f = py
            .import("bipolar._bipolar")?
            .getattr("_distance_options_from_dict")?;
        Ok((f, PyTuple::new(py, [self.as_dict(py)?])?))
    }
}

/// Rebuilds pickled `DistanceOptions`.
#[pyfunction]
pub fn _distance_options_from_dict(
    py: Python<'_>,
    d: &Bound<'_, PyDict>,
) -> PyResult<Py<PyDistanceOptions>> {
    let cls = py.get_type::<PyDistanceOptions>();
    Ok(cls
        .call((), Some(d))?
        .cast_into::<PyDistanceOptions>()?
        .unbind())
}

/// `options`, or options built from keyword arguments (not both).
pub fn options_arg(
    py: Python<'_>,
    options: Option<&Bound<'_, PyDistanceOptions>>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyDistanceOptions> {
    let has_kw = kwargs.is_some_and(|k| !k.is_empty());
    match (options, has_kw) {
        (Some(_), true) => Err(errors::input(
            "give either options=DistanceOptions(...) or keyword options, not both",
        )),
        (Some(o), false) => Ok(o.get().clone()),
        (None, _) => {
            let cls = py.get_type::<PyDistanceOptions>();
            let o = cls.call((), kwargs)?;
            Ok(o.cast_into::<PyDistanceOptions>()?.get().clone())
        }
    }
}

/// A descriptor reduced to what the distances need (as `bipolar distance` loads a file).
struct Loaded {
    keys: Vec<u64>,
    key_points: Vec<DVec3>,
    points: Vec<DVec3>,
}

fn load(d: &bipolar::Descriptor, keep_ambiguous: bool) -> Loaded {
    let kept: Vec<_> = d
        .points
        .iter()
        .filter(|p| keep_ambiguous || !p.ambiguous)
        .collect();
    Loaded {
        keys: kept.iter().map(|p| p.key.pack()).collect(),
        key_points: kept.iter().map(|p| p.position).collect(),
        points: d.positions(),
    }
}

/// The sets of a list of descriptors, prepared once for the ICP modes.
struct Sets {
    loaded: Vec<Loaded>,
    prepared: Option<Vec<PreparedSet>>,
}

fn prepare_sets(
    ds: &[&bipolar::Descriptor],
    o: &PyDistanceOptions,
    which: Which,
) -> Result<Sets, (usize, ShapeDistError)> {
    let loaded: Vec<Loaded> = ds.iter().map(|d| load(d, o.keep_ambiguous)).collect();
    let prepared = if o.mode == Mode::Keys {
        None
    } else {
        let po = PrepareOptions::default();
        Some(
            loaded
                .par_iter()
                .enumerate()
                .map(|(i, l)| PreparedSet::new(&l.points, &po, which).map_err(|e| (i, e)))
                .collect::<Result<Vec<_>, _>>()?,
        )
    };
    Ok(Sets { loaded, prepared })
}

fn rows(r: DMat3) -> [[f64; 3]; 3] {
    let t = r.transpose();
    [
        t.x_axis.to_array(),
        t.y_axis.to_array(),
        t.z_axis.to_array(),
    ]
}

/// The distance of one pair and, when `details`, the fields `bipolar distance --json` prints.
fn compare(
    a: &Loaded,
    b: &Loaded,
    pa: Option<&PreparedSet>,
    pb: Option<&PreparedSet>,
    o: &PyDistanceOptions,
    details: bool,
) -> Result<(f64, Option<serde_json::Value>), ShapeDistError> {
    match o.mode {
        Mode::Keys => {
            let r = shapedist::keyed_distance(
                &a.keys,
                &a.key_points,
                &b.keys,
                &b.key_points,
                &o.keyed,
            )?;
            let v = details.then(|| {
                json!({
                    "mode": "keys",
                    "distance": r.distance,
                    "rotation": rows(r.motion.matrix3),
                    "translation": r.motion.translation.to_array(),
                    "shared_keys": r.shared_keys,
                    "pairs_used": r.pairs_used,
                    "share_a": r.share_a,
                    "share_b": r.share_b,
                    "points_a": a.points.len(),
                    "points_b": b.points.len(),
                    "keyed_points_a": a.keys.len(),
                    "keyed_points_b": b.keys.len(),
                    "repeated_keys_a": r.ambiguous_a,
                    "repeated_keys_b": r.ambiguous_b,
                    "gated": r.gated,
                    "rmse": r.rmse,
                    "max_residual": r.max_residual,
                })
            });
            Ok((r.distance, v))
        }
        Mode::Icp | Mode::Hausdorff => {
            let owned;
            let (pa, pb) = match (pa, pb) {
                (Some(x), Some(y)) => (x, y),
                _ => {
                    let po = PrepareOptions::default();
                    owned = (
                        PreparedSet::new(&a.points, &po, Which::A)?,
                        PreparedSet::new(&b.points, &po, Which::B)?,
                    );
                    (&owned.0, &owned.1)
                }
            };
            let r = shapedist::icp_distance(pa, pb, &o.global)?;
            let d = if o.mode == Mode::Icp {
                r.stats.mean_normalised
            } else {
                r.stats.hausdorff_normalised
            };
            let v = details.then(|| {
                json!({
                    "mode": if o.mode == Mode::Icp { "icp" } else { "hausdorff" },
                    "distance": d,
                    "mean_normalised": r.stats.mean_normalised,
                    "hausdorff_normalised": r.stats.hausdorff_normalised,
                    "rms_normalised": r.stats.rms_normalised,
                    "mean": r.stats.mean,
                    "hausdorff": r.stats.hausdorff,
                    "rms": r.stats.rms,
                    "rotation": rows(r.motion.matrix3),
                    "translation": r.motion.translation.to_array(),
                    "iterations": r.iterations,
                    "converged": r.converged,
                    "starts": r.starts,
                    "rmse": r.rmse,
                    "points_a": a.points.len(),
                    "points_b": b.points.len(),
                })
            });
            Ok((d, v))
        }
    }
}

/// A failure inside a detached computation, turned into an exception once the GIL is held.
enum Fail {
    Pair(usize, usize, ShapeDistError),
    Set(&'static str, usize, ShapeDistError),
    Threads(String),
}

impl Fail {
    fn into_py(self) -> PyErr {
        match self {
            Fail::Pair(i, j, e) => errors::input(format!("pair ({i}, {j}): {e}")),
            Fail::Set(what, i, e) => errors::input(format!("{what}[{i}]: {e}")),
            Fail::Threads(m) => errors::input(m),
        }
    }
}

fn descriptor_list<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Vec<Bound<'py, PyDescriptor>>> {
    let it = obj
        .try_iter()
        .map_err(|_| errors::type_error(format!("{what} must be a sequence of Descriptor")))?;
    let mut out = Vec::new();
    for (k, item) in it.enumerate() {
        let item = item?;
        let d = item
            .cast::<PyDescriptor>()
            .map_err(|_| errors::type_error(format!("{what}[{k}] is not a bipolar.Descriptor")))?;
        out.push(d.clone());
    }
    Ok(out)
}

/// Normalised shape distance between two descriptors, in [0, 1] (see ``DistanceOptions``;
/// ``options`` or the same keyword arguments).
#[pyfunction]
#[pyo3(signature = (a, b, options=None, **kwargs))]
pub fn distance(
    py: Python<'_>,
    a: &Bound<'_, PyDescriptor>,
    b: &Bound<'_, PyDescriptor>,
    options: Option<&Bound<'_, PyDistanceOptions>>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<f64> {
    let o = options_arg(py, options, kwargs)?;
    let (da, db) = (&a.get().d, &b.get().d);
    py.detach(|| {
        let (la, lb) = (load(da, o.keep_ambiguous), load(db, o.keep_ambiguous));
        compare(&la, &lb, None, None, &o, false).map(|(d, _)| d)
    })
    .map_err(errors::shapedist)
}

/// ``distance`` with the details ``bipolar distance --json`` prints (rotation, shared keys and
/// shares, iterations, rmse, raw closest-point distances, ...) as a dict.
#[pyfunction]
#[pyo3(signature = (a, b, options=None, **kwargs))]
pub fn distance_details<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyDescriptor>,
    b: &Bound<'py, PyDescriptor>,
    options: Option<&Bound<'py, PyDistanceOptions>>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let o = options_arg(py, options, kwargs)?;
    let (da, db) = (&a.get().d, &b.get().d);
    let v = py
        .detach(|| {
            let (la, lb) = (load(da, o.keep_ambiguous), load(db, o.keep_ambiguous));
            compare(&la, &lb, None, None, &o, true)
        })
        .map_err(errors::shapedist)?
        .1
        .unwrap_or_default();
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

/// The symmetric matrix of pairwise distances, zero diagonal, shape (n, n); pairs in parallel
/// (``threads`` rayon threads, default one per core), each ICP set prepared once.
#[pyfunction]
#[pyo3(signature = (descriptors, options=None, *, threads=None, **kwargs))]
pub fn distance_matrix<'py>(
    py: Python<'py>,
    descriptors: &Bound<'py, PyAny>,
    options: Option<&Bound<'py, PyDistanceOptions>>,
    threads: Option<usize>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let o = options_arg(py, options, kwargs)?;
    let ds = descriptor_list(descriptors, "descriptors")?;
    let refs: Vec<&bipolar::Descriptor> = ds.iter().map(|d| &d.get().d).collect();
    let n = refs.len();
    let m = py
        .detach(|| {
            convert::with_threads(threads, || {
                let sets = prepare_sets(&refs, &o, Which::A)
                    .map_err(|(i, e)| Fail::Set("descriptors", i, e))?;
                let idx: Vec<usize> = (0..n).collect();
                shapedist::pairwise_matrix(&idx, |&i, &j| {
                    let (pa, pb) = match &sets.prepared {
                        Some(p) => (Some(&p[i]), Some(&p[j])),
                        None => (None, None),
                    };
                    compare(&sets.loaded[i], &sets.loaded[j], pa, pb, &o, false).map(|(d, _)| d)
                })
                .map_err(|e| Fail::Pair(e.i, e.j, e.error))
            })
            .map_err(Fail::Threads)?
        })
        .map_err(Fail::into_py)?;
    Ok(rows_out(py, m.into_iter().flatten().collect(), n))
}

/// Distances of every row descriptor to every column descriptor, shape (r, c): entry (i, j) is
/// ``distance(rows[i], cols[j])`` (for blocks of a matrix, 1:N identification). Parallel as
/// ``distance_matrix``.
#[pyfunction]
#[pyo3(signature = (rows, cols, options=None, *, threads=None, **kwargs))]
pub fn cross_distances<'py>(
    py: Python<'py>,
    rows: &Bound<'py, PyAny>,
    cols: &Bound<'py, PyAny>,
    options: Option<&Bound<'py, PyDistanceOptions>>,
    threads: Option<usize>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let o = options_arg(py, options, kwargs)?;
    let r = descriptor_list(rows, "rows")?;
    let c = descriptor_list(cols, "cols")?;
    let rr: Vec<&bipolar::Descriptor> = r.iter().map(|d| &d.get().d).collect();
    let cc: Vec<&bipolar::Descriptor> = c.iter().map(|d| &d.get().d).collect();
    let (nr, nc) = (rr.len(), cc.len());
    let flat = py
        .detach(|| {
            convert::with_threads(threads, || {
                let sr =
                    prepare_sets(&rr, &o, Which::A).map_err(|(i, e)| Fail::Set("rows", i, e))?;
                let sc =
                    prepare_sets(&cc, &o, Which::A).map_err(|(j, e)| Fail::Set("cols", j, e))?;
                let pairs: Vec<(usize, usize)> =
                    (0..nr).flat_map(|i| (0..nc).map(move |j| (i, j))).collect();
                pairs
                    .par_iter()
                    .map(|&(i, j)| {
                        let (pa, pb) = match (&sr.prepared, &sc.prepared) {
                            (Some(p), Some(q)) => (Some(&p[i]), Some(&q[j])),
                            _ => (None, None),
                        };
                        compare(&sr.loaded[i], &sc.loaded[j], pa, pb, &o, false)
                            .map(|(d, _)| d)
                            .map_err(|e| Fail::Pair(i, j, e))
                    })
                    .collect::<Result<Vec<f64>, Fail>>()
            })
            .map_err(Fail::Threads)?
        })
        .map_err(Fail::into_py)?;
    Ok(rows_out(py, flat, nc))
}
