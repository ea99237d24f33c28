//! numpy arrays in and out, with every check a caller from Python needs: type and dtype,
//! shape, index range. Non-contiguous arrays are read through their strides (no copy is
//! required from the caller); values NaN / infinite are left to the library checks, which name
//! the offending vertex or point.

use crate::errors;
use glam::DVec3;
use numpy::ndarray::{Array1, Array2};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

/// `obj` as a numpy array (`numpy.asarray` for lists, tuples and other array-likes).
fn as_ndarray<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let py = obj.py();
    let arr = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| errors::type_error(format!("{what}: cannot be read as an array ({e})")))?;
    arr.cast_into::<PyUntypedArray>()
        .map_err(|_| errors::type_error(format!("{what}: cannot be read as an array")))
}

/// `a`, or an aligned copy when its data is not aligned for its dtype (arrays rebuilt from
/// pickle-5 buffers, `np.frombuffer` at odd offsets): ndarray views require alignment.
fn aligned<'py>(a: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let ok: bool = a.getattr("flags")?.getattr("aligned")?.extract()?;
    if ok {
        Ok(a)
    } else {
        a.call_method0("copy")
    }
}

fn dtype_name(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype()
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// `a` if its dtype kind is one of `kinds` (numpy's one-letter kinds), else an
/// `InputTypeError` saying it must be an array of `of`.
fn check_kind(a: &Bound<'_, PyUntypedArray>, what: &str, kinds: &[u8], of: &str) -> PyResult<u8> {
    let kind = a.dtype().kind();
    if !kinds.contains(&kind) {
        return Err(errors::type_error(format!(
            "{what} must be an array of {of}, got dtype {}",
            dtype_name(a)
        )));
    }
    Ok(kind)
}

/// `a` as an aligned array of `T` (`name`: the numpy dtype name), converted with `astype` when
/// its dtype is another one.
fn typed<'py, T: numpy::Element>(
    a: Bound<'py, PyUntypedArray>,
    name: &str,
    what: &str,
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let a = if a.dtype().is_equiv_to(&numpy::dtype::<T>(a.py())) {
        a.into_any()
    } else {
        a.call_method1("astype", (name,))?
    };
    aligned(a)?
        .cast_into::<PyArrayDyn<T>>()
        .map_err(|_| errors::type_error(format!("{what}: expected an array of dtype {name}")))
}

/// `obj` as a float64 array: real floating and integer dtypes are converted (exactly for
/// float16/32 and integers below 2^53), anything else (bool, complex, strings, objects) is an
/// `InputTypeError`.
pub fn f64_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let a = as_ndarray(obj, what)?;
    check_kind(&a, what, b"fiu", "real numbers")?;
    typed(a, "float64", what)
}

/// `obj` as an int64 array; integer dtypes only (a float array of indices is an
/// `InputTypeError`, as numpy's own indexing has it). uint64 values above `i64::MAX` are
/// rejected.
pub fn i64_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, PyArrayDyn<i64>>> {
    let a = as_ndarray(obj, what)?;
    let kind = check_kind(&a, what, b"iu", "integers")?;
    if kind == b'u' && a.dtype().itemsize() == 8 {
        let max = a.call_method0("max");
        if let Ok(m) = max {
            let m: u64 = m.extract().unwrap_or(0);
            if m > i64::MAX as u64 {
                return Err(errors::index(format!("{what}: value {m} is out of range")));
            }
        }
    }
    typed(a, "int64", what)
}

fn shape_str(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(|s| s.to_string()).collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

/// How the shape of an array is checked by [`values`].
#[derive(Debug, Clone, Copy)]
enum Shape {
    /// 1-dimensional (`scalar`: a 0-dimensional array is taken as one value).
    Vector { scalar: bool },
    /// `(rows, 3)`, `rows` naming the row count in the message (`n`, `m`).
    Rows3(&'static str),
}

/// The values of `a` in row-major order (read through its strides) after checking its shape.
fn values<T: numpy::Element + Copy>(
    a: &Bound<'_, PyArrayDyn<T>>,
    what: &str,
    shape: Shape,
) -> PyResult<Vec<T>> {
    let ro = a
        .try_readonly()
        .map_err(|e| errors::input(format!("{what}: {e}")))?;
    let v = ro.as_array();
    let sh = v.shape();
    let (ok, expected) = match shape {
        Shape::Vector { scalar } => (
            sh.len() == 1 || (scalar && sh.is_empty()),
            "be 1-dimensional, got shape".to_string(),
        ),
        Shape::Rows3(rows) => (
            sh.len() == 2 && sh[1] == 3,
            format!("have shape ({rows}, 3), got"),
        ),
    };
    if !ok {
        return Err(errors::input(format!(
            "{what} must {expected} {}",
            shape_str(sh)
        )));
    }
    Ok(v.iter().copied().collect())
}

/// An `(n, 3)` array of real numbers as points (`n` may be 0; callers decide).
pub fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<DVec3>> {
    let v = values(&f64_array(obj, what)?, what, Shape::Rows3("n"))?;
    Ok(v.chunks_exact(3)
        .map(|r| DVec3::new(r[0], r[1], r[2]))
        .collect())
}

/// A single point: shape `(3,)`.
pub fn point(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<DVec3> {
    let v = f64_vec(obj, what)?;
    if v.len() != 3 {
        return Err(errors::input(format!(
            "{what} must have 3 coordinates, got {}",
            v.len()
        )));
    }
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// A 1-D array of real numbers.
pub fn f64_vec(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    values(
        &f64_array(obj, what)?,
        what,
        Shape::Vector { scalar: false },
    )
}

/// A 1-D array (or a scalar) of integers, each in `0..=u32::MAX`.
pub fn u32_vec(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u32>> {
    let v = values(&i64_array(obj, what)?, what, Shape::Vector { scalar: true })?;
    v.into_iter()
        .enumerate()
        .map(|(k, x)| {
            u32::try_from(x)
                .map_err(|_| errors::index(format!("{what}[{k}] = {x} is not a valid index")))
        })
        .collect()
}

/// A 1-D array of integers as `u64` (negative values rejected).
pub fn u64_vec(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u64>> {
    let a = as_ndarray(obj, what)?;
    let kind = check_kind(&a, what, b"iu", "integers")?;
    let vector = Shape::Vector { scalar: false };
    if kind == b'u' {
        return values(&typed::<u64>(a, "uint64", what)?, what, vector);
    }
    let v = values(&i64_array(a.as_any(), what)?, what, vector)?;
    v.into_iter()
        .enumerate()
        .map(|(k, x)| {
            u64::try_from(x).map_err(|_| errors::input(format!("{what}[{k}] = {x} is negative")))
        })
        .collect()
}

/// A 1-D boolean array (bool dtype only).
pub fn bool_vec(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<bool>> {
    let a = as_ndarray(obj, what)?;
    if a.dtype().kind() != b'b' {
        return Err(errors::type_error(format!(
            "{what} must be a boolean array, got dtype {}",
            dtype_name(&a)
        )));
    }
    if a.ndim() != 1 {
        return Err(errors::input(format!(
            "{what} must be 1-dimensional, got shape {}",
            shape_str(a.shape())
        )));
    }
    a.call_method0("tolist")?.extract()
}

/// An `(m, 3)` array of vertex indices (range against the vertex count is checked by
/// `TriMesh::new`).
pub fn triangles(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[u32; 3]>> {
    let v = values(&i64_array(obj, what)?, what, Shape::Rows3("m"))?;
    let mut out = Vec::with_capacity(v.len() / 3);
    for (f, r) in v.chunks_exact(3).enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            t[k] = u32::try_from(r[k]).map_err(|_| {
                errors::index(format!(
                    "{what}[{f}, {k}] = {} is not a valid vertex index",
                    r[k]
                ))
            })?;
        }
        out.push(t);
    }
    Ok(out)
}

/// Points as an `(n, 3)` float64 array.
pub fn points_out<'py>(py: Python<'py>, p: &[DVec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flat_map(|q| q.to_array()).collect();
    rows_out(py, flat, 3)
}

/// A flat row-major buffer as an `(len / cols, cols)` array.
pub fn rows_out<'py, T: numpy::Element>(
    py: Python<'py>,
    flat: Vec<T>,
    cols: usize,
) -> Bound<'py, PyArray2<T>> {
    let cols = cols.max(1);
    let n = flat.len() / cols;
    let mut flat = flat;
    // Every caller passes n * cols values; a stray tail would be dropped, never a panic.
    flat.truncate(n * cols);
    match Array2::from_shape_vec((n, cols), flat) {
        Ok(a) => a.into_pyarray(py),
        Err(_) => PyArray2::zeros(py, [0, cols], false),
    }
}

/// A vector as a 1-D array.
pub fn vec_out<'py, T: numpy::Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyArray1<T>> {
    Array1::from_vec(v).into_pyarray(py)
}

/// A path argument: `str` or any `os.PathLike`.
pub fn path(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<std::path::PathBuf> {
    obj.extract::<std::path::PathBuf>()
        .map_err(|_| errors::type_error(format!("{what} must be a str or os.PathLike path")))
}

/// Runs `f` on a rayon pool of `threads` threads (`None`: the global pool, one thread per core).
/// Returns the message of a bad thread count (callers turn it into an exception once they hold
/// the GIL again).
pub fn with_threads<R: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> R + Send,
) -> Result<R, String> {
    match threads {
        None => Ok(f()),
        Some(0) => Err("threads must be at least 1".into()),
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| e.to_string())?;
            Ok(pool.install(f))
        }
    }
}

/// What `__reduce__` returns: the module function rebuilding the object, and its arguments.
pub type Reduced<'py> = (Bound<'py, PyAny>, Bound<'py, pyo3::types::PyTuple>);

/// The `__reduce__` value of an object rebuilt (unpickled) by `bipolar._bipolar.<rebuild>(*args)`.
pub fn reduced<'py>(
    py: Python<'py>,
    rebuild: &str,
    args: impl IntoIterator<Item = Bound<'py, PyAny>, IntoIter: ExactSizeIterator>,
) -> PyResult<Reduced<'py>> {
    let f = py.import("bipolar._bipolar")?.getattr(rebuild)?;
    Ok((f, pyo3::types::PyTuple::new(py, args)?))
}
