//! `flatland scene`: generate a realistic scene (a floor plan or a hall) of any size, or
//! convert an SVG drawing into a scene file once.

use std::path::PathBuf;

use anyhow::Context;
use flatland_geom::Scene;
use flatland_geom::generate::{GenerateParams, SceneKind};
use flatland_lab::output;

use super::SceneArgs;

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
    /// The kind of scene to generate (not with --from-svg).
    #[arg(
        value_enum,
        required_unless_present = "from_svg",
        conflicts_with = "from_svg"
    )]
    pub kind: Option<Kind>,
    /// About this many edges, in [24, 1 000 000] (the count lands within a fifth of it).
    #[arg(long, default_value_t = 300)]
    pub size: usize,
    /// Seed: the same kind, size and seed give the same scene.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Light it by point lights (a lamp in each room of a floor plan, lamps under a hall's
    /// ceiling) instead of emitting edges.
    #[arg(long)]
    pub lamps: bool,
    /// Convert this SVG drawing instead (docs/SVG.md), with --flatten and --unit.
    #[arg(long, value_name = "SVG")]
    pub from_svg: Option<PathBuf>,
    /// An SVG's curves become segments no farther than this from them, in drawing units.
    #[arg(long, value_name = "T", requires = "from_svg")]
    pub flatten: Option<f64>,
    /// Scene units per SVG drawing unit (0.001 reads a drawing in millimetres as metres).
    #[arg(long, value_name = "U", requires = "from_svg")]
    pub unit: Option<f64>,
    /// Output scene file, .json or .ron (by extension).
    #[arg(long)]
    pub out: PathBuf,
}

/// Generates or converts the scene and writes it (atomically).
pub fn run(args: &Args) -> anyhow::Result<()> {
    let inputs: Vec<&std::path::Path> = args.from_svg.iter().map(PathBuf::as_path).collect();
    output::file(&args.out, &inputs)?;
    let scene = match (&args.from_svg, args.kind) {
        (Some(svg), _) => {
            let drawing = SceneArgs {
                scene: Some(svg.clone()),
                flatten: args.flatten,
                unit: args.unit,
                subdivide: 1,
            };
            drawing.load()?.0
        }
        (None, Some(kind)) => generated(args, kind)?,
        (None, None) => anyhow::bail!("give a kind of scene (floorplan, hall) or --from-svg"),
    };
    scene.save(&args.out)?;
    let edges = scene.edges();
    let emitters = edges.iter().filter(|e| e.emission > 0.0).count();
    let lights = scene.lights().len();
    let (lo, hi) = scene.bounds();
    println!(
        "wrote {}: {} edges ({emitters} emitting), {lights} point lights, {:.1} × {:.1} units",
        args.out.display(),
        edges.len(),
        hi.x - lo.x,
        hi.y - lo.y
    );
    Ok(())
}

/// The generated scene `args` ask for.
fn generated(args: &Args, kind: Kind) -> anyhow::Result<Scene> {
    let params = GenerateParams {
        kind: match kind {
            Kind::Floorplan => SceneKind::FloorPlan,
            Kind::Hall => SceneKind::Hall,
        },
        edges: args.size,
        seed: args.seed,
    };
    let scene = match args.lamps {
        true => flatland_geom::generate::generate_lit(&params),
        false => flatland_geom::generate::generate(&params),
    };
    scene.context("generating the scene")
}
