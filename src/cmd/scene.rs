//! `flatland scene`: generate a realistic scene (a floor plan or a hall) of any size.

use std::path::PathBuf;

use flatland_geom::generate::{GenerateParams, SceneKind};
use flatland_lab::output;

/// Which scene to generate.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Rooms behind thick one-sided walls, doors, furniture and floor lamps.
    Floorplan,
    /// A large room full of solid boxes, lit by skylights.
    Hall,
}

/// Arguments of `flatland scene`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The kind of scene.
    #[arg(value_enum)]
    pub kind: Kind,
    /// About this many edges, in [24, 1 000 000] (the count lands within a fifth of it).
    #[arg(long, default_value_t = 300)]
    pub size: usize,
    /// Seed: the same kind, size and seed give the same scene.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output scene file, .json or .ron (by extension).
    #[arg(long)]
    pub out: PathBuf,
}

/// Generates the scene and writes it (atomically).
pub fn run(args: &Args) -> anyhow::Result<()> {
    output::file(&args.out, &[])?;
    let params = GenerateParams {
        kind: match args.kind {
            Kind::Floorplan => SceneKind::FloorPlan,
            Kind::Hall => SceneKind::Hall,
        },
        edges: args.size,
        seed: args.seed,
    };
    let scene = flatland_geom::generate::generate(&params)?;
    scene.save(&args.out)?;
    let edges = scene.edges();
    let emitters = edges.iter().filter(|e| e.emission > 0.0).count();
    let (lo, hi) = scene.bounds();
    println!(
        "wrote {}: {} edges ({emitters} emitting), {:.1} × {:.1} units",
        args.out.display(),
        edges.len(),
        hi.x - lo.x,
        hi.y - lo.y
    );
    Ok(())
}
