//! `bipolar convert` (not implemented yet, issue 2).

/// Arguments of `bipolar convert`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Remaining arguments (the command is not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    rest: Vec<String>,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::bail!(
        "`bipolar convert` is not implemented yet (issue 2); arguments: {:?}",
        args.rest
    )
}
