//! Checks shared by the geodesic integration tests (the meshes, fields and field comparisons
//! they share come from `testsupport`).

use geodesic::{GeodesicError, GeodesicSolver, SolveOptions, Source};

/// A cut-off distance of zero, below zero or NaN is an `InvalidCutoff` error of `solver`.
pub fn assert_rejects_bad_cutoffs(solver: &dyn GeodesicSolver) {
    for c in [0.0, -1.0, f64::NAN] {
        let o = SolveOptions {
            max_distance: Some(c),
        };
        let r = solver.distances(&[Source::Vertex(0)], &o);
        assert!(
            matches!(r, Err(GeodesicError::InvalidCutoff(_))),
            "{:?} cut-off {c}: {r:?}",
            solver.method()
        );
    }
}
