//! `flatland stress`: runs the adversarial suite of [`flatland_lab::stress`].

use anyhow::Result;

/// Arguments of `flatland stress`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The short suite CI runs (fewer scales and parameter values, a shorter soak).
    #[arg(long)]
    pub quick: bool,
    /// Run only the cases whose name contains this text.
    #[arg(long, value_name = "TEXT")]
    pub only: Option<String>,
    /// Steps of the soak (default 10⁷, or 5·10⁵ with --quick).
    #[arg(long, value_name = "N")]
    pub soak_steps: Option<u64>,
}

/// Runs `flatland stress`.
pub fn run(args: &Args) -> Result<()> {
    flatland_lab::stress::run(args.quick, args.soak_steps, args.only.clone())
}
