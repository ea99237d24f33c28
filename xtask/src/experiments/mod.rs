//! Shared pieces of `cargo xtask robustness`, `recognition` and `section6`: the single-pole
//! descriptor, the curve representations of section 6 (`curves`), the pipeline glue around
//! `bipolar` and `shapedist`, and report writing. Straightest geodesics are
//! `geodesic::straightest`, the single-pole descriptor is `bipolar::polar`; face-set loading,
//! the face frame and the static-area mask are in the `facemodel` crate.

pub mod curves;
pub mod pipeline;
pub mod report;
pub mod scans;

/// Straightest geodesics: the library's walker (`geodesic::straightest`).
pub mod walk {
    pub use geodesic::straightest::Walker;

    #[cfg(test)]
    pub(crate) mod tests {
        use meshcore::TriMesh;

        /// The shared jittered unit plane ([`testsupport::jittered_unit_plane`]).
        pub(crate) fn plane(n: usize, jitter: f64, seed: u64) -> TriMesh {
            testsupport::jittered_unit_plane(n, jitter, seed)
        }
    }
}

/// The single-pole descriptor of `bipolar::polar`.
pub mod polar {
    use anyhow::Result;
    use bipolar::{BipolarError, PolarDescriptor};
    use geodesic::Walker;
    use meshcore::DVec3;

    pub use bipolar::PolarOptions;
    /// Where the pole is (a vertex or a surface point).
    pub use bipolar::Source as Pole;

    /// [`bipolar::describe_polar`]; a descriptor with no point (no ray reaches level 1) is the
    /// empty set, as the experiments count it.
    pub fn polar_descriptor(
        walker: &Walker<'_>,
        u: &[f64],
        pole: Pole,
        towards: DVec3,
        opts: &PolarOptions,
    ) -> Result<PolarDescriptor> {
        match bipolar::describe_polar(walker, u, pole, towards, opts) {
            Ok(d) => Ok(d),
            Err(BipolarError::NoIntersections(_)) => Ok(empty(opts)),
            Err(e) => Err(e.into()),
        }
    }

    /// The descriptor without points (counted as the empty set).
    pub fn empty(opts: &PolarOptions) -> PolarDescriptor {
        PolarDescriptor {
            points: Vec::new(),
            options: *opts,
        }
    }
}
