//! What the oracle weighs a link's sender by: first its emission E' (the first shot, as HR),
//! then the radiosity the links so far solve for (Hanrahan's BF refinement), as its largest
//! value over the node, relative to the largest of all.

use super::clusters::{Hierarchy, Kind};
use super::solve::{ClusterOperator, Gather};
use flatland_geom::Kernel;
use flatland_solve::{Mesh, SolveError, SolveParams, Stop, TransferOperator, solve_operator};

/// The relative residual of the weighting solves: weights need two digits, not ten.
const WEIGHT_TOLERANCE: f64 = 1e-4;

/// Each node's sender weight in [0, 1]: the largest E' of its edges over the scene's largest.
pub(super) fn emission(h: &Hierarchy) -> Vec<f64> {
    let max = h.nodes.first().map_or(0.0, |n| n.max_weight);
    let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
    h.nodes.iter().map(|n| n.max_weight * scale).collect()
}

/// Each node's sender weight in [0, 1] from the radiosity `links` solve for on `mesh`: the
/// largest B of the mesh elements it overlaps, over the largest B of all.
pub(super) fn radiosity(
    h: &Hierarchy,
    links: Vec<Gather>,
    mesh: &Mesh,
    stop: &Stop,
) -> Result<Vec<f64>, SolveError> {
    let op = ClusterOperator::new(h, links, mesh);
    let params = SolveParams {
        tolerance: WEIGHT_TOLERANCE,
        ..SolveParams::default()
    };
    let b = solve_operator(&op, mesh, &params, stop)?.radiosity;
    let mut weight = vec![0.0_f64; h.nodes.len()];
    for (i, node) in h.nodes.iter().enumerate().rev() {
        weight[i] = match node.kind {
            Kind::Element(e) => {
                let (from, to) = (mesh.element_at(e.s0), mesh.element_at(e.s1.next_down()));
                b[from..=to.max(from)].iter().fold(0.0, |m, &v| m.max(v))
            }
            Kind::Cluster { .. } => {
                let c = node.first_child as usize;
                weight[c].max(weight[c + 1])
            }
        };
    }
    let max = weight.first().copied().unwrap_or(0.0);
    let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
    weight.iter_mut().for_each(|w| *w *= scale);
    debug_assert!(op.len() == mesh.len());
    Ok(weight)
}

/// The mesh the weighting solves run on: the scene's default element count.
pub(super) fn mesh(kernel: &Kernel) -> Result<Mesh, SolveError> {
    Mesh::new(kernel, Mesh::default_elements(kernel.scene()))
}
