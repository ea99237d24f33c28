//! `bipolar describe` (not implemented yet, issue 4).

/// Arguments of `bipolar describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Remaining arguments (the command is not implemented yet).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    rest: Vec<String>,
}

/// Runs the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::bail!(
        "`bipolar describe` is not implemented yet (issue 4); arguments: {:?}",
        args.rest
    )
}
