//! Isolines of piecewise-linear scalar fields on triangle meshes.
//!
//! Not implemented yet (issue 4): this crate currently exports nothing.
