//! Shared pieces of `cargo xtask robustness` and `cargo xtask recognition`: the single-pole
//! point set, the pipeline glue around `bipolar` and `shapedist`, and report writing. Straightest geodesics are
//! `geodesic::straightest`, the single-pole descriptor is `bipolar::polar`; face-set loading,
//! the face frame and the static-area mask are in the `facemodel` crate.

pub mod keyed;
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

/// The single-pole descriptor of `bipolar::polar`, as the experiments' keyed point sets.
pub mod polar {
    use super::keyed::KeyedPoints;
    use anyhow::Result;
    use bipolar::{BipolarError, PolarKey};
    use geodesic::Walker;
    use meshcore::DVec3;

    pub use bipolar::PolarOptions;
    /// Where the pole is (a vertex or a surface point).
    pub use bipolar::Source as Pole;

    /// `(level, sector)` of a packed polar key.
    pub fn polar_key_parts(k: u64) -> (u32, u32) {
        let k = PolarKey::unpack(k);
        (k.level, k.sector)
    }

    /// [`bipolar::describe_polar`] as keyed points; a descriptor with no point (no ray reaches
    /// level 1) is the empty set, as the experiments count it.
    pub fn polar_descriptor(
        walker: &Walker<'_>,
        u: &[f64],
        pole: Pole,
        towards: DVec3,
        opts: &PolarOptions,
    ) -> Result<KeyedPoints> {
        match bipolar::describe_polar(walker, u, pole, towards, opts) {
            Ok(d) => Ok(KeyedPoints::from_pairs(
                d.points
                    .iter()
                    .map(|p| (p.key.pack(), p.position))
                    .collect(),
                0.0,
            )),
            Err(BipolarError::NoIntersections(_)) => Ok(KeyedPoints::default()),
            Err(e) => Err(e.into()),
        }
    }
}
