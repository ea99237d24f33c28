//! The Python methods the descriptor wrappers (`Descriptor`, `PolarDescriptor`,
//! `FacialCurves`) share, written once: [`descriptor_pymethods!`].

/// Writes `#[pymethods] impl $ty` for a frozen wrapper `{ d }` of a descriptor: the pieces
/// named, then the type's own methods (the block at the end).
///
/// - `surface_points { keys: METHOD, /// doc\n faces }`: the getters ``points`` (from
///   `d.positions()`), ``keys`` (from `d.METHOD()`), ``faces`` (with the doc given) and
///   ``bary`` of the keyed surface points `d.points`.
/// - `levels { /// doc\n step, /// doc\n n_levels }`: ``step`` and ``n_levels`` of
///   `d.options`, each with the doc given.
/// - `summary { "Name", ITEMS "noun", key = path, ... }`: ``__len__`` (the length of
///   `d.ITEMS`) and ``__repr__`` ``Name(<len> noun, key=<d.path>, ...)``.
macro_rules! descriptor_pymethods {
    (
        $ty:ty,
        $(surface_points { keys: $keys:ident, $(#[$faces_doc:meta])* faces })?
        $(levels { $(#[$step_doc:meta])* step, $(#[$levels_doc:meta])* n_levels })?
        $(summary {
            $name:literal, $items:ident $noun:literal $(, $key:ident = $($path:ident).+)*
        })?
        { $($own:tt)* }
    ) => {
        #[pymethods]
        impl $ty {
            $(
                /// Point positions, shape (n, 3).
                #[getter]
                fn points<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
                    $crate::convert::points_out(py, &self.d.positions())
                }

                /// Packed keys, shape (n,), uint64.
                #[getter]
                fn keys<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<u64>> {
                    $crate::convert::vec_out(py, self.d.$keys())
                }

                $(#[$faces_doc])*
                #[getter]
                fn faces<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<u32>> {
                    $crate::convert::vec_out(py, self.d.points.iter().map(|p| p.face).collect())
                }

                /// Barycentric coordinates of each point in its face, shape (n, 3).
                #[getter]
                fn bary<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
                    let b: Vec<glam::DVec3> = self.d.points.iter().map(|p| p.bary).collect();
                    $crate::convert::points_out(py, &b)
                }
            )?

            $(
                $(#[$step_doc])*
                #[getter]
                fn step(&self) -> f64 {
                    self.d.options.step
                }

                $(#[$levels_doc])*
                #[getter]
                fn n_levels(&self) -> u32 {
                    self.d.options.levels
                }
            )?

            $(
                fn __len__(&self) -> usize {
                    self.d.$items.len()
                }

                fn __repr__(&self) -> String {
                    let mut s = format!("{}({} {}", $name, self.d.$items.len(), $noun);
                    $(s += &format!(", {}={}", stringify!($key), self.d.$($path).+);)*
                    s.push(')');
                    s
                }
            )?

            $($own)*
        }
    };
}
