//! Pictures of results: mesh renders with curves and points, plots and heatmaps.
//!
//! Not implemented yet (issue 4): this crate currently exports nothing.
