//! Report folder writing: `report.md` (text, tables, embedded figures), CSV tables, and simple
//! SVG figures (line plots, heatmaps, orthographic mesh renders with curves and points).

use anyhow::{Context, Result};
use meshcore::{DVec3, TriMesh};
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

    /// Appends an embedded figure (file relative to the report folder).
    pub fn figure(&mut self, file: &str, caption: &str) {
        let _ = write!(self.md, "![{caption}]({file})\n\n*{caption}*\n\n");
    }

    /// Appends a Markdown table.
    pub fn table(&mut self, header: &[&str], rows: &[Vec<String>]) {
        let _ = writeln!(self.md, "| {} |", header.join(" | "));
        let _ = writeln!(self.md, "|{}|", vec!["---"; header.len()].join("|"));
        for r in rows {
            let _ = writeln!(self.md, "| {} |", r.join(" | "));
        }
        self.md.push('\n');
    }

    /// Writes a CSV file into the folder.
    pub fn csv(&self, name: &str, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
        write_csv(&self.path(name), header, rows)
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
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
    let esc = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut out = header.iter().map(|h| esc(h)).collect::<Vec<_>>().join(",");
    out.push('\n');
    for r in rows {
        out.push_str(&r.iter().map(|f| esc(f)).collect::<Vec<_>>().join(","));
        out.push('\n');
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}

/// Formats a number with 4 significant decimals.
pub fn f4(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.4}")
    } else {
        "n/a".into()
    }
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

const PALETTE: [&str; 10] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

/// One series of a line plot.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points (x, y); non-finite ones are skipped.
    pub points: Vec<(f64, f64)>,
    /// Dashed line.
    pub dashed: bool,
}

fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = (hi - lo).max(1e-12);
    let raw = span / n as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= n as f64)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + 1e-9 * step {
        out.push(t);
        t += step;
    }
    out
}

/// Writes an SVG line plot.
pub fn line_plot(
    path: &Path,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
) -> Result<()> {
    let (w, h) = (760.0, 460.0);
    let (l, r, t, b) = (70.0, 200.0, 40.0, 55.0);
    let pts = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, f64::NEG_INFINITY);
    for p in pts {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if !x0.is_finite() {
        (x0, x1, y1) = (0.0, 1.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    y1 += 0.05 * (y1 - y0);
    let sx = |x: f64| l + (x - x0) / (x1 - x0) * (w - l - r);
    let sy = |y: f64| h - b - (y - y0) / (y1 - y0) * (h - t - b);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"22\" font-size=\"15\" text-anchor=\"middle\">{}</text>",
        (w - r + l) / 2.0,
        xml(title)
    );
    for tx in nice_ticks(x0, x1, 8) {
        let _ = writeln!(s, "<line x1=\"{0:.1}\" y1=\"{1}\" x2=\"{0:.1}\" y2=\"{2}\" stroke=\"#ddd\"/><text x=\"{0:.1}\" y=\"{3}\" text-anchor=\"middle\">{4}</text>", sx(tx), t, h - b, h - b + 16.0, fmt_tick(tx));
    }
    for ty in nice_ticks(y0, y1, 6) {
        let _ = writeln!(s, "<line x1=\"{1}\" y1=\"{0:.1}\" x2=\"{2}\" y2=\"{0:.1}\" stroke=\"#ddd\"/><text x=\"{3}\" y=\"{4:.1}\" text-anchor=\"end\">{5}</text>", sy(ty), l, w - r, l - 6.0, sy(ty) + 4.0, fmt_tick(ty));
    }
    let _ = writeln!(
        s,
        "<rect x=\"{l}\" y=\"{t}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>",
        w - l - r,
        h - t - b
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
        (w - r + l) / 2.0,
        h - 12.0,
        xml(xlabel)
    );
    let _ = writeln!(
        s,
        "<text transform=\"translate(18,{}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
        (h - b + t) / 2.0,
        xml(ylabel)
    );
    for (k, se) in series.iter().enumerate() {
        let col = PALETTE[k % PALETTE.len()];
        let dash = if se.dashed {
            " stroke-dasharray=\"6,4\""
        } else {
            ""
        };
        let mut d = String::new();
        for p in se
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
        {
            let _ = write!(
                d,
                "{}{:.1},{:.1} ",
                if d.is_empty() { "M" } else { "L" },
                sx(p.0),
                sy(p.1)
            );
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"{col}\"/>",
                sx(p.0),
                sy(p.1)
            );
        }
        let _ = writeln!(
            s,
            "<path d=\"{d}\" fill=\"none\" stroke=\"{col}\" stroke-width=\"1.8\"{dash}/>"
        );
        let ly = t + 10.0 + 18.0 * k as f64;
        let _ = writeln!(s, "<line x1=\"{}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"{col}\" stroke-width=\"2\"{dash}/><text x=\"{}\" y=\"{}\">{}</text>", w - r + 10.0, w - r + 34.0, w - r + 40.0, ly + 4.0, xml(&se.label));
    }
    s.push_str("</svg>\n");
    std::fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

fn fmt_tick(v: f64) -> String {
    if v.abs() >= 100.0 || v == v.round() {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.1}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').to_string()
    }
}

#[allow(clippy::needless_range_loop)]
/// Writes an SVG heatmap of a square matrix with row/column labels and values in the cells.
pub fn heatmap(
    path: &Path,
    title: &str,
    labels: &[String],
    m: &[Vec<f64>],
    value_label: &str,
) -> Result<()> {
    let n = labels.len();
    let cell = 44.0;
    let (l, t) = (130.0, 130.0);
    let w = l + cell * n as f64 + 110.0;
    let h = t + cell * n as f64 + 30.0;
    let vmax = m
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let mut s = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"20\" font-size=\"14\" text-anchor=\"middle\">{}</text>",
        w / 2.0,
        xml(title)
    );
    for i in 0..n {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            l - 5.0,
            t + cell * (i as f64 + 0.6),
            xml(&labels[i])
        );
        let _ = writeln!(
            s,
            "<text transform=\"translate({:.1},{}) rotate(-60)\">{}</text>",
            l + cell * (i as f64 + 0.5),
            t - 5.0,
            xml(&labels[i])
        );
        for j in 0..n {
            let v = m[i][j];
            let col = if v.is_finite() {
                colormap(v / vmax)
            } else {
                "#cccccc".into()
            };
            let _ = writeln!(s, "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{cell}\" height=\"{cell}\" fill=\"{col}\" stroke=\"white\"/>", l + cell * j as f64, t + cell * i as f64);
            let txt = if v.is_finite() {
                format!("{v:.3}")
            } else {
                "-".into()
            };
            let fg = if v / vmax > 0.6 { "white" } else { "black" };
            let _ = writeln!(s, "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"9\" fill=\"{fg}\">{txt}</text>", l + cell * (j as f64 + 0.5), t + cell * (i as f64 + 0.6));
        }
    }
    let bx = l + cell * n as f64 + 20.0;
    for k in 0..50 {
        let f = 1.0 - k as f64 / 49.0;
        let _ = writeln!(
            s,
            "<rect x=\"{bx}\" y=\"{:.1}\" width=\"16\" height=\"{:.1}\" fill=\"{}\"/>",
            t + k as f64 * cell * n as f64 / 50.0,
            cell * n as f64 / 50.0 + 0.5,
            colormap(f)
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\">{vmax:.3}</text><text x=\"{}\" y=\"{}\">0</text>",
        bx + 20.0,
        t + 8.0,
        bx + 20.0,
        t + cell * n as f64
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" >{}</text>",
        bx - 10.0,
        t - 10.0,
        xml(value_label)
    );
    s.push_str("</svg>\n");
    std::fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

/// Viridis-like colour for `f` in [0, 1].
pub fn colormap(f: f64) -> String {
    let stops = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let f = f.clamp(0.0, 1.0) * 4.0;
    let i = (f.floor() as usize).min(3);
    let u = f - i as f64;
    let (a, b) = (stops[i], stops[i + 1]);
    format!(
        "#{:02x}{:02x}{:02x}",
        (a.0 + u * (b.0 - a.0)) as u8,
        (a.1 + u * (b.1 - a.1)) as u8,
        (a.2 + u * (b.2 - a.2)) as u8
    )
}

/// Things drawn over a mesh render.
#[derive(Debug, Clone, Default)]
pub struct Overlay {
    /// Segment groups with a colour each.
    pub segments: Vec<(String, Vec<[DVec3; 2]>)>,
    /// Point groups with a colour and radius each.
    pub points: Vec<(String, f64, Vec<DVec3>)>,
    /// Per-vertex highlight (faces whose vertices are all marked are tinted).
    pub highlight: Option<Vec<bool>>,
}

/// Orthographic front render (view along -`forward`, `up` up) of a shaded mesh with overlays,
/// painter's algorithm, written as SVG.
pub fn render(
    path: &Path,
    title: &str,
    mesh: &TriMesh,
    up: DVec3,
    forward: DVec3,
    ov: &Overlay,
) -> Result<()> {
    let right = up.cross(forward).normalize_or_zero();
    let up = forward.cross(right).normalize_or_zero();
    let proj = |p: DVec3| (p.dot(right), p.dot(up), p.dot(forward));
    let pos = mesh.positions();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pos {
        let (x, y, _) = proj(*p);
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let w = 560.0;
    let scale = (w - 40.0) / (x1 - x0).max(1e-12);
    let h = (y1 - y0) * scale + 70.0;
    let sx = |x: f64| 20.0 + (x - x0) * scale;
    let sy = |y: f64| 50.0 + (y1 - y) * scale;
    let light = (forward * 0.8 + up * 0.4 - right * 0.3).normalize();
    let mut order: Vec<(f64, u32)> = (0..mesh.n_faces() as u32)
        .map(|f| {
            let [a, b, c] = mesh.face_corners(f);
            ((a + b + c).dot(forward), f)
        })
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut s = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h:.0}\" font-family=\"sans-serif\" font-size=\"13\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"24\" text-anchor=\"middle\">{}</text>",
        w / 2.0,
        xml(title)
    );
    for (_, f) in order {
        let n = mesh.face_normal(f);
        if n.dot(forward) <= 0.0 {
            continue;
        }
        let shade = 0.25 + 0.75 * n.dot(light).max(0.0);
        let t = mesh.triangles()[f as usize];
        let hl = ov
            .highlight
            .as_ref()
            .is_some_and(|m| t.iter().all(|&v| m[v as usize]));
        let (r, g, b) = if hl {
            (170.0, 200.0, 255.0)
        } else {
            (225.0, 215.0, 205.0)
        };
        let col = format!(
            "#{:02x}{:02x}{:02x}",
            (r * shade) as u8,
            (g * shade) as u8,
            (b * shade) as u8
        );
        let [a, b2, c] = mesh.face_corners(f);
        let (pa, pb, pc) = (proj(a), proj(b2), proj(c));
        let _ = writeln!(s, "<polygon points=\"{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}\" fill=\"{col}\" stroke=\"{col}\" stroke-width=\"0.4\"/>", sx(pa.0), sy(pa.1), sx(pb.0), sy(pb.1), sx(pc.0), sy(pc.1));
    }
    for (col, segs) in &ov.segments {
        let mut d = String::new();
        for sg in segs {
            let (a, b) = (proj(sg[0]), proj(sg[1]));
            let _ = write!(
                d,
                "M{:.1},{:.1}L{:.1},{:.1}",
                sx(a.0),
                sy(a.1),
                sx(b.0),
                sy(b.1)
            );
        }
        let _ = writeln!(
            s,
            "<path d=\"{d}\" stroke=\"{col}\" stroke-width=\"1.1\" fill=\"none\"/>"
        );
    }
    for (col, rad, pts) in &ov.points {
        for p in pts {
            let (x, y, _) = proj(*p);
            let _ = writeln!(s, "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{rad}\" fill=\"{col}\" stroke=\"black\" stroke-width=\"0.3\"/>", sx(x), sy(y));
        }
    }
    s.push_str("</svg>\n");
    std::fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::walk::tests::plane;

    fn tmp(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("xtask-report-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn report_writes_markdown_csv_and_figures() {
        let d = tmp("a");
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
            &[Series {
                label: "s".into(),
                points: vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)],
                dashed: false,
            }],
        )
        .unwrap();
        heatmap(
            &r.path("h.svg"),
            "h",
            &["a".into(), "b".into()],
            &[vec![0.0, 0.5], vec![0.5, f64::NAN]],
            "d",
        )
        .unwrap();
        let m = plane(4, 0.0, 0);
        render(
            &r.path("r.svg"),
            "r",
            &m,
            DVec3::Y,
            DVec3::Z,
            &Overlay {
                points: vec![("red".into(), 3.0, vec![DVec3::new(0.5, 0.5, 0.0)])],
                ..Default::default()
            },
        )
        .unwrap();
        let md = std::fs::read_to_string(r.finish().unwrap()).unwrap();
        assert!(
            md.starts_with("# T\n")
                && md.contains("## Sec")
                && md.contains("| 1 | 2 |")
                && md.contains("![cap](p.svg)")
        );
        let csv = std::fs::read_to_string(d.join("t.csv")).unwrap();
        assert_eq!(csv, "x,\"y,z\"\n1,\"say \"\"hi\"\"\"\n");
        let svg = std::fs::read_to_string(d.join("p.svg")).unwrap();
        // The NaN point is skipped: two markers.
        assert_eq!(svg.matches("<circle").count(), 2);
        let svg = std::fs::read_to_string(d.join("r.svg")).unwrap();
        assert_eq!(svg.matches("<polygon").count(), 32);
        assert_eq!(svg.matches("<circle").count(), 1);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn ticks_and_colours() {
        assert_eq!(
            nice_ticks(0.0, 1.0, 5),
            vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
        );
        assert_eq!(colormap(0.0), "#440154");
        assert_eq!(colormap(1.0), "#fde725");
    }
}
