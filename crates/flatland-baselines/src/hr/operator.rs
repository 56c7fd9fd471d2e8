//! HR as a [`Representation`]: ζ̃ by tree descent, its bytes, and its transfer operator — its
//! own links, each a rectangle of constant `ζ̃ / E'(sender edge)` applied by gather and
//! push–pull ([`RectangleOperator`]).

use super::refine::Node;
use super::tree::HierarchicalRadiosity;
use flatland_solve::{
    KernelRectangle, Mesh, RectangleOperator, Representation, SolveError, SolveParams, Stop,
    TransferOperator, inverse_source_weights,
};
use std::mem::size_of;

/// Links never straddle an edge, so each link's sender edge divides it by one E'. Building the
/// operator is linear in the links (one binary search of the mesh each).
impl Representation for HierarchicalRadiosity {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        self.lookup(s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(self.stats.links)
    }

    /// Every table the approximation keeps: the tree nodes (about two per link: the leaves and
    /// the splits above them), the linked pairs and the surface edges' geometry.
    fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node>()
            + self.offsets.capacity() * size_of::<u32>()
            + self.pairs.capacity() * size_of::<(u32, u32)>()
            + self.surfaces.heap_bytes()
    }

    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        let inverse = inverse_source_weights(mesh)?;
        if stop() {
            return Err(SolveError::Interrupted);
        }
        let rectangles = self.links().into_iter().map(|link| {
            let sender = mesh.elements()[mesh.element_at(0.5 * (link.s[0] + link.s[1]))];
            KernelRectangle {
                s: link.s,
                t: link.t,
                k: link.value * inverse[sender.mesh_edge],
            }
        });
        Ok(Box::new(RectangleOperator::new(mesh, rectangles)))
    }
}

#[cfg(test)]
mod tests {
    use crate::test_support::blocker_kernel;
    use crate::{HierarchicalRadiosity, HrParams};
    use flatland_solve::Representation;

    #[test]
    fn bytes_grow_with_the_links_and_stay_a_few_dozen_per_link() {
        let kernel = blocker_kernel();
        let build = |f_eps| {
            let params = HrParams {
                f_eps,
                ..HrParams::default()
            };
            HierarchicalRadiosity::build(&kernel, &params, 1).unwrap()
        };
        let (coarse, fine) = (build(0.1), build(0.005));
        assert!(fine.stats().links > 10 * coarse.stats().links);
        assert!(fine.memory_bytes() > coarse.memory_bytes());
        // A leaf and the split above it per link, 16 bytes each.
        let per_link = fine.memory_bytes() as f64 / fine.stats().links as f64;
        assert!(
            (16.0..64.0).contains(&per_link),
            "{per_link} bytes per link"
        );
    }
}
