//! flatland as a library: load a scene, learn its kernel, measure the error, save the model,
//! load it back and evaluate it (the README's "Use as a library").
//!
//! `cargo run --release --example library -- [SCENE.ron] [MODEL.json] [CELLS]`
//! (defaults: `scenes/fig3.ron`, `model.json`, 400). Built and run by `cargo test`.

use std::error::Error;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;

use flatland_geom::{Kernel, Scene};
use flatland_solve::{Reference, Representation};
use kernel_fit::{Fit, FitParams, FitSummary, ModelFile, REFERENCE_SEED};

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "scenes/fig3.ron".into());
    let out = args.next().unwrap_or_else(|| "model.json".into());
    let cells = args.next().map_or(Ok(400), |c| c.parse())?;
    let summary = learn(Path::new(&scene), Path::new(&out), cells)?;
    println!(
        "{cells} cells learned from {} rays in {:.2} s; relative L2 on the grid {:.3}, at \
         held-out points {:.3}; model saved to {out}",
        summary.rays, summary.wall_s, summary.errors.grid, summary.errors.heldout
    );
    Ok(())
}

/// Learns the kernel of the scene in `scene_file` with `cells` cells, saves the model to `out`,
/// loads it back and checks that the loaded model is the one learned.
fn learn(scene_file: &Path, out: &Path, cells: usize) -> Result<FitSummary, Box<dyn Error>> {
    // A scene: validated when loaded (a bad file is an error naming the file, line and edge).
    let scene = Scene::load(scene_file)?;
    // The exact kernel k(s, t) and the learning target ζ(s, t) = E'(sender) k(s, t).
    let kernel = Arc::new(Kernel::new(scene));

    // What errors are measured against: the exact ζ on a 256² grid and at held-out points that
    // training never sees (the seed the `flatland` tools use, so the numbers match theirs).
    let params = FitParams {
        target_cells: cells,
        ..FitParams::default()
    };
    let reference = Arc::new(Reference::new(&kernel, 256, params.heldout, REFERENCE_SEED));

    // Learn: the callback runs every 1000 steps and may stop the fit (ControlFlow::Break).
    let mut fit = Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params)?;
    let summary = fit.run(1000, |_| ControlFlow::Continue(()))?;

    // Save the model (scene fingerprint, parameters, network; written atomically) and load it
    // back: every field is validated on load.
    ModelFile::new(fit.model().clone(), params, Some(summary.clone())).save(out)?;
    let loaded = ModelFile::load(out)?;
    loaded.check_scene(kernel.scene(), scene_file)?;

    // Evaluate the learned ζ anywhere in [0, 1)²: s is the sender, t the receiver.
    let (s, t) = (0.2, 0.6);
    assert_eq!(loaded.model.zeta(s, t), fit.model().zeta(s, t));
    assert_eq!(reference.errors(&loaded.model), summary.errors);
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_example_learns_saves_and_reloads_a_model() {
        let dir = std::env::temp_dir().join(format!("flatland-example-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fig3.ron");
        let out = dir.join("model.json");
        let summary = learn(&scene, &out, 40).unwrap();
        assert_eq!(summary.cells, 40);
        assert!(summary.errors.heldout < 1.0, "{summary:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
