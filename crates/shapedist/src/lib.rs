//! Normalised shape distances between descriptors.
//!
//! Not implemented yet (issue 5): this crate currently exports nothing.
