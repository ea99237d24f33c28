//! Shape distances between descriptors: keyed closed form, ICP, Hausdorff; matrices.
//!
//! The option names and their mapping are those of `bipolar distance` / `bipolar matrix`.

use crate::convert::{self, rows_out};
use crate::descriptor::PyDescriptor;
use crate::errors;
use meshcore::Choice;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use shapedist::{
    CompareOptions, ComparedSet, IcpVariant, Mode, RobustWeights, RotationMethod, ShapeDistError,
    Which,
};

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
    solver: String,
    robust: Option<String>,
    keep_ambiguous: bool,
    variant: String,
    o: CompareOptions,
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
        let mode = Mode::from_name(mode).map_err(|e| {
            errors::input(meshcore::UnknownChoice { what: "mode", ..e }.to_string())
        })?;
        let robust_weights = robust
            .map(|r| {
                RobustWeights::from_name(r).map_err(|_| {
                    errors::input(format!(
                        "unknown robust weights {r:?} (expected huber, tukey or None)"
                    ))
                })
            })
            .transpose()?;
        let o = CompareOptions {
            mode,
            solver: solver
                .parse::<RotationMethod>()
                .map_err(errors::shapedist)?,
            robust: robust_weights,
            gate,
            variant: variant.parse::<IcpVariant>().map_err(errors::shapedist)?,
            trim,
            iterations,
            global_search,
        };
        Ok(Self {
            solver: solver.into(),
            robust: robust.map(Into::into),
            keep_ambiguous,
            variant: variant.into(),
            o,
        })
    }

    /// ``"keys"``, ``"icp"`` or ``"hausdorff"``.
    #[getter]
    fn mode(&self) -> &'static str {
        self.o.mode.name()
    }

    /// The options as keyword arguments of the constructor.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("mode", self.mode())?;
        d.set_item("solver", &self.solver)?;
        d.set_item("robust", &self.robust)?;
        d.set_item("gate", self.o.gate)?;
        d.set_item("keep_ambiguous", self.keep_ambiguous)?;
        d.set_item("variant", &self.variant)?;
        d.set_item("trim", self.o.trim)?;
        d.set_item("iterations", self.o.iterations)?;
        d.set_item("global_search", self.o.global_search)?;
        Ok(d)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("DistanceOptions(**{})", self.as_dict(py)?.repr()?))
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<convert::Reduced<'py>> {
        convert::reduced(
            py,
            "_distance_options_from_dict",
            [self.as_dict(py)?.into_any()],
        )
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
fn load(d: &bipolar::Descriptor, keep_ambiguous: bool) -> ComparedSet {
    let (keys, key_points) = d.keyed_points(keep_ambiguous);
    ComparedSet::new(keys, key_points, d.positions())
}

/// The distance of one pair.
fn distance_of(
    a: &ComparedSet,
    b: &ComparedSet,
    o: &PyDistanceOptions,
) -> Result<f64, ShapeDistError> {
    shapedist::compare(a, b, &o.o).map(|r| r.distance())
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

/// The descriptors of each of `lists` (a Python sequence of Descriptor and its name) reduced to
/// their sets and prepared once for the ICP modes, in parallel with the GIL released on
/// `threads` rayon threads (default one per core); then `f` on them, in the same pool.
fn on_sets<const N: usize, T: Send>(
    py: Python<'_>,
    lists: [(&Bound<'_, PyAny>, &'static str); N],
    o: &PyDistanceOptions,
    threads: Option<usize>,
    f: impl FnOnce(&[Vec<ComparedSet>; N]) -> Result<T, Fail> + Send,
) -> PyResult<T> {
    let mut bound = Vec::with_capacity(N);
    for (obj, what) in lists {
        bound.push((descriptor_list(obj, what)?, what));
    }
    let ds: Vec<(Vec<&bipolar::Descriptor>, &'static str)> = bound
        .iter()
        .map(|(l, what)| (l.iter().map(|d| &d.get().d).collect(), *what))
        .collect();
    py.detach(|| {
        convert::with_threads(threads, || {
            let mut sets = Vec::with_capacity(N);
            for (list, what) in &ds {
                let mut s: Vec<ComparedSet> =
                    list.iter().map(|d| load(d, o.keep_ambiguous)).collect();
                s.par_iter_mut().enumerate().try_for_each(|(i, x)| {
                    x.prepare(o.o.mode, Which::A)
                        .map_err(|e| Fail::Set(what, i, e))
                })?;
                sets.push(s);
            }
            let mut sets = sets.into_iter();
            f(&std::array::from_fn(|_| sets.next().unwrap_or_default()))
        })
        .map_err(Fail::Threads)?
    })
    .map_err(Fail::into_py)
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
    py.detach(|| distance_of(&load(da, o.keep_ambiguous), &load(db, o.keep_ambiguous), &o))
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
            shapedist::compare(&la, &lb, &o.o).map(|r| r.details(&la, &lb))
        })
        .map_err(errors::shapedist)?;
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

/// A face described with a reference-point search: a list from ``describe(...,
/// search_radius=)`` (the own descriptor first), or one Descriptor (a list of one).
fn searched_list<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Vec<Bound<'py, PyDescriptor>>> {
    if let Ok(d) = obj.cast::<PyDescriptor>() {
        return Ok(vec![d.clone()]);
    }
    let list = descriptor_list(obj, what)?;
    if list.is_empty() {
        return Err(errors::input(format!(
            "{what} is an empty list: a searched face is its own descriptor followed by the moved ones"
        )));
    }
    Ok(list)
}

/// The distance of two faces described with a reference-point search (``describe(...,
/// search_radius=)`` lists, own descriptor first; a Descriptor counts as a list of one): the
/// least of the own descriptors' distance and each side's moved descriptors against the other
/// side's own (``bipolar::least_searched_distance``; moved against moved is not compared, so
/// the two faces never both move). Symmetric. Failed distances are skipped; the own pair's
/// error is raised when every one fails.
#[pyfunction]
#[pyo3(signature = (a, b, options=None, **kwargs))]
pub fn searched_distance(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDistanceOptions>>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<f64> {
    let o = options_arg(py, options, kwargs)?;
    let (la, lb) = (searched_list(a, "a")?, searched_list(b, "b")?);
    let da: Vec<&bipolar::Descriptor> = la.iter().map(|d| &d.get().d).collect();
    let db: Vec<&bipolar::Descriptor> = lb.iter().map(|d| &d.get().d).collect();
    py.detach(|| {
        let sets = |l: &[&bipolar::Descriptor]| -> Vec<ComparedSet> {
            l.iter().map(|d| load(d, o.keep_ambiguous)).collect()
        };
        let (sa, sb) = (sets(&da), sets(&db));
        bipolar::least_searched_distance(&sa[0], &sa[1..], &sb[0], &sb[1..], |x, y| {
            distance_of(x, y, &o)
        })
    })
    .map_err(errors::shapedist)
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
    let m = on_sets(py, [(descriptors, "descriptors")], &o, threads, |[sets]| {
        let idx: Vec<usize> = (0..sets.len()).collect();
        shapedist::pairwise_matrix(&idx, |&i, &j| distance_of(&sets[i], &sets[j], &o))
            .map_err(|e| Fail::Pair(e.i, e.j, e.error))
    })?;
    let n = m.len();
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
    let (flat, nc) = on_sets(
        py,
        [(rows, "rows"), (cols, "cols")],
        &o,
        threads,
        |[r, c]| {
            let pairs: Vec<(usize, usize)> = (0..r.len())
                .flat_map(|i| (0..c.len()).map(move |j| (i, j)))
                .collect();
            let flat = pairs
                .par_iter()
                .map(|&(i, j)| distance_of(&r[i], &c[j], &o).map_err(|e| Fail::Pair(i, j, e)))
                .collect::<Result<Vec<f64>, Fail>>()?;
            Ok((flat, c.len()))
        },
    )?;
    Ok(rows_out(py, flat, nc))
}
