//! `bipolar info` (not implemented yet, issue 2).

/// Arguments of `bipolar info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Remaining arguments (the command is not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    rest: Vec<String>,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::bail!(
        "`bipolar info` is not implemented yet (issue 2); arguments: {:?}",
        args.rest
    )
}
