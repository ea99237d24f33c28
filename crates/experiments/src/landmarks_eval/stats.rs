//! Per-landmark error statistics and the error histogram shared by the evaluations on
//! meshes, on range scans and beyond the model.

use anyhow::Result;
use std::path::Path;

/// Statistics of one landmark's errors (mm).
#[derive(Debug, serde::Serialize)]
pub(super) struct Stats {
    /// The landmark's key.
    pub landmark: String,
    /// Errors counted.
    pub n: usize,
    /// Errors that are not finite (not found).
    pub failures: usize,
    /// Mean of the finite errors.
    pub mean_mm: f64,
    /// Median (not-found counted as infinite).
    pub median_mm: f64,
    /// 95th percentile.
    pub p95_mm: f64,
    /// Largest error.
    pub max_mm: f64,
    /// Share within 2.5 mm.
    pub within_2_5mm: f64,
    /// Share within 5 mm.
    pub within_5mm: f64,
    /// Share within 10 mm.
    pub within_10mm: f64,
}

/// The statistics of one landmark's errors `errs` (mm; infinite: not found).
pub(super) fn stats(name: &str, errs: &[f64]) -> Stats {
    let mut v = errs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let q = |p: f64| {
        if n == 0 {
            f64::NAN
        } else {
            v[((n - 1) as f64 * p).round() as usize]
        }
    };
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let share = |t: f64| v.iter().filter(|&&x| x <= t).count() as f64 / n.max(1) as f64;
    Stats {
        landmark: name.to_owned(),
        n,
        failures: n - finite.len(),
        mean_mm: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
        median_mm: q(0.5),
        p95_mm: q(0.95),
        max_mm: q(1.0),
        within_2_5mm: share(2.5),
        within_5mm: share(5.0),
        within_10mm: share(10.0),
    }
}

/// Writes the histogram of each landmark's errors (`series`: key, errors in mm), clipped at
/// 15 mm, with `title`.
pub(super) fn error_histogram(
    path: &Path,
    title: &str,
    series: Vec<(String, Vec<f64>)>,
) -> Result<()> {
    let clipped: Vec<(String, Vec<f64>)> = series
        .into_iter()
        .map(|(n, e)| (n, e.into_iter().map(|x| x.min(15.0)).collect()))
        .collect();
    viz::histogram(path, title, "error (mm, clipped at 15)", &clipped, 30)?;
    Ok(())
}
