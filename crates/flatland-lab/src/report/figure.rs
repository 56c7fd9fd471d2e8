//! The paper's Fig. 3 panels of a finished fit, shared by `flatland figure` and `flatland
//! results`: the learned ζ̃ evaluated on the reference's grid, drawn by
//! [`flatland_pictures::figure`].

use anyhow::Result;
use flatland_pictures::figure::{Figure, panels_png};
use flatland_pictures::plot::Overlay;
use flatland_solve::Reference;
use kernel_fit::Fit;

/// The five panels of a finished fit, as PNG bytes in
/// [`PANELS`](flatland_pictures::figure::PANELS) order.
pub fn panels(
    fit: &Fit,
    reference: &Reference,
    label: &str,
    log: bool,
) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let learned = reference.approximate_grid(fit.model());
    let cells: Vec<Option<[f64; 2]>> = fit.cell_st();
    let edges = fit.network().edges();
    Ok(panels_png(&Figure {
        scene: fit.kernel().scene(),
        label,
        log,
        res: reference.res(),
        exact: reference.grid(),
        learned: &learned,
        overlay: Overlay {
            cells: &cells,
            edges: &edges,
        },
    })?)
}
