//! `bipolar matrix` (not implemented yet, issue 5).

/// Arguments of `bipolar matrix`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Remaining arguments (the command is not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    rest: Vec<String>,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::bail!(
        "`bipolar matrix` is not implemented yet (issue 5); arguments: {:?}",
        args.rest
    )
}
