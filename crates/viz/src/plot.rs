//! Line plots, heatmaps and histograms (plotters SVG; PNG by rasterising the SVG with resvg).

use crate::{colormap, write_bytes, Format, VizError};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use resvg::{tiny_skia, usvg};
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// One named series of a line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points, drawn in the given order; non-finite points (and, on a log axis,
    /// non-positive y) are skipped.
    pub points: Vec<(f64, f64)>,
    /// Draw the line (and its legend entry) dashed instead of solid; markers are unchanged.
    pub dashed: bool,
}

impl Series {
    /// A solid series.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            dashed: false,
        }
    }

    /// Sets whether the line is dashed (builder style).
    pub fn dashed(mut self, dashed: bool) -> Self {
        self.dashed = dashed;
        self
    }
}

/// A line plot: several named series with markers and a legend.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotSpec {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The series.
    pub series: Vec<Series>,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Picture width in pixels (default 800).
    pub width: u32,
    /// Picture height in pixels (default 560).
    pub height: u32,
}

impl Default for PlotSpec {
    fn default() -> Self {
        Self {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            series: Vec::new(),
            log_y: false,
            width: 800,
            height: 560,
        }
    }
}

impl PlotSpec {
    /// An empty plot with a title and axis labels.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }

    /// Adds a solid series (builder style).
    pub fn with_series(mut self, name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        self.series.push(Series::new(name, points));
        self
    }

    /// Adds a series with its style (builder style).
    pub fn with(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// Sets the log-y flag (builder style).
    pub fn with_log_y(mut self, log_y: bool) -> Self {
        self.log_y = log_y;
        self
    }
}

/// Distinct series colours (Tableau 10).
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// Dash and gap lengths of dashed series, in pixels.
const DASH: i32 = 8;
const GAP: i32 = 5;

fn pick(i: usize) -> RGBColor {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    RGBColor(r, g, b)
}

fn perr<E: std::fmt::Display>(e: E) -> VizError {
    VizError::Plot(e.to_string())
}

/// Padded range of values (a degenerate range is widened).
/// Draws the grid, tick labels and axis descriptions in the style of every plot here.
fn draw_axes<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    x_label: &str,
    y_label: &str,
) -> Result<(), VizError>
where
    DB: DrawingBackend,
    X: Ranged + ValueFormatter<X::ValueType>,
    Y: Ranged + ValueFormatter<Y::ValueType>,
{
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(perr)
}

/// Draws the series legend (upper right) in the style of every plot here.
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), VizError> {
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(perr)
}

fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let (a, b) = if b - a < 1e-9 {
            (a - 0.5, b + 0.5)
        } else {
            (a, b)
        };
        let pad = 0.05 * (b - a);
        return (10f64.powf(a - pad), 10f64.powf(b + pad));
    }
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - d, hi + d);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

fn check_size(w: u32, h: u32) -> Result<(), VizError> {
    if w < 50 || h < 50 || w > crate::MAX_SIZE || h > crate::MAX_SIZE {
        return Err(VizError::InvalidSize {
            width: w,
            height: h,
        });
    }
    Ok(())
}

/// Draws a line plot as an SVG string.
pub fn line_plot_svg(spec: &PlotSpec) -> Result<String, VizError> {
    check_size(spec.width, spec.height)?;
    if spec.series.is_empty() {
        return Err(VizError::NoData(format!(
            "line plot `{}` has no series",
            spec.title
        )));
    }
    let mut clean: Vec<Vec<(f64, f64)>> = Vec::new();
    for s in &spec.series {
        if s.points.is_empty() {
            return Err(VizError::EmptySeries(s.name.clone()));
        }
        clean.push(
            s.points
                .iter()
                .copied()
                .filter(|(x, y)| x.is_finite() && y.is_finite() && (!spec.log_y || *y > 0.0))
                .collect(),
        );
    }
    let all: Vec<(f64, f64)> = clean.iter().flatten().copied().collect();
    if all.is_empty() {
        return Err(VizError::NoData(format!(
            "line plot `{}` has no finite{} values",
            spec.title,
            if spec.log_y { " positive" } else { "" }
        )));
    }
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in &all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x0, x1) = padded(x0, x1, false);
    let (y0, y1) = padded(y0, y1, spec.log_y);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (spec.width, spec.height)).into_drawing_area();
        root.fill(&WHITE).map_err(perr)?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(&spec.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(48)
            .y_label_area_size(72);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                draw_axes(&mut chart, &spec.x_label, &spec.y_label)?;
                for (i, (s, pts)) in spec.series.iter().zip(&clean).enumerate() {
                    let c = pick(i);
                    let style = c.stroke_width(2);
                    if s.dashed {
                        chart
                            .draw_series(DashedLineSeries::new(
                                pts.iter().copied(),
                                DASH,
                                GAP,
                                style,
                            ))
                            .map_err(perr)?
                            .label(s.name.as_str())
                            .legend(move |(x, y)| {
                                DashedPathElement::new(vec![(x, y), (x + 20, y)], 6, 3, style)
                            });
                    } else {
                        chart
                            .draw_series(LineSeries::new(pts.iter().copied(), style))
                            .map_err(perr)?
                            .label(s.name.as_str())
                            .legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 20, y)], style)
                            });
                    }
                    chart
                        .draw_series(pts.iter().map(|&(x, y)| Circle::new((x, y), 3, c.filled())))
                        .map_err(perr)?;
                }
                draw_legend(&mut chart)?;
            }};
        }
        if spec.log_y {
            body!(builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(perr)?);
        } else {
            body!(builder.build_cartesian_2d(x0..x1, y0..y1).map_err(perr)?);
        }
        root.present().map_err(perr)?;
    }
    Ok(buf)
}

/// Writes a line plot to `path` (SVG or PNG by extension). Errors: no series, an empty series,
/// no finite values, bad size, unsupported extension, I/O.
pub fn line_plot(path: impl AsRef<Path>, spec: &PlotSpec) -> Result<(), VizError> {
    let path = path.as_ref();
    let fmt = Format::from_path(path)?;
    let svg = line_plot_svg(spec)?;
    write_svg_as(path, fmt, &svg)
}

/// Compact number formatting for cell values and colour-bar ticks.
fn fmt_value(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e4).contains(&a) {
        format!("{v:.2e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

fn text_color(c: [u8; 3]) -> RGBColor {
    let lum = 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
    if lum < 120.0 {
        WHITE
    } else {
        BLACK
    }
}

/// Draws a square heatmap as an SVG string: `matrix[i][j]` in row `i`, column `j`, rows and
/// columns labelled by `labels`, a viridis colour bar titled `value_label`, values printed in
/// the cells when there are at most 15 rows. Non-finite cells are grey.
pub fn heatmap_svg(
    title: &str,
    labels: &[String],
    matrix: &[Vec<f64>],
    value_label: &str,
) -> Result<String, VizError> {
    let n = labels.len();
    if n == 0 {
        return Err(VizError::NoData(format!("heatmap `{title}` has no rows")));
    }
    if matrix.len() != n {
        return Err(VizError::MatrixShape(format!(
            "{} rows for {n} labels",
            matrix.len()
        )));
    }
    for (i, row) in matrix.iter().enumerate() {
        if row.len() != n {
            return Err(VizError::MatrixShape(format!(
                "row {i} has {} values, expected {n}",
                row.len()
            )));
        }
    }
    let flat: Vec<f64> = matrix.iter().flatten().copied().collect();
    let range = colormap::finite_range(&flat);
    let max_label = labels.iter().map(|l| l.chars().count()).max().unwrap_or(1) as u32;
    let label_px = (max_label * 8 + 12).clamp(30, 260);
    let cell = (640 / n as u32).clamp(12, 60);
    let grid = cell * n as u32;
    let (left, top) = (label_px + 10, 60u32);
    let bar_w = 24u32;
    let width = left + grid + 40 + bar_w + 90;
    let height = top + grid + label_px + 20;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(perr)?;
        draw_heatmap(
            &root,
            title,
            labels,
            matrix,
            value_label,
            range,
            (left, top, cell, bar_w),
        )?;
        root.present().map_err(perr)?;
    }
    Ok(buf)
}

fn draw_heatmap(
    root: &DrawingArea<SVGBackend, Shift>,
    title: &str,
    labels: &[String],
    matrix: &[Vec<f64>],
    value_label: &str,
    range: Option<(f64, f64)>,
    (left, top, cell, bar_w): (u32, u32, u32, u32),
) -> Result<(), VizError> {
    let n = labels.len() as i32;
    let (left, top, cell) = (left as i32, top as i32, cell as i32);
    let grid = cell * n;
    let (w, _) = root.dim_in_pixel();
    let title_style =
        TextStyle::from(("sans-serif", 22).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
    root.draw(&Text::new(
        title.to_string(),
        (w as i32 / 2, 12),
        title_style,
    ))
    .map_err(perr)?;
    let norm = |v: f64| -> [u8; 3] {
        match range {
            Some((lo, hi)) if v.is_finite() => {
                if hi > lo {
                    colormap::viridis((v - lo) / (hi - lo))
                } else {
                    colormap::viridis(0.5)
                }
            }
            _ => colormap::MISSING,
        }
    };
    let font_px = (cell as f64 * 0.28).clamp(8.0, 14.0);
    for (i, row) in matrix.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            let c = norm(v);
            let x = left + j as i32 * cell;
            let y = top + i as i32 * cell;
            root.draw(&Rectangle::new(
                [(x, y), (x + cell, y + cell)],
                RGBColor(c[0], c[1], c[2]).filled(),
            ))
            .map_err(perr)?;
            if n <= 15 {
                let tc = text_color(c);
                let style = TextStyle::from(("sans-serif", font_px).into_font())
                    .color(&tc)
                    .pos(Pos::new(HPos::Center, VPos::Center));
                root.draw(&Text::new(
                    fmt_value(v),
                    (x + cell / 2, y + cell / 2),
                    style,
                ))
                .map_err(perr)?;
            }
        }
    }
    root.draw(&Rectangle::new(
        [(left, top), (left + grid, top + grid)],
        BLACK.stroke_width(1),
    ))
    .map_err(perr)?;
    let lab_px = (cell as f64 * 0.45).clamp(9.0, 14.0);
    for (i, l) in labels.iter().enumerate() {
        let yc = top + i as i32 * cell + cell / 2;
        let style = TextStyle::from(("sans-serif", lab_px).into_font())
            .pos(Pos::new(HPos::Right, VPos::Center));
        root.draw(&Text::new(l.clone(), (left - 6, yc), style))
            .map_err(perr)?;
        let xc = left + i as i32 * cell + cell / 2;
        let style = TextStyle::from(
            ("sans-serif", lab_px)
                .into_font()
                .transform(FontTransform::Rotate270),
        )
        .pos(Pos::new(HPos::Right, VPos::Center));
        root.draw(&Text::new(l.clone(), (xc, top + grid + 6), style))
            .map_err(perr)?;
    }
    // Colour bar.
    let bx = left + grid + 40;
    let steps = 100;
    for k in 0..steps {
        let t = 1.0 - (k as f64 + 0.5) / steps as f64;
        let c = colormap::viridis(t);
        let y0 = top + (grid * k) / steps;
        let y1 = top + (grid * (k + 1)) / steps;
        root.draw(&Rectangle::new(
            [(bx, y0), (bx + bar_w as i32, y1.max(y0 + 1))],
            RGBColor(c[0], c[1], c[2]).filled(),
        ))
        .map_err(perr)?;
    }
    root.draw(&Rectangle::new(
        [(bx, top), (bx + bar_w as i32, top + grid)],
        BLACK.stroke_width(1),
    ))
    .map_err(perr)?;
    let tick =
        TextStyle::from(("sans-serif", 12).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    let (lo, hi) = range.unwrap_or((f64::NAN, f64::NAN));
    for (frac, v) in [(0.0, hi), (0.5, 0.5 * (lo + hi)), (1.0, lo)] {
        let y = top + (grid as f64 * frac) as i32;
        root.draw(&Text::new(
            fmt_value(v),
            (bx + bar_w as i32 + 5, y),
            tick.clone(),
        ))
        .map_err(perr)?;
    }
    let style = TextStyle::from(
        ("sans-serif", 14)
            .into_font()
            .transform(FontTransform::Rotate270),
    )
    .pos(Pos::new(HPos::Center, VPos::Top));
    root.draw(&Text::new(
        value_label.to_string(),
        (bx + bar_w as i32 + 58, top + grid / 2),
        style,
    ))
    .map_err(perr)?;
    Ok(())
}

/// Writes a heatmap to `path` (SVG or PNG by extension); see [`heatmap_svg`].
pub fn heatmap(
    path: impl AsRef<Path>,
    title: &str,
    labels: &[String],
    matrix: &[Vec<f64>],
    value_label: &str,
) -> Result<(), VizError> {
    let path = path.as_ref();
    let fmt = Format::from_path(path)?;
    let svg = heatmap_svg(title, labels, matrix, value_label)?;
    write_svg_as(path, fmt, &svg)
}

/// Draws overlaid histograms (common bins over the finite values of all series) as SVG.
pub fn histogram_svg(
    title: &str,
    x_label: &str,
    series: &[(String, Vec<f64>)],
    bins: usize,
) -> Result<String, VizError> {
    if bins == 0 || bins > 10_000 {
        return Err(VizError::InvalidArgument(format!(
            "histogram bins = {bins} (must be 1..=10000)"
        )));
    }
    if series.is_empty() {
        return Err(VizError::NoData(format!(
            "histogram `{title}` has no series"
        )));
    }
    for (name, v) in series {
        if v.is_empty() {
            return Err(VizError::EmptySeries(name.clone()));
        }
    }
    let all: Vec<f64> = series.iter().flat_map(|(_, v)| v.iter().copied()).collect();
    let Some((lo, hi)) = colormap::finite_range(&all) else {
        return Err(VizError::NoData(format!(
            "histogram `{title}` has no finite values"
        )));
    };
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        padded(lo, hi, false)
    };
    let bw = (hi - lo) / bins as f64;
    let counts: Vec<Vec<usize>> = series
        .iter()
        .map(|(_, v)| {
            let mut c = vec![0usize; bins];
            for &x in v.iter().filter(|x| x.is_finite()) {
                let b = (((x - lo) / bw).floor() as usize).min(bins - 1);
                c[b] += 1;
            }
            c
        })
        .collect();
    let cmax = counts.iter().flatten().copied().max().unwrap_or(0).max(1);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (800, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(perr)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(lo..hi, 0f64..cmax as f64 * 1.08)
            .map_err(perr)?;
        draw_axes(&mut chart, x_label, "count")?;
        let alpha = if series.len() > 1 { 0.45 } else { 0.75 };
        for (i, ((name, _), c)) in series.iter().zip(&counts).enumerate() {
            let col = pick(i);
            chart
                .draw_series(c.iter().enumerate().filter(|(_, &k)| k > 0).map(|(b, &k)| {
                    let x0 = lo + b as f64 * bw;
                    Rectangle::new([(x0, 0.0), (x0 + bw, k as f64)], col.mix(alpha).filled())
                }))
                .map_err(perr)?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 14, y + 5)], col.mix(alpha).filled())
                });
            chart
                .draw_series(c.iter().enumerate().filter(|(_, &k)| k > 0).map(|(b, &k)| {
                    let x0 = lo + b as f64 * bw;
                    Rectangle::new([(x0, 0.0), (x0 + bw, k as f64)], col.stroke_width(1))
                }))
                .map_err(perr)?;
        }
        draw_legend(&mut chart)?;
        root.present().map_err(perr)?;
    }
    Ok(buf)
}

/// Writes overlaid histograms to `path` (SVG or PNG by extension); see [`histogram_svg`].
/// Non-finite values are ignored; errors for no series, an empty series, no finite value,
/// `bins == 0`.
pub fn histogram(
    path: impl AsRef<Path>,
    title: &str,
    x_label: &str,
    series: &[(String, Vec<f64>)],
    bins: usize,
) -> Result<(), VizError> {
    let path = path.as_ref();
    let fmt = Format::from_path(path)?;
    let svg = histogram_svg(title, x_label, series, bins)?;
    write_svg_as(path, fmt, &svg)
}

fn write_svg_as(path: &Path, fmt: Format, svg: &str) -> Result<(), VizError> {
    match fmt {
        Format::Svg => write_bytes(path, svg.as_bytes()),
        Format::Png => write_bytes(path, &svg_to_png(svg)?),
    }
}

fn font_db() -> Arc<usvg::fontdb::Database> {
    static DB: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_system_fonts();
        let families: Vec<String> = db
            .faces()
            .flat_map(|f| f.families.iter().map(|(n, _)| n.clone()))
            .collect();
        for preferred in ["DejaVu Sans", "Liberation Sans", "Arial", "Noto Sans"] {
            if families.iter().any(|f| f == preferred) {
                db.set_sans_serif_family(preferred);
                break;
            }
        }
        if db.is_empty() {
            eprintln!("viz: no system fonts found; PNG plots are drawn without text");
        }
        Arc::new(db)
    })
    .clone()
}

/// Whether system fonts were found for the text of PNG plots.
pub fn fonts_available() -> bool {
    !font_db().is_empty()
}

/// Rasterises an SVG document (at its own size, on white) to PNG bytes with resvg. Text uses
/// the system fonts; without fonts the text is left out.
pub fn svg_to_png(svg: &str) -> Result<Vec<u8>, VizError> {
    let opts = usvg::Options {
        fontdb: font_db(),
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_str(svg, &opts).map_err(|e| VizError::Svg(e.to_string()))?;
    let size = tree.size().to_int_size();
    let (w, h) = (size.width(), size.height());
    let mut pixmap = tiny_skia::Pixmap::new(w, h).ok_or(VizError::InvalidSize {
        width: w,
        height: h,
    })?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::identity(),
        &mut pixmap.as_mut(),
    );
    // Opaque background, so the premultiplied data is plain RGB.
    let rgb: Vec<u8> = pixmap
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    crate::encode_png(&rgb, w, h)
}
