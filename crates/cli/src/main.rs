//! `bipolar`: the command-line tool of the bipolar workspace.

use clap::{Parser, Subcommand};

mod choice;
mod cmd_clean;
mod cmd_convert;
mod cmd_curves;
mod cmd_describe;
mod cmd_distance;
mod cmd_geodesic;
mod cmd_info;
mod cmd_landmarks;
mod cmd_match;
mod cmd_matrix;
mod cmd_render;
mod cmd_scan;
mod load;
mod refpoint;
mod searchfiles;

/// Bipolar invariant representation of 3D surfaces: inspect meshes, compute geodesic fields and
/// descriptors, compare faces.
#[derive(Debug, Parser)]
#[command(name = "bipolar", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print statistics and checks of a mesh (counts, bbox, edges, components, defects).
    Info(cmd_info::Args),
    /// Convert a mesh between formats (chosen by file extension).
    Convert(cmd_convert::Args),
    /// Compute a geodesic distance field from a source vertex or point.
    Geodesic(cmd_geodesic::Args),
    /// Compute the bipolar descriptor of a mesh.
    Describe(cmd_describe::Args),
    /// Render a mesh with level curves and descriptor points (SVG, PNG or GLB).
    Render(cmd_render::Args),
    /// Normalised shape distance between two descriptor files.
    Distance(cmd_distance::Args),
    /// Pairwise distance matrix of descriptor files.
    Matrix(cmd_matrix::Args),
    /// Detect face landmarks (outer eye corners, nose tip).
    Landmarks(cmd_landmarks::Args),
    /// Scan a mesh with the virtual range scanner into a Bosphorus `.bnt` grid (mm).
    Scan(cmd_scan::Args),
    /// Prepare a scan: spikes, outliers, small holes, crop, smoothing, decimation; units.
    Clean(cmd_clean::Args),
    /// Curve representations of the paper's section 6: iso-curvature or facial curves (JSON).
    Curves(cmd_curves::Args),
    /// Distance between two curve files (elastic for facial curves, ICP for iso-curvature).
    CurveDistance(cmd_curves::DistanceArgs),
    /// Enrol scans into a gallery of face templates (one per scan; in parallel).
    Enroll(cmd_match::EnrollArgs),
    /// Rank a gallery's identities by their score against a probe scan or template.
    Identify(cmd_match::IdentifyArgs),
    /// Score two faces (scans or templates) and decide whether they are the same person.
    Verify(cmd_match::VerifyArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(a) => cmd_info::run(a),
        Command::Convert(a) => cmd_convert::run(a),
        Command::Geodesic(a) => cmd_geodesic::run(a),
        Command::Describe(a) => cmd_describe::run(a),
        Command::Render(a) => cmd_render::run(a),
        Command::Distance(a) => cmd_distance::run(a),
        Command::Matrix(a) => cmd_matrix::run(a),
        Command::Landmarks(a) => cmd_landmarks::run(a),
        Command::Scan(a) => cmd_scan::run(a),
        Command::Clean(a) => cmd_clean::run(a),
        Command::Curves(a) => cmd_curves::run(a),
        Command::CurveDistance(a) => cmd_curves::run_distance(a),
        Command::Enroll(a) => cmd_match::run_enroll(a),
        Command::Identify(a) => cmd_match::run_identify(a),
        Command::Verify(a) => cmd_match::run_verify(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
