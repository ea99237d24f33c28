//! Project tasks, run as `cargo xtask <task>` (the alias lives in `.cargo/config.toml`): the
//! command line of the `experiments` crate, one subcommand per task.

use clap::Parser;
use experiments::{
    landmarks_eval, match_eval, recognition, robustness, scan_path, scan_study, section6,
    sphere_validate,
};

/// Experiments and evaluations of the bipolar workspace.
#[derive(Debug, Parser)]
#[command(name = "xtask")]
enum Task {
    /// The paper's section 3: the descriptor on a sphere against analytic curves.
    SphereValidate(sphere_validate::Args),
    /// The paper's sections 4-6 on the face set.
    Robustness(robustness::Args),
    /// Identification/verification benchmark on sampled faces.
    Recognition(recognition::Args),
    /// Landmark detection accuracy on sampled faces.
    LandmarksEval(landmarks_eval::Args),
    /// Face matching through the public API (enrol, identify, verify) on virtual scans of the
    /// benchmark's scanner and of another one, with the residual gate chosen on the first.
    MatchEval(match_eval::Args),
    /// The descriptor's stability on range scans: rescans, expressions, other persons.
    ScanStudy(scan_study::Args),
    /// Wall time of each step of the path of one range scan (read, clean, detect, describe).
    ScanPath(scan_path::Args),
    /// The paper's section 6: bipolar, single pole, facial curves and iso-curvature curves
    /// side by side.
    Section6(section6::Args),
}

fn main() -> anyhow::Result<()> {
    match Task::parse() {
        Task::SphereValidate(args) => sphere_validate::run(args),
        Task::Robustness(args) => robustness::run(args),
        Task::Recognition(args) => recognition::run(args),
        Task::LandmarksEval(args) => landmarks_eval::run(args),
        Task::MatchEval(args) => match_eval::run(args),
        Task::ScanStudy(args) => scan_study::run(args),
        Task::ScanPath(args) => scan_path::run(args),
        Task::Section6(args) => section6::run(args),
    }
}
