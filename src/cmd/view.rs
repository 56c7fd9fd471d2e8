//! `flatland view`: the desktop viewer, or the headless fit when there is no display.

use std::path::PathBuf;

use anyhow::Result;

/// Arguments of `flatland view` (the default: none given).
#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// Scene file (.ron, .json, or an .svg drawing imported with default settings: docs/SVG.md);
    /// in the window also a scene the viewer offers by name (fig3, maze, floorplan, hall, or
    /// floorplan-N, hall-N: a generated scene of N edges). Default: the scene of the last
    /// session, else a generated floor plan of 300 edges.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Open paused instead of learning at once.
    #[arg(long)]
    pub paused: bool,
    /// The learner: `light` (the light-driven learner's rounds, the default), `visibility` (the
    /// visibility network) or `paper` (the paper's network). Default: the learner of the last
    /// session.
    #[arg(long, value_name = "NAME", value_parser = parse_learner)]
    pub learner: Option<flatland_viewer::Learner>,
    /// Target cell count of the fit.
    #[arg(long, value_name = "N")]
    pub cells: Option<usize>,
    /// Pace of growth in cells per second of training, or `max` (as fast as this machine can).
    #[arg(long, value_name = "CELLS_PER_S", value_parser = parse_growth)]
    pub growth: Option<f64>,
    /// Ignore the settings remembered from the last session (they are still saved on exit).
    #[arg(long)]
    pub fresh: bool,
    /// Print the frame rate, frame times and the learner's speed to stderr every two seconds.
    #[arg(long)]
    pub fps_log: bool,
    /// Folder for "Save view" and "Save model". Default: the current folder.
    #[arg(long, value_name = "DIR")]
    pub export_dir: Option<PathBuf>,
}

/// `max`, or a positive number of cells per second.
fn parse_growth(text: &str) -> Result<f64, String> {
    if text == "max" {
        return Ok(f64::INFINITY);
    }
    match text.parse::<f64>() {
        Ok(r) if r > 0.0 && r.is_finite() => Ok(r),
        _ => Err(format!(
            "expected `max` or cells per second > 0, got {text:?}"
        )),
    }
}

/// `light`, `visibility` or `paper`, as every command names a method ([`Method::parse`]).
///
/// [`Method::parse`]: flatland_methods::Method::parse
fn parse_learner(text: &str) -> Result<flatland_viewer::Learner, String> {
    flatland_viewer::Learner::parse(text).map_err(|e| e.to_string())
}

/// Runs `flatland view`: the viewer when a display is available; otherwise one line saying so,
/// then the headless fit of the same scene (the window's options do not apply to it).
pub fn run(args: &Args) -> Result<()> {
    if flatland_viewer::display_available() {
        return Ok(flatland_viewer::run_with(flatland_viewer::Options {
            scene: args.scene.clone(),
            paused: args.paused,
            learner: args.learner,
            target_cells: args.cells,
            growth: args.growth,
            fresh_settings: args.fresh,
            fps_log: args.fps_log,
            export_dir: args.export_dir.clone(),
        })?);
    }
    eprintln!("no display available (DISPLAY is not set): running the headless fit instead");
    let fit_args = super::fit::Args::for_scene(args.scene.clone());
    super::fit::run(&fit_args)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growth_is_max_or_a_positive_rate() {
        assert_eq!(parse_growth("max"), Ok(f64::INFINITY));
        assert_eq!(parse_growth("12.5"), Ok(12.5));
        for bad in ["0", "-3", "fast", "inf", "NaN"] {
            assert!(parse_growth(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_learner_is_named_as_every_command_names_its_method() {
        use flatland_viewer::Learner;
        assert_eq!(parse_learner("visibility"), Ok(Learner::Visibility));
        assert_eq!(parse_learner("paper"), Ok(Learner::Paper));
        assert_eq!(parse_learner("light"), Ok(Learner::Light));
        let err = parse_learner("theta").unwrap_err();
        assert!(err.contains("`visibility`"), "a retired name: {err}");
        let err = parse_learner("clustered").unwrap_err();
        assert!(err.contains("light, visibility or paper"), "{err}");
        let err = parse_learner("θ").unwrap_err();
        assert!(err.contains("light, visibility, paper"), "{err}");
    }
}
