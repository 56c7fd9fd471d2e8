//! Subcommands. Each module has `Args` (clap) and `run(&Args) -> anyhow::Result<()>`.

pub mod check;
pub mod kernel;

/// What `cargo run --release` does with no arguments.
pub fn default_job() -> anyhow::Result<()> {
    anyhow::bail!("no default job yet: try `flatland --help`")
}
