//! The `flatland` command line: one module per subcommand in `src/cmd/`.

use anyhow::Result;
use clap::{Parser, Subcommand};

mod cmd;

use flatland_lab::interrupt;

/// Light 2D scenes with all their bounces, and learn the light transport with supervised growing
/// cell structures (after Bohn 1996).
#[derive(Parser)]
#[command(name = "flatland", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a scene file and print a summary.
    Check(cmd::check::Args),
    /// List every numeric learner parameter: name, symbol, valid range, defaults, meaning.
    Params,
    /// Evaluate the exact kernel k(s,t) (or zeta with --weighted) on an RxR grid, to CSV or PNG.
    Kernel(cmd::kernel::Args),
    /// Learn a scene's kernel with an SGCS network; print the figures, optionally save the model.
    Fit(cmd::fit::Args),
    /// Evaluate a saved model on a grid (CSV or PNG) and report its errors.
    Eval(cmd::eval::Args),
    /// The desktop viewer: watch the cells grow over the (s, t) kernel plot.
    View(cmd::view::Args),
    /// Regenerate RESULTS.md and its plots: every experiment, measured.
    Results(cmd::results::Args),
    /// The paper's Fig. 3 panels as PNGs: geometry, kernel, cells, approximation, error.
    Figure(cmd::figure::Args),
    /// Every method at equal time on one scene (error against time, bytes, basis functions), or
    /// cost against scene size (--scaling).
    Bench(cmd::bench::Args),
    /// Light the scene: solve the radiosity equation with a kernel (exact, learned, HR, uniform)
    /// and compare the solved B with the exact kernel's.
    Solve(cmd::solve::Args),
    /// Relight one scene again and again: a light at many positions (given, from a file, or a
    /// walk through the rooms), the exact operator built once and re-solved per move.
    Relight(cmd::relight::Args),
    /// Generate a realistic scene of any size: a floor plan or a hall.
    Scene(cmd::scene::Args),
    /// Run the adversarial stability suite (scaling, extreme scenes and parameters, soak).
    Stress(cmd::stress::Args),
}

/// Counts the heap's peak for the memory figures of `bench --scaling` (a few atomic adds per
/// allocation: no measurable cost).
#[global_allocator]
static ALLOCATOR: &peakmem_alloc::PeakMemAlloc<std::alloc::System> =
    &peakmem_alloc::INSTRUMENTED_SYSTEM;

fn main() {
    let cli = Cli::parse();
    interrupt::install();
    let result: Result<()> = match cli.command {
        Some(Command::Check(args)) => cmd::check::run(&args),
        Some(Command::Params) => {
            print!("{}", kernel_fit::parameter_table());
            Ok(())
        }
        Some(Command::Kernel(args)) => cmd::kernel::run(&args),
        Some(Command::Fit(args)) => cmd::fit::run(&args),
        Some(Command::Eval(args)) => cmd::eval::run(&args),
        Some(Command::Stress(args)) => cmd::stress::run(&args),
        Some(Command::Solve(args)) => cmd::solve::run(&args),
        Some(Command::Relight(args)) => cmd::relight::run(&args),
        Some(Command::Scene(args)) => cmd::scene::run(&args),
        Some(Command::Bench(args)) => cmd::bench::run(&args),
        Some(Command::Figure(args)) => cmd::figure::run(&args),
        Some(Command::Results(args)) => cmd::results::run(&args),
        Some(Command::View(args)) => cmd::view::run(&args),
        None => cmd::default_job(),
    };
    if let Err(err) = result {
        // Ctrl-C: what was kept, and the shell's code for an interrupted command.
        if let Some(stopped) = err
            .chain()
            .find_map(|e| e.downcast_ref::<interrupt::Interrupted>())
        {
            eprintln!("{stopped}");
            std::process::exit(interrupt::EXIT_CODE);
        }
        // One line, the whole cause chain, no backtrace.
        let chain: Vec<String> = err.chain().map(|c| c.to_string()).collect();
        eprintln!("error: {}", chain.join(": "));
        std::process::exit(1);
    }
}
