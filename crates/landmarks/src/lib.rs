//! Curvature and automatic face landmarks.
//!
//! Not implemented yet (issue 6): this crate currently exports nothing.
