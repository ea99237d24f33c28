//! Per-landmark error statistics and the error histogram, shared by the evaluations on meshes,
//! on range scans and beyond the model (a detection is scored by `landmarks::eval`).

use anyhow::Result;
use landmarks::eval::{scored_errors, Scored};
use landmarks::LandmarkName;
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

pub(super) use crate::report::{quantile, sorted};

/// The statistics of one landmark's errors `errs` (mm; infinite: not found).
pub(super) fn stats(name: &str, errs: &[f64]) -> Stats {
    let v = sorted(errs.to_vec());
    let n = v.len();
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let share = |t: f64| v.iter().filter(|&&x| x <= t).count() as f64 / n.max(1) as f64;
    Stats {
        landmark: name.to_owned(),
        n,
        failures: n - finite.len(),
        mean_mm: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
        median_mm: quantile(&v, 0.5),
        p95_mm: quantile(&v, 0.95),
        max_mm: quantile(&v, 1.0),
        within_2_5mm: share(2.5),
        within_5mm: share(5.0),
        within_10mm: share(10.0),
    }
}

/// Prints the per-landmark table of `st`: with each landmark's count when `counts`, and the
/// column `extra` (header, one value per landmark) last when given.
pub(super) fn print_table(st: &[Stats], counts: bool, extra: Option<(&str, &[usize])>) {
    let n = |s: &str| {
        if counts {
            format!(" {s:>5}")
        } else {
            String::new()
        }
    };
    let x = |s: &str| extra.map_or(String::new(), |_| format!(" {s:>7}"));
    println!(
        "{:<16}{} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}{}",
        "landmark",
        n("n"),
        "mean",
        "median",
        "p95",
        "max",
        "<2.5",
        "<5",
        "<10",
        x(extra.map_or("", |e| e.0))
    );
    for (k, s) in st.iter().enumerate() {
        println!(
            "{:<16}{} {:>7.2} {:>7.2} {:>7.2} {:>7.2} {:>6.1}% {:>6.1}% {:>6.1}%{}",
            s.landmark,
            n(&s.n.to_string()),
            s.mean_mm,
            s.median_mm,
            s.p95_mm,
            s.max_mm,
            100.0 * s.within_2_5mm,
            100.0 * s.within_5mm,
            100.0 * s.within_10mm,
            x(&extra.map_or(0, |e| e.1[k]).to_string())
        );
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

/// The histogram of the errors of the landmarks whose truth is on the surface.
pub(super) fn scored_histogram(path: &Path, title: &str, scored: &[&Scored]) -> Result<()> {
    let series = LandmarkName::ALL
        .iter()
        .map(|&n| (n.key().to_string(), scored_errors(scored, n)))
        .collect();
    error_histogram(path, title, series)
}

/// The per-landmark statistics of the errors whose truth is on the surface.
pub(super) fn scored_stats(scored: &[&Scored]) -> Vec<Stats> {
    LandmarkName::ALL
        .iter()
        .map(|&n| stats(n.key(), &scored_errors(scored, n)))
        .collect()
}

/// A CSV cell of free text: commas become semicolons.
pub(super) fn text(s: &str) -> String {
    s.replace(',', ";")
}
