//! What the fit's tests share: the bundled scenes' kernels, fits with a small reference, the
//! presets at a cell count, and a run to the end.

use std::ops::ControlFlow;
use std::sync::Arc;

use flatland_geom::{Kernel, Scene};
use flatland_solve::Reference;

use crate::{Fit, FitParams, FitSummary, Preset};

pub(crate) const FIG3: &str = flatland_geom::bundled::SCENES[0].2;
pub(crate) const BOX: &str = flatland_geom::bundled::SCENES[1].2;
pub(crate) const MAZE: &str = flatland_geom::bundled::SCENES[2].2;

pub(crate) fn fig3() -> Arc<Kernel> {
    Arc::new(Kernel::new(Scene::from_ron_str(FIG3).unwrap()))
}

pub(crate) fn maze() -> Arc<Kernel> {
    Arc::new(Kernel::new(Scene::from_ron_str(MAZE).unwrap()))
}

/// A fit of `kernel` measured against a 64² grid and 2048 held-out points.
pub(crate) fn fit_with(kernel: &Arc<Kernel>, params: FitParams) -> Fit {
    let reference = Arc::new(Reference::new(kernel, 64, 2048, crate::REFERENCE_SEED));
    Fit::new(Arc::clone(kernel), reference, params).unwrap()
}

/// The paper's network at `cells` cells, without a learning curve.
pub(crate) fn paper(cells: usize) -> FitParams {
    preset(Preset::Paper, cells)
}

/// `preset` at `cells` cells, without a learning curve.
pub(crate) fn preset(preset: Preset, cells: usize) -> FitParams {
    FitParams {
        target_cells: cells,
        eval_every: 0,
        ..preset.params()
    }
}

/// Trains to a stop and finishes.
pub(crate) fn run(fit: &mut Fit) -> FitSummary {
    fit.run(1000, |_| ControlFlow::Continue(())).unwrap()
}
