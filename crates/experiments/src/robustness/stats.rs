//! The separation tables' columns and finite-value reductions of distances.

use crate::report::f4;
pub(crate) use shapedist::Separation as Sep;

/// "separated" when `ratio` is above 1.
pub(crate) fn verdict(ratio: f64) -> &'static str {
    if ratio > 1.0 {
        "separated"
    } else {
        "NOT separated"
    }
}

/// A column of the separation tables: its header and its cell for a [`Sep`] (distances with 4
/// decimals, ratios with 3).
pub(super) type SepColumn = (&'static str, fn(&Sep) -> String);

/// Every column of the separation tables, in table order.
pub(super) const SEP_COLUMNS: [SepColumn; 8] = [
    ("max same", |s| f4(s.max_same)),
    ("min different", |s| f4(s.min_diff)),
    ("ratio", |s| format!("{:.3}", s.ratio())),
    ("whole matrix", |s| verdict(s.ratio()).into()),
    ("test row: max same", |s| f4(s.row_max_same)),
    ("test row: min different", |s| f4(s.row_min_diff)),
    ("test-row ratio", |s| format!("{:.3}", s.row_ratio())),
    ("test row", |s| verdict(s.row_ratio()).into()),
];

/// The finite values of `v`, in order.
fn finite(v: &[f64]) -> impl Iterator<Item = f64> + '_ {
    v.iter().copied().filter(|x| x.is_finite())
}

/// Mean of the finite values (NaN if none).
pub(crate) fn mean(v: &[f64]) -> f64 {
    let (sum, n) = finite(v).fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// Max of the finite values (NaN if none).
pub(crate) fn max(v: &[f64]) -> f64 {
    finite(v).reduce(f64::max).unwrap_or(f64::NAN)
}

/// Min of the finite values (NaN if none).
pub(crate) fn min(v: &[f64]) -> f64 {
    finite(v).reduce(f64::min).unwrap_or(f64::NAN)
}
