//! Filled in by the geometry issue.

/// Arguments.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
