//! Mesh readers and writers.
//!
//! Not implemented yet (issue 2): this crate currently exports nothing.
