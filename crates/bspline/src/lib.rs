//! Least-squares cubic B-spline fitting of ordered polylines.
//!
//! Not implemented yet (issue 4): this crate currently exports nothing.
