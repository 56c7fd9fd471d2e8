//! Opens the viewer with every option on the command line (used by `scripts/screenshot.sh`):
//!
//! `cargo run --release -p flatland-viewer --example viewer -- [--scene FILE|NAME] [--paused]
//! [--learner light|visibility|paper] [--cells N] [--growth CELLS_PER_S|max] [--fresh]
//! [--fps-log] [--export-dir DIR]` (it learns at once unless `--paused`; FILE may be an SVG
//! drawing)

use std::path::PathBuf;

use flatland_viewer::Learner;

fn main() {
    let mut options = flatland_viewer::Options::default();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--scene" => options.scene = args.next().map(PathBuf::from),
            "--paused" => options.paused = true,
            // Learning at once is the default; kept so older command lines still work.
            "--play" => options.paused = false,
            "--learner" => match args.next().map(|name| Learner::parse(&name)) {
                Some(Ok(learner)) => options.learner = Some(learner),
                Some(Err(e)) => {
                    eprintln!("--learner: {e}");
                    std::process::exit(2);
                }
                None => {
                    eprintln!("--learner needs a value: light, visibility or paper");
                    std::process::exit(2);
                }
            },
            "--cells" => options.target_cells = args.next().and_then(|n| n.parse().ok()),
            "--growth" => {
                options.growth = args.next().and_then(|g| match g.as_str() {
                    "max" => Some(f64::INFINITY),
                    g => g.parse().ok().filter(|r: &f64| *r > 0.0),
                });
            }
            "--export-dir" => options.export_dir = args.next().map(PathBuf::from),
            "--fresh" => options.fresh_settings = true,
            "--fps-log" => options.fps_log = true,
            other => {
                eprintln!("unknown argument {other:?}");
                std::process::exit(2);
            }
        }
    }
    if !flatland_viewer::display_available() {
        eprintln!("no display (DISPLAY is not set): the viewer needs a window");
        std::process::exit(1);
    }
    if let Err(e) = flatland_viewer::run_with(options) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
