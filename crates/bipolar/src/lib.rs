//! The bipolar invariant descriptor.
//!
//! Not implemented yet (issue 4): this crate currently exports nothing.
