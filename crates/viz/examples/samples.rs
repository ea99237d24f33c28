//! Sample pictures and plots for inspection by eye (a line plot, a heatmap, a histogram, and
//! a sphere rendered with a field, curves and a point, as PNG and SVG):
//!
//! ```text
//! cargo run -p viz --example samples -- [out_dir]
//! ```
//!
//! `out_dir` defaults to `viz-samples` in the system's temporary folder; the files written are
//! listed on standard output.

use glam::DVec3;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use viz::{heatmap, histogram, line_plot, render_to_file, Marker, PlotSpec, Polyline, Scene, View};

fn main() {
    let out = std::env::args_os()
        .nth(1)
        .map_or_else(|| std::env::temp_dir().join("viz-samples"), PathBuf::from);
    if let Err(e) = std::fs::create_dir_all(&out) {
        panic!("creating {}: {e}", out.display());
    }
    for p in plots(&out).into_iter().chain(pictures(&out)) {
        println!("{}", p.display());
    }
}

/// A log-scale line plot, a 6 x 6 heatmap with one missing value and a two-series histogram.
fn plots(out: &Path) -> Vec<PathBuf> {
    let spec = PlotSpec::new("Shape distance vs levels", "levels N", "distance")
        .with_series(
            "method one",
            (1..=10).map(|i| (i as f64, 1.0 / i as f64)).collect(),
        )
        .with_series(
            "method two",
            (1..=10).map(|i| (i as f64, 0.5 / (i * i) as f64)).collect(),
        )
        .with_log_y(true);
    let line = out.join("viz-line.png");
    line_plot(&line, &spec).unwrap();

    let labels: Vec<String> = (0..6).map(|i| format!("face_{i:02}")).collect();
    let mut m: Vec<Vec<f64>> = (0..6)
        .map(|i| {
            (0..6)
                .map(|j| (i as f64 - j as f64).abs() * 0.125)
                .collect()
        })
        .collect();
    m[1][2] = f64::NAN;
    let heat = out.join("viz-heat.png");
    heatmap(&heat, "Distances", &labels, &m, "shape distance").unwrap();

    let a: Vec<f64> = (0..200).map(|i| ((i * 37) % 101) as f64 / 10.0).collect();
    let b: Vec<f64> = (0..100)
        .map(|i| 3.0 + ((i * 13) % 29) as f64 / 10.0)
        .collect();
    let hist = out.join("viz-hist.png");
    histogram(
        &hist,
        "Errors",
        "angle error (deg)",
        &[("first".into(), a), ("second".into(), b)],
        20,
    )
    .unwrap();
    vec![line, heat, hist]
}

/// A unit sphere coloured by `x + y` with three red latitude circles and a blue point, seen
/// obliquely: PNG, SVG, and the SVG rasterised.
fn pictures(out: &Path) -> Vec<PathBuf> {
    let mesh = testsupport::uv_sphere_y_up(1.0, 32, 64);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p.x + p.y).collect();
    let mut scene = Scene::new(&mesh).with_field(&field);
    for z in [-0.6, 0.0, 0.6] {
        let r = (1.0f64 - z * z).sqrt();
        scene.polylines.push(Polyline {
            points: (0..64)
                .map(|k| {
                    let a = TAU * k as f64 / 64.0;
                    DVec3::new(r * a.cos(), z, r * a.sin())
                })
                .collect(),
            closed: true,
            color: [220, 30, 30],
            width: 2.0,
        });
    }
    scene.points.push(Marker {
        position: DVec3::new(0.0, 0.0, 1.0),
        color: [30, 30, 220],
        radius: 5.0,
    });
    let view = View::new(DVec3::new(-0.3, -0.4, -1.0), DVec3::Y);
    let (png, svg, svg_png) = (
        out.join("viz-sphere.png"),
        out.join("viz-sphere.svg"),
        out.join("viz-sphere-svg.png"),
    );
    render_to_file(&png, &scene, &view, 400, 300).unwrap();
    render_to_file(&svg, &scene, &view, 400, 300).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    std::fs::write(&svg_png, viz::svg_to_png(&text).unwrap()).unwrap();
    vec![png, svg, svg_png]
}
