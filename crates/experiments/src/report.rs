//! Report folder writing: `report.md` (text, tables, embedded figures), CSV tables, PNG twins
//! of the SVG figures, the line-plot call shared by the reports (figures are drawn by `viz`),
//! and the list of the errors a run met ([`Failures`]).

use anyhow::{Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A report being written into a folder.
#[derive(Debug)]
pub struct Report {
    dir: PathBuf,
    md: String,
}

impl Report {
    /// Creates (or reuses) `dir` and starts `report.md` with a title.
    pub fn new(dir: &Path, title: &str) -> Result<Self> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            md: format!("# {title}\n\n"),
        })
    }

    /// Path of a file in the report folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// Appends a heading.
    pub fn heading(&mut self, level: usize, text: &str) {
        let _ = write!(self.md, "{} {text}\n\n", "#".repeat(level.clamp(1, 6)));
    }

    /// Appends a paragraph.
    pub fn para(&mut self, text: &str) {
        let _ = write!(self.md, "{}\n\n", text.trim_end());
    }

    /// Appends a bulleted list, one item per line.
    pub fn list<T: std::fmt::Display>(&mut self, items: &[T]) {
        let text: String = items.iter().map(|s| format!("- {s}\n")).collect();
        self.para(&text);
    }

    /// Appends an embedded figure (file relative to the report folder).
    pub fn figure(&mut self, file: &str, caption: &str) {
        let _ = write!(self.md, "![{caption}]({file})\n\n*{caption}*\n\n");
    }

    /// Appends a Markdown table.
    pub fn table(&mut self, header: &[impl AsRef<str>], rows: &[Vec<String>]) {
        let _ = writeln!(
            self.md,
            "| {} |",
            joined(header, " | ", |h| h.as_ref().into())
        );
        let _ = writeln!(self.md, "|{}|", vec!["---"; header.len()].join("|"));
        for r in rows {
            let _ = writeln!(self.md, "| {} |", r.join(" | "));
        }
        self.md.push('\n');
    }

    /// Writes a CSV file into the folder.
    pub fn csv(&self, name: &str, header: &[impl AsRef<str>], rows: &[Vec<String>]) -> Result<()> {
        write_csv(&self.path(name), header, rows)
    }

    /// Appends a Markdown table and writes the same cells as the CSV file `name`.
    pub fn table_csv(
        &mut self,
        name: &str,
        header: &[impl AsRef<str>],
        rows: &[Vec<String>],
    ) -> Result<()> {
        self.table(header, rows);
        self.csv(name, header, rows)
    }

    /// Writes the matrix `m` as the CSV file `name`, rows and columns labelled by `labels`
    /// (the header's first cell `face`).
    pub fn matrix_csv(&self, name: &str, labels: &[impl AsRef<str>], m: &[Vec<f64>]) -> Result<()> {
        let header: Vec<&str> = std::iter::once("face")
            .chain(labels.iter().map(AsRef::as_ref))
            .collect();
        self.csv(name, &header, &labelled_rows(labels, m))
    }

    /// Draws a line plot into `file` ([`line_plot`]) and appends it as a figure with `caption`.
    pub fn plot(
        &mut self,
        file: &str,
        (title, x_label, y_label): (&str, &str, &str),
        series: &[Series],
        caption: &str,
    ) -> Result<()> {
        line_plot(&self.path(file), title, x_label, y_label, series)?;
        self.figure(file, caption);
        Ok(())
    }

    /// The Markdown written so far.
    pub fn markdown(&self) -> &str {
        &self.md
    }

    /// Writes a PNG twin of every SVG of the folder (rasterised by `viz::svg_to_png`, in
    /// parallel); returns how many were written.
    pub fn png_twins(&self) -> Result<usize> {
        use rayon::prelude::*;
        let mut svgs: Vec<PathBuf> = std::fs::read_dir(&self.dir)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "svg"))
            .collect();
        svgs.sort();
        svgs.par_iter()
            .map(|p| -> Result<()> {
                let svg = std::fs::read_to_string(p)?;
                let png = viz::svg_to_png(&svg)
                    .with_context(|| format!("rasterising {}", p.display()))?;
                std::fs::write(p.with_extension("png"), png)?;
                Ok(())
            })
            .collect::<Result<Vec<()>>>()?;
        Ok(svgs.len())
    }

    /// Writes `report.md` and returns its path.
    pub fn finish(&self) -> Result<PathBuf> {
        let p = self.path("report.md");
        std::fs::write(&p, &self.md).with_context(|| format!("writing {}", p.display()))?;
        Ok(p)
    }
}

/// Writes a CSV file (fields containing `,` or `"` are quoted).
pub fn write_csv(path: &Path, header: &[impl AsRef<str>], rows: &[Vec<String>]) -> Result<()> {
    let esc = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut out = joined(header, ",", |h| esc(h.as_ref()));
    out.push('\n');
    for r in rows {
        out.push_str(&r.iter().map(|f| esc(f)).collect::<Vec<_>>().join(","));
        out.push('\n');
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}

/// Writes `value` as pretty-printed JSON with a final newline.
pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

/// Rows of a labelled matrix: each label, then its row's values with 6 decimals.
pub fn labelled_rows(labels: &[impl AsRef<str>], m: &[Vec<f64>]) -> Vec<Vec<String>> {
    let row = |(l, r): (&_, &Vec<f64>)| {
        let values = r.iter().map(|v| format!("{v:.6}"));
        std::iter::once(AsRef::<str>::as_ref(l).to_string())
            .chain(values)
            .collect()
    };
    labels.iter().zip(m).map(row).collect()
}

/// The errors a run met, listed from parallel work (their cells are NaN), and a count of
/// pairs left out for too few shared keys.
#[derive(Debug, Default)]
pub struct Failures {
    listed: std::sync::Mutex<Vec<String>>,
    too_few: std::sync::atomic::AtomicUsize,
}

impl Failures {
    /// Lists an error.
    pub fn list(&self, msg: String) {
        let mut v = self
            .listed
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        v.push(msg);
    }

    /// Counts a pair with too few shared keys.
    pub fn too_few(&self) {
        self.too_few
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// `r`'s value, or `None` with its error listed (described by `what`).
    pub fn ok<T, E: std::fmt::Display>(
        &self,
        r: Result<T, E>,
        what: impl FnOnce() -> String,
    ) -> Option<T> {
        r.map_err(|e| self.list(format!("{}: {e}", what()))).ok()
    }

    /// The listed errors, sorted (the run is parallel), and the too-few-keys count.
    pub fn summary(&self) -> (Vec<String>, usize) {
        let mut v = self
            .listed
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone();
        v.sort();
        (v, self.too_few.load(std::sync::atomic::Ordering::Relaxed))
    }
}

/// `f` of every item of `items`, in parallel (rayon) and in item order, counted on a progress
/// bar labelled `msg` (`pipeline::bar`).
pub fn par_map<T: Sync, R: Send>(
    items: &[T],
    msg: &str,
    f: impl Fn(&T) -> R + Sync + Send,
) -> Vec<R> {
    use rayon::prelude::*;
    let pb = crate::pipeline::bar(items.len(), msg);
    let out = items
        .par_iter()
        .map(|x| {
            let r = f(x);
            pb.inc(1);
            r
        })
        .collect();
    pb.finish();
    out
}

/// The value at fraction `p` of the sorted values `v` (the nearest rank, rounded; NaN when
/// empty): the median of an even count is the upper middle value.
pub fn quantile(v: &[f64], p: f64) -> f64 {
    let k = ((v.len().max(1) - 1) as f64 * p).round() as usize;
    v.get(k).copied().unwrap_or(f64::NAN)
}

/// `v` sorted (NaN last).
pub fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v
}

/// Formats a number with 4 significant decimals.
pub fn f4(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.4}")
    } else {
        "n/a".into()
    }
}

/// `items` formatted by `f` and separated by `sep`.
pub fn joined<T>(
    items: impl IntoIterator<Item = T>,
    sep: &str,
    f: impl FnMut(T) -> String,
) -> String {
    items.into_iter().map(f).collect::<Vec<_>>().join(sep)
}

pub use viz::Series;

/// Markers of one colour and radius at `points`.
pub fn markers(
    points: impl IntoIterator<Item = meshcore::DVec3>,
    color: [u8; 3],
    radius: f64,
) -> Vec<viz::Marker> {
    points
        .into_iter()
        .map(|position| viz::Marker {
            position,
            color,
            radius,
        })
        .collect()
}

/// Polylines of one width through `curves` (`(points, closed, colour)` each).
pub fn polylines(
    curves: impl IntoIterator<Item = (Vec<meshcore::DVec3>, bool, [u8; 3])>,
    width: f64,
) -> Vec<viz::Polyline> {
    curves
        .into_iter()
        .map(|(points, closed, color)| viz::Polyline {
            points,
            closed,
            color,
            width,
        })
        .collect()
}

/// Renders a scene of a face seen from the front of its frame (looking along -`forward`),
/// 560 x 640 pixels, into `path` (SVG or PNG by the extension).
pub fn render_face(
    path: &Path,
    scene: &viz::Scene<'_>,
    up: meshcore::DVec3,
    forward: meshcore::DVec3,
) -> Result<()> {
    viz::render_to_file(path, scene, &viz::View::new(-forward, up), 560, 640)
        .with_context(|| format!("rendering {}", path.display()))
}

/// A line plot drawn by `viz` (SVG or PNG by the extension of `path`).
pub fn line_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<()> {
    let spec = viz::PlotSpec {
        series: series.to_vec(),
        ..viz::PlotSpec::new(title, x_label, y_label)
    };
    viz::line_plot(path, &spec).with_context(|| format!("plotting {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_take_the_nearest_rank() {
        let v = sorted(vec![4.0, 1.0, 3.0, 2.0]);
        assert_eq!(v, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(
            [0.0, 0.5, 0.95, 1.0].map(|p| quantile(&v, p)),
            [1.0, 3.0, 4.0, 4.0]
        );
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn report_writes_markdown_csv_and_figures() {
        let d = testsupport::fresh_temp_dir("xtask-report-test", "a");
        let mut r = Report::new(&d, "T").unwrap();
        r.heading(2, "Sec");
        r.table(&["a", "b"], &[vec!["1".into(), "2".into()]]);
        r.figure("p.svg", "cap");
        r.csv(
            "t.csv",
            &["x", "y,z"],
            &[vec!["1".into(), "say \"hi\"".into()]],
        )
        .unwrap();
        line_plot(
            &r.path("p.svg"),
            "t",
            "x",
            "y",
            &[Series::new(
                "s",
                vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)],
            )],
        )
        .unwrap();
        assert_eq!(r.png_twins().unwrap(), 1);
        assert!(d.join("p.png").is_file());
        let md = std::fs::read_to_string(r.finish().unwrap()).unwrap();
        assert!(
            md.starts_with("# T\n")
                && md.contains("## Sec")
                && md.contains("| 1 | 2 |")
                && md.contains("![cap](p.svg)")
        );
        let csv = std::fs::read_to_string(d.join("t.csv")).unwrap();
        assert_eq!(csv, "x,\"y,z\"\n1,\"say \"\"hi\"\"\"\n");
        let _ = std::fs::remove_dir_all(&d);
    }
}
