//! `bipolar geodesic` (not implemented yet, issue 3).

/// Arguments of `bipolar geodesic`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Remaining arguments (the command is not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    rest: Vec<String>,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::bail!(
        "`bipolar geodesic` is not implemented yet (issue 3); arguments: {:?}",
        args.rest
    )
}
