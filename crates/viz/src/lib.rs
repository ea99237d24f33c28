//! Pictures of results: mesh renders with curves and points, line plots, heatmaps and
//! histograms, written as SVG or PNG (chosen by the file extension). Pure Rust and
//! deterministic: the same input gives the same bytes.
//!
//! * [`render_svg`], [`render_png`], [`render_to_file`]: an orthographic view ([`View`]) of a
//!   [`Scene`] (mesh, optional vertex colours, [`Polyline`]s, [`Marker`]s). PNG comes from a
//!   z-buffered software rasteriser (Lambert shading, 2×2 supersampling); SVG draws the
//!   front-facing triangles back to front (painter's algorithm). Curves and points are drawn
//!   only where the surface does not hide them.
//! * [`colormap`]: viridis and per-value field colours.
//! * [`line_plot`], [`heatmap`], [`histogram`]: charts drawn with plotters' SVG backend; PNG
//!   versions rasterise that SVG with resvg using the system fonts. Without any system font
//!   the PNG is drawn without text (a warning is printed once); [`fonts_available`] tells.

pub mod colormap;
mod plot;
mod render;

pub use plot::{
    fonts_available, heatmap, heatmap_svg, histogram, histogram_svg, line_plot, line_plot_svg,
    svg_to_png, PlotSpec, Series,
};
pub use render::{
    encode_png, render_png, render_rgb, render_svg, Marker, Polyline, Scene, View, MAX_SIZE,
};

use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors of the picture functions.
#[derive(Debug, Error)]
pub enum VizError {
    /// Picture size is zero or larger than [`MAX_SIZE`].
    #[error("invalid picture size {width}x{height} (each side must be 1..={max})", max = MAX_SIZE)]
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// A view specification could not be understood.
    #[error("invalid view {0}")]
    InvalidView(String),
    /// The number of vertex colours differs from the number of mesh vertices.
    #[error("{got} vertex colours for a mesh of {expected} vertices")]
    VertexColorCount {
        /// Number of mesh vertices.
        expected: usize,
        /// Number of colours given.
        got: usize,
    },
    /// The output path has an extension other than `.svg` or `.png`.
    #[error("unsupported picture format for {0} (use .svg or .png)")]
    UnsupportedFormat(PathBuf),
    /// An operating-system failure on a file (the path and the OS error are kept).
    #[error(transparent)]
    Io(#[from] meshcore::FileError),
    /// PNG encoding failed.
    #[error("PNG encoding failed: {0}")]
    Png(String),
    /// The SVG could not be parsed for rasterisation.
    #[error("SVG rasterisation failed: {0}")]
    Svg(String),
    /// Drawing a chart failed.
    #[error("plot drawing failed: {0}")]
    Plot(String),
    /// A plot has nothing to draw (no series, or no finite values at all).
    #[error("nothing to plot: {0}")]
    NoData(String),
    /// A series has no points.
    #[error("series `{0}` is empty")]
    EmptySeries(String),
    /// Matrix rows do not match the labels.
    #[error("matrix shape mismatch: {0}")]
    MatrixShape(String),
    /// Another invalid argument.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// An option name that is none of the valid names (they are listed).
    #[error(transparent)]
    UnknownChoice(#[from] meshcore::UnknownChoice),
}

meshcore::choice! {
    /// Picture formats chosen from the file extension.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Format: "picture format", VizError {
        /// `.svg`
        Svg = "svg",
        /// `.png`
        Png = "png",
    }
}

impl Format {
    /// Format of a path by its (case-insensitive) extension.
    pub fn from_path(path: &Path) -> Result<Self, VizError> {
        path.extension()
            .and_then(|e| e.to_str())
            .and_then(|e| <Format as meshcore::Choice>::from_name(e).ok())
            .ok_or_else(|| VizError::UnsupportedFormat(path.to_path_buf()))
    }
}

pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), VizError> {
    Ok(meshcore::write_bytes(path, bytes)?)
}

/// Renders the scene to `path`, SVG or PNG by extension (validating size and vertex colours
/// in both cases).
pub fn render_to_file(
    path: impl AsRef<Path>,
    scene: &Scene,
    view: &View,
    width: u32,
    height: u32,
) -> Result<(), VizError> {
    let path = path.as_ref();
    match Format::from_path(path)? {
        Format::Svg => {
            // Same validation as PNG.
            render::validate_scene(scene, width, height)?;
            write_bytes(path, render_svg(scene, view, width, height).as_bytes())
        }
        Format::Png => write_bytes(path, &render_png(scene, view, width, height)?),
    }
}
