//! The experiments of the bipolar workspace, run as `cargo xtask <task>`: one module per task
//! (`sphere_validate`, `robustness`, `recognition`, `landmarks_eval`, `scan_study`, `scan_path`,
//! `section6`), each with its clap `Args` and a `run` function. They compose the libraries'
//! public APIs; the pieces several tasks share are the pipeline glue around `bipolar` and
//! `shapedist` (`pipeline`), the range-scan sets (`scans`), report writing (`report`) and the
//! default paths (`paths`). The curve representations of section 6 are `facecurves::nose`,
//! straightest geodesics `geodesic::straightest`, the single-pole descriptor `bipolar::polar`;
//! face-set loading, the face frame and the static-area mask are in the `facemodel` crate.

pub mod landmarks_eval;
pub mod match_eval;
pub mod recognition;
pub mod robustness;
pub mod scan_path;
pub mod scan_study;
pub mod section6;
pub mod sphere_validate;

/// A task's options parsed from `argv` (the task's name first, then its flags) as `cargo xtask
/// <task>` parses them; for tests and programs that run a task in-process. Bad arguments end
/// the process with clap's message.
pub fn parse_args<A: clap::Args>(argv: &[&str]) -> A {
    #[derive(clap::Parser)]
    struct Cli<A: clap::Args> {
        #[command(flatten)]
        args: A,
    }
    <Cli<A> as clap::Parser>::parse_from(argv).args
}

mod paths;
mod pipeline;
mod report;
mod scans;

/// Straightest geodesics: the library's walker (`geodesic::straightest`).
mod walk {
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
mod polar {
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
