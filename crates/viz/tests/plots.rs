//! Plot tests: well-formed SVG with the labels, valid PNG, errors.

use viz::{
    heatmap, heatmap_svg, histogram, histogram_svg, line_plot, line_plot_svg, PlotSpec, Series,
    VizError,
};

const PNG_SIG: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Minimal well-formedness check: balanced tags (ignoring self-closing ones and the XML
/// declaration), starts with `<svg` and ends with `</svg>`.
fn assert_well_formed(svg: &str) {
    let t = svg.trim();
    assert!(
        t.starts_with("<svg") || t.starts_with("<?xml"),
        "{}",
        &t[..40.min(t.len())]
    );
    assert!(t.ends_with("</svg>"));
    let mut stack: Vec<String> = Vec::new();
    let mut rest = t;
    while let Some(i) = rest.find('<') {
        let j = rest[i..].find('>').expect("unterminated tag") + i;
        let tag = &rest[i + 1..j];
        rest = &rest[j + 1..];
        if tag.starts_with('?') || tag.starts_with('!') || tag.ends_with('/') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "mismatched </{name}>"
            );
        } else {
            let name = tag.split_whitespace().next().unwrap().to_string();
            stack.push(name);
        }
    }
    assert!(stack.is_empty(), "unclosed {stack:?}");
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("viz-plots-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn png_dims(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], PNG_SIG);
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    (w, h)
}

fn spec() -> PlotSpec {
    PlotSpec::new("Shape distance vs levels", "levels N", "distance")
        .with_series(
            "method one",
            (1..=10).map(|i| (i as f64, 1.0 / i as f64)).collect(),
        )
        .with_series(
            "method two",
            (1..=10).map(|i| (i as f64, 0.5 / (i * i) as f64)).collect(),
        )
}

#[test]
fn line_plot_svg_has_labels_and_is_deterministic() {
    let s = spec();
    let a = line_plot_svg(&s).unwrap();
    assert_eq!(a, line_plot_svg(&s).unwrap());
    assert_well_formed(&a);
    for label in [
        "Shape distance vs levels",
        "levels N",
        "distance",
        "method one",
        "method two",
    ] {
        assert!(a.contains(label), "missing {label}");
    }
    // One marker per point.
    assert!(a.matches("<circle").count() >= 20);
    let log = line_plot_svg(&s.clone().with_log_y(true)).unwrap();
    assert_well_formed(&log);
    assert_ne!(a, log);
}

/// Number of line pieces an SVG draws (plotters writes a path as one `<polyline>` and each
/// dash of a dashed path as its own).
fn polylines(svg: &str) -> usize {
    svg.matches("<polyline").count() + svg.matches("<line").count()
}

#[test]
fn dashed_series_are_drawn_in_pieces_and_solid_ones_are_unchanged() {
    let pts: Vec<(f64, f64)> = (0..=20)
        .map(|i| (i as f64, (i as f64 / 3.0).sin()))
        .collect();
    let solid = PlotSpec::new("t", "x", "y").with_series("a", pts.clone());
    let same = PlotSpec::new("t", "x", "y").with(Series::new("a", pts.clone()).dashed(false));
    assert_eq!(solid, same);
    assert_eq!(
        line_plot_svg(&solid).unwrap(),
        line_plot_svg(&same).unwrap()
    );
    let dashed = PlotSpec::new("t", "x", "y").with(Series::new("a", pts.clone()).dashed(true));
    let (s, d) = (
        line_plot_svg(&solid).unwrap(),
        line_plot_svg(&dashed).unwrap(),
    );
    assert_well_formed(&d);
    assert_ne!(s, d);
    // A curve 20 units long across ~700 pixels: dozens of dashes instead of one polyline,
    // and the legend entry dashed too; the markers stay.
    assert!(
        polylines(&d) >= polylines(&s) + 20,
        "{} vs {}",
        polylines(&d),
        polylines(&s)
    );
    assert_eq!(d.matches("<circle").count(), s.matches("<circle").count());
    assert_eq!(d, line_plot_svg(&dashed).unwrap());
    // Mixed: a dashed and a solid series share the legend.
    let mixed = PlotSpec::new("t", "x", "y")
        .with_series("solid one", pts.clone())
        .with(Series::new("dashed one", pts).dashed(true));
    let m = line_plot_svg(&mixed).unwrap();
    assert!(m.contains("solid one") && m.contains("dashed one"));
}

#[test]
fn line_plot_files_svg_and_png() {
    let p = tmp("line.png");
    line_plot(&p, &spec()).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(png_dims(&bytes), (800, 560));
    let again = {
        line_plot(&p, &spec()).unwrap();
        std::fs::read(&p).unwrap()
    };
    assert_eq!(bytes, again);
    let p = tmp("line.svg");
    line_plot(&p, &spec()).unwrap();
    assert_well_formed(&std::fs::read_to_string(&p).unwrap());
    assert!(matches!(
        line_plot(tmp("line.gif"), &spec()),
        Err(VizError::UnsupportedFormat(_))
    ));
}

#[test]
fn line_plot_errors_and_non_finite() {
    assert!(matches!(
        line_plot_svg(&PlotSpec::new("t", "x", "y")),
        Err(VizError::NoData(_))
    ));
    let s = PlotSpec::new("t", "x", "y")
        .with_series("ok", vec![(0.0, 1.0)])
        .with_series("void", vec![]);
    assert!(matches!(line_plot_svg(&s), Err(VizError::EmptySeries(n)) if n == "void"));
    let s = PlotSpec::new("t", "x", "y")
        .with_series("nan", vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)]);
    assert!(matches!(line_plot_svg(&s), Err(VizError::NoData(_))));
    // Log axis with only non-positive values: nothing to draw.
    let s = PlotSpec::new("t", "x", "y")
        .with_series("neg", vec![(0.0, -1.0), (1.0, 0.0)])
        .with_log_y(true);
    assert!(matches!(line_plot_svg(&s), Err(VizError::NoData(_))));
    // Non-finite points are skipped, a single point and constant values are fine.
    let s = PlotSpec::new("t", "x", "y")
        .with_series("mixed", vec![(0.0, 1.0), (f64::NAN, 2.0), (1.0, 1.0)]);
    assert_well_formed(&line_plot_svg(&s).unwrap());
    let s = PlotSpec::new("t", "x", "y").with_series("one", vec![(3.0, 3.0)]);
    assert_well_formed(&line_plot_svg(&s).unwrap());
    let mut s = spec();
    s.width = 0;
    assert!(matches!(
        line_plot_svg(&s),
        Err(VizError::InvalidSize { .. })
    ));
}

fn labels(n: usize) -> Vec<String> {
    (0..n).map(|i| format!("face_{i:02}")).collect()
}

fn matrix(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| (i as f64 - j as f64).abs() * 0.125)
                .collect()
        })
        .collect()
}

#[test]
fn heatmap_small_prints_values_large_does_not() {
    let mut m = matrix(4);
    m[1][2] = f64::NAN;
    let svg = heatmap_svg("Distances", &labels(4), &m, "shape distance").unwrap();
    assert_well_formed(&svg);
    for l in [
        "Distances",
        "face_00",
        "face_03",
        "shape distance",
        "0.375",
        "n/a",
    ] {
        assert!(svg.contains(l), "missing {l}");
    }
    assert_eq!(
        svg,
        heatmap_svg("Distances", &labels(4), &m, "shape distance").unwrap()
    );
    let big = heatmap_svg("Big", &labels(20), &matrix(20), "d").unwrap();
    assert_well_formed(&big);
    assert!(big.contains("face_19"));
    assert!(
        !big.contains(">0.375<"),
        "values must not be printed for n > 15"
    );
    let p = tmp("heat.png");
    heatmap(&p, "Distances", &labels(4), &m, "shape distance").unwrap();
    png_dims(&std::fs::read(&p).unwrap());
}

#[test]
fn heatmap_errors() {
    assert!(matches!(
        heatmap_svg("t", &labels(3), &matrix(4), "v"),
        Err(VizError::MatrixShape(_))
    ));
    let mut m = matrix(3);
    m[2].pop();
    assert!(matches!(
        heatmap_svg("t", &labels(3), &m, "v"),
        Err(VizError::MatrixShape(_))
    ));
    assert!(matches!(
        heatmap_svg("t", &[], &[], "v"),
        Err(VizError::NoData(_))
    ));
    // All non-finite: drawn grey, not an error.
    let m = vec![vec![f64::NAN; 2]; 2];
    assert_well_formed(&heatmap_svg("t", &labels(2), &m, "v").unwrap());
}

#[test]
fn histogram_svg_png_and_errors() {
    let a: Vec<f64> = (0..200).map(|i| ((i * 37) % 101) as f64 / 10.0).collect();
    let b: Vec<f64> = (0..100)
        .map(|i| 3.0 + ((i * 13) % 29) as f64 / 10.0)
        .collect();
    let series = vec![("first".to_string(), a.clone()), ("second".to_string(), b)];
    let svg = histogram_svg("Errors", "angle error (deg)", &series, 20).unwrap();
    assert_well_formed(&svg);
    for l in ["Errors", "angle error (deg)", "first", "second", "count"] {
        assert!(svg.contains(l), "missing {l}");
    }
    let p = tmp("hist.png");
    histogram(&p, "Errors", "angle error (deg)", &series, 20).unwrap();
    png_dims(&std::fs::read(&p).unwrap());
    assert!(matches!(
        histogram_svg("t", "x", &series, 0),
        Err(VizError::InvalidArgument(_))
    ));
    assert!(matches!(
        histogram_svg("t", "x", &[], 5),
        Err(VizError::NoData(_))
    ));
    assert!(matches!(
        histogram_svg("t", "x", &[("e".into(), vec![])], 5),
        Err(VizError::EmptySeries(_))
    ));
    assert!(matches!(
        histogram_svg("t", "x", &[("e".into(), vec![f64::NAN])], 5),
        Err(VizError::NoData(_))
    ));
    // Constant data and non-finite values mixed in are fine.
    let svg = histogram_svg("t", "x", &[("c".into(), vec![2.0, 2.0, f64::NAN])], 5).unwrap();
    assert_well_formed(&svg);
}
