//! The built approximation and its [`Representation`]: links by receiver node, ζ̃ by a walk
//! up the receiver's ancestors, its bytes, and its matrix-free operator.

use super::ClusteredParams;
use super::clusters::{Hierarchy, Kind, NONE};
use super::refine::refine;
use super::solve::{ClusterOperator, Gather};
use crate::BaselineError;
use flatland_geom::{EdgeId, Kernel};
use flatland_solve::{
    Mesh, Representation, SolveError, SolveParams, Stop, TransferOperator, check_fingerprint,
};
use std::mem::size_of;

/// What one build did.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClusteredStats {
    /// Final links: the basis functions.
    pub links: usize,
    /// Of those, links with a cluster of several edges at one end at least.
    pub cluster_links: usize,
    /// Of those, links whose every ray was blocked or that geometry hides (value 0).
    pub zero_links: usize,
    /// Links made on the way, including those refined away (each cast its rays).
    pub links_made: usize,
    /// Nodes: clusters and elements.
    pub nodes: usize,
    /// Rays cast.
    pub rays: u64,
    /// The oracle value the budget stopped at: the largest of the links kept that could still
    /// be split (0 when none could).
    pub f_eps: f64,
    /// Whether nothing was left to split: every link at the minimum length, or certain.
    pub finest: bool,
}

/// One final link, as exported for checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusteredLink {
    /// The sender node's surface edges (indices into `Scene::edges`), or the one edge of an
    /// element with its s-interval.
    pub sender: LinkEnd,
    /// The receiver node, likewise.
    pub receiver: LinkEnd,
    /// The mean of `G · V` over the two ends (ζ̃ = E' · ρ · value).
    pub value: f64,
}

/// One end of a link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinkEnd {
    /// A cluster: this many whole surface edges.
    Cluster {
        /// Edges in it.
        edges: usize,
    },
    /// An interval of one surface edge.
    Element {
        /// The edge.
        edge: EdgeId,
        /// Its parameter interval `[s0, s1)`.
        s: [f64; 2],
    },
}

/// Hierarchical radiosity with clustering: a tree of clusters and elements, and the links
/// between its nodes.
#[derive(Clone, Debug)]
pub struct ClusteredRadiosity {
    h: Hierarchy,
    /// `links[offsets[q]..offsets[q + 1]]` are receiver node q's links.
    offsets: Vec<u32>,
    links: Vec<Gather>,
    fingerprint: u64,
    stats: ClusteredStats,
}

impl ClusteredRadiosity {
    /// Refines from the root cluster's link with itself to `budget` links (fewer only when
    /// nothing is left to split), casting `rays_per_link` rays for every link made.
    /// Deterministic: each link's rays come from its own seed stream.
    pub fn build(
        kernel: &Kernel,
        budget: usize,
        params: &ClusteredParams,
        seed: u64,
    ) -> Result<ClusteredRadiosity, BaselineError> {
        params.check()?;
        params.check_budget(budget)?;
        let mut h = Hierarchy::new(kernel, params.min_length);
        let refined = refine(kernel, &mut h, budget, params, seed)?;
        let mut links: Vec<Gather> = refined
            .links
            .iter()
            .filter(|l| l.alive)
            .map(|l| Gather {
                p: l.p,
                q: l.q,
                g: l.g,
            })
            .collect();
        links.sort_by_key(|l| (l.q, l.p));
        let mut offsets = vec![0u32; h.nodes.len() + 1];
        for l in &links {
            offsets[l.q as usize + 1] += 1;
        }
        for k in 1..offsets.len() {
            offsets[k] += offsets[k - 1];
        }
        h.nodes.shrink_to_fit();
        let is_cluster = |i: u32| matches!(h.nodes[i as usize].kind, Kind::Cluster { .. });
        let stats = ClusteredStats {
            links: links.len(),
            cluster_links: links
                .iter()
                .filter(|l| is_cluster(l.p) || is_cluster(l.q))
                .count(),
            zero_links: links.iter().filter(|l| l.g == 0.0).count(),
            links_made: refined.links.len(),
            nodes: h.nodes.len(),
            rays: refined.rays,
            f_eps: refined.f_eps,
            finest: refined.finest,
        };
        Ok(ClusteredRadiosity {
            h,
            offsets,
            links,
            fingerprint: kernel.scene().fingerprint(),
            stats,
        })
    }

    /// What the build did.
    pub fn stats(&self) -> &ClusteredStats {
        &self.stats
    }

    /// Every final link (for checks).
    pub fn links(&self) -> Vec<ClusteredLink> {
        let end = |i: u32| match self.h.nodes[i as usize].kind {
            Kind::Cluster { lo, hi } => LinkEnd::Cluster {
                edges: (hi - lo) as usize,
            },
            Kind::Element(e) => LinkEnd::Element {
                edge: EdgeId::new(self.h.surfaces.edge[e.ord]),
                s: [e.s0, e.s1],
            },
        };
        self.links
            .iter()
            .map(|l| ClusteredLink {
                sender: end(l.p),
                receiver: end(l.q),
                value: l.g,
            })
            .collect()
    }

    /// ζ̃(s, t): from the deepest node holding t up to the root, the receiver's links are
    /// searched for the one whose sender holds s (the links partition the pairs that interact).
    fn lookup(&self, s: f64, t: f64) -> f64 {
        let h = &self.h;
        let (Some(os), Some(ot)) = (h.surfaces.locate(s), h.surfaces.locate(t)) else {
            return 0.0;
        };
        let mut node = h.edge_node[ot];
        while h.nodes[node as usize].first_child != NONE {
            let [a, b] = [0, 1].map(|k| h.nodes[node as usize].first_child + k);
            node = if h.holds(a, ot, t) { a } else { b };
        }
        loop {
            let (lo, hi) = (self.offsets[node as usize], self.offsets[node as usize + 1]);
            for l in &self.links[lo as usize..hi as usize] {
                if h.holds(l.p, os, s) {
                    return h.surfaces.source_weight[os] * h.surfaces.reflectance[ot] * l.g;
                }
            }
            node = h.nodes[node as usize].parent;
            if node == NONE {
                return 0.0;
            }
        }
    }
}

/// Links gather into a receiver node and push down to its elements, so the operator is the
/// links themselves: no N × N matrix is formed.
impl Representation for ClusteredRadiosity {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        self.lookup(s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(self.stats.links)
    }

    /// The hierarchy (clusters, elements, the surface edges' tables) and the links by
    /// receiver.
    fn memory_bytes(&self) -> usize {
        self.h.heap_bytes()
            + self.offsets.capacity() * size_of::<u32>()
            + self.links.capacity() * size_of::<Gather>()
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.fingerprint)
    }

    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        check_fingerprint(self.scene_fingerprint(), mesh)?;
        if stop() {
            return Err(SolveError::Interrupted);
        }
        Ok(Box::new(ClusterOperator::new(
            &self.h,
            self.links.clone(),
            mesh,
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::blocker_kernel;
    use flatland_solve::Reference;

    #[test]
    fn a_seed_gives_one_result_and_another_seed_another() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(80, 4).unwrap());
        let params = ClusteredParams::default();
        let a = ClusteredRadiosity::build(&kernel, 2000, &params, 5).unwrap();
        let b = ClusteredRadiosity::build(&kernel, 2000, &params, 5).unwrap();
        assert_eq!(a.links(), b.links());
        assert_eq!(a.stats(), b.stats());
        let c = ClusteredRadiosity::build(&kernel, 2000, &params, 6).unwrap();
        assert_ne!(
            a.links(),
            c.links(),
            "rays from another seed see other values"
        );
    }

    #[test]
    fn zeta_falls_as_the_budget_grows_and_bytes_grow_with_the_links() {
        let kernel = blocker_kernel();
        let reference = Reference::new(&kernel, 128, 2000, 3);
        let mut last = (f64::INFINITY, 0);
        for budget in [100, 1000, 10_000] {
            let rep =
                ClusteredRadiosity::build(&kernel, budget, &ClusteredParams::default(), 2).unwrap();
            let e = reference.errors(&rep).grid;
            assert!(e < last.0, "budget {budget}: {e} after {last:?}");
            assert!(rep.memory_bytes() > last.1);
            assert_eq!(rep.basis_functions(), Some(rep.links().len()));
            last = (e, rep.memory_bytes());
        }
        // About the hierarchy plus a link's 16 bytes and its receiver's offset.
        let rep =
            ClusteredRadiosity::build(&kernel, 10_000, &ClusteredParams::default(), 2).unwrap();
        let per_link = rep.memory_bytes() as f64 / 10_000.0;
        assert!(
            (16.0..200.0).contains(&per_link),
            "{per_link} bytes per link"
        );
    }

    #[test]
    fn zeta_is_the_value_of_the_one_link_holding_the_pair() {
        let kernel = blocker_kernel();
        let rep = ClusteredRadiosity::build(&kernel, 500, &ClusteredParams::default(), 7).unwrap();
        let h = &rep.h;
        for k in 0..4000 {
            let (s, t) = ((k as f64 * 0.618_034) % 1.0, (k as f64 * 0.414_214) % 1.0);
            let (Some(os), Some(ot)) = (h.surfaces.locate(s), h.surfaces.locate(t)) else {
                continue;
            };
            let holding: Vec<&Gather> = rep
                .links
                .iter()
                .filter(|l| h.holds(l.p, os, s) && h.holds(l.q, ot, t))
                .collect();
            assert!(holding.len() <= 1, "({s}, {t})");
            let expected = holding.first().map_or(0.0, |l| {
                h.surfaces.source_weight[os] * h.surfaces.reflectance[ot] * l.g
            });
            assert_eq!(rep.zeta(s, t), expected, "({s}, {t})");
        }
    }
}
