//! The built approximation: one refinement tree per linked edge pair, built from the
//! refinement and the link estimates, looked up by descent and read back as links.

use super::HrParams;
use super::elements::Surfaces;
use super::estimate::estimate;
use super::linking::InitialLinks;
use super::refine::{Node, Pending, Refiner};
use crate::{BaselineError, seeds};
use flatland_geom::{EdgeId, Kernel};
use rayon::prelude::*;

/// What one HR build did.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HrStats {
    /// The F_ε used.
    pub f_eps: f64,
    /// The minimum element length used, as a fraction of L.
    pub min_length: f64,
    /// Initial links (ordered surface-edge pairs that can interact).
    pub initial_links: usize,
    /// Final links with transfer: the basis functions.
    pub links: usize,
    /// Of those, links whose every ray was blocked (value 0, still a link).
    pub zero_links: usize,
    /// Rays cast (`links · rays_per_link`).
    pub rays: u64,
    /// Refinement-tree nodes stored.
    pub nodes: usize,
}

/// One final link, as exported for plots and checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HrLink {
    /// Sender edge.
    pub sender: EdgeId,
    /// Receiver edge.
    pub receiver: EdgeId,
    /// The sender element's s-interval `[s0, s1)`.
    pub s: [f64; 2],
    /// The receiver element's t-interval `[t0, t1)`.
    pub t: [f64; 2],
    /// The stored mean ζ.
    pub value: f64,
}

/// Hierarchical-radiosity approximation of ζ: a refinement tree per linked edge pair.
#[derive(Clone, Debug)]
pub struct HierarchicalRadiosity {
    pub(super) surfaces: Surfaces,
    /// `pairs[offsets[i]..offsets[i + 1]]` are sender ordinal i's (receiver ordinal, root node),
    /// sorted by receiver.
    pub(super) offsets: Vec<u32>,
    pub(super) pairs: Vec<(u32, u32)>,
    pub(super) nodes: Vec<Node>,
    pub(super) stats: HrStats,
}

/// The refinement's output: the trees with their links still waiting for rays.
struct Refined {
    offsets: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    nodes: Vec<Node>,
    pending: Vec<Pending>,
    links: usize,
}

impl HierarchicalRadiosity {
    /// Refines at `params.f_eps`, then casts `rays_per_link` rays per link (in parallel,
    /// deterministic: each link's rays come from its own seed stream). Refuses, naming
    /// `max_links`, an initial linking or a refinement larger than `params.max_links`.
    pub fn build(
        kernel: &Kernel,
        params: &HrParams,
        seed: u64,
    ) -> Result<HierarchicalRadiosity, BaselineError> {
        params.check()?;
        let surfaces = Surfaces::new(kernel);
        let initial = InitialLinks::within(&surfaces, params.max_links)?;
        let refined = refine_all(&surfaces, &initial, params)?;
        let values: Vec<(f64, u64)> = refined
            .pending
            .par_iter()
            .enumerate()
            .map(|(k, link)| estimate(kernel, &surfaces, link, params, seeds::item(seed, k as u64)))
            .collect();
        let Refined {
            offsets,
            mut pairs,
            mut nodes,
            pending,
            links,
        } = refined;
        let (mut rays, mut zero_links) = (0, 0);
        for (link, &(value, r)) in pending.iter().zip(&values) {
            nodes[link.slot as usize] = Node::Leaf(value);
            rays += r;
            zero_links += usize::from(value == 0.0);
        }
        nodes.shrink_to_fit();
        pairs.shrink_to_fit();
        let stats = HrStats {
            f_eps: params.f_eps,
            min_length: params.min_length,
            initial_links: initial.len(),
            links,
            zero_links,
            rays,
            nodes: nodes.len(),
        };
        Ok(HierarchicalRadiosity {
            surfaces,
            offsets,
            pairs,
            nodes,
            stats,
        })
    }

    /// What the build did.
    pub fn stats(&self) -> &HrStats {
        &self.stats
    }

    /// Every final link with its rectangle and value, by traversing the trees (for plots and
    /// checks; the representation itself stores only the trees).
    pub fn links(&self) -> Vec<HrLink> {
        let mut out = Vec::with_capacity(self.stats.links);
        for i in 0..self.surfaces.len() {
            for &(j, root) in self.linked(i) {
                let j = j as usize;
                let s = [self.surfaces.s0[i], self.surfaces.s1[i]];
                let t = [self.surfaces.s0[j], self.surfaces.s1[j]];
                self.collect(root, (i, j), s, t, &mut out);
            }
        }
        out
    }

    /// Sender ordinal i's (receiver ordinal, root node), sorted by receiver.
    fn linked(&self, i: usize) -> &[(u32, u32)] {
        &self.pairs[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    fn collect(
        &self,
        slot: u32,
        ij: (usize, usize),
        s: [f64; 2],
        t: [f64; 2],
        out: &mut Vec<HrLink>,
    ) {
        match self.nodes[slot as usize] {
            Node::Leaf(value) => out.push(HrLink {
                sender: EdgeId::new(self.surfaces.edge[ij.0]),
                receiver: EdgeId::new(self.surfaces.edge[ij.1]),
                s,
                t,
                value,
            }),
            Node::Empty => {}
            Node::Split {
                sender: true,
                first,
            } => {
                let mid = 0.5 * (s[0] + s[1]);
                self.collect(first, ij, [s[0], mid], t, out);
                self.collect(first + 1, ij, [mid, s[1]], t, out);
            }
            Node::Split {
                sender: false,
                first,
            } => {
                let mid = 0.5 * (t[0] + t[1]);
                self.collect(first, ij, s, [t[0], mid], out);
                self.collect(first + 1, ij, s, [mid, t[1]], out);
            }
        }
    }

    /// ζ̃(s, t): binary search of the sender and receiver edges, binary search of the receiver
    /// among the sender's linked edges, then a descent of that pair's tree.
    pub(super) fn lookup(&self, s: f64, t: f64) -> f64 {
        let (Some(i), Some(j)) = (self.surfaces.locate(s), self.surfaces.locate(t)) else {
            return 0.0;
        };
        let pairs = self.linked(i);
        let Ok(k) = pairs.binary_search_by_key(&(j as u32), |&(r, _)| r) else {
            return 0.0;
        };
        let (mut s0, mut s1) = (self.surfaces.s0[i], self.surfaces.s1[i]);
        let (mut t0, mut t1) = (self.surfaces.s0[j], self.surfaces.s1[j]);
        let mut slot = pairs[k].1;
        loop {
            match self.nodes[slot as usize] {
                Node::Leaf(value) => return value,
                Node::Empty => return 0.0,
                Node::Split {
                    sender: true,
                    first,
                } => {
                    let mid = 0.5 * (s0 + s1);
                    if s < mid {
                        (s1, slot) = (mid, first)
                    } else {
                        (s0, slot) = (mid, first + 1)
                    }
                }
                Node::Split {
                    sender: false,
                    first,
                } => {
                    let mid = 0.5 * (t0 + t1);
                    if t < mid {
                        (t1, slot) = (mid, first)
                    } else {
                        (t0, slot) = (mid, first + 1)
                    }
                }
            }
        }
    }
}

/// Refines every initial link in order (sender, then receiver), so the pending links, and with
/// them the per-link seeds, come in one fixed order.
fn refine_all(
    surfaces: &Surfaces,
    initial: &InitialLinks,
    params: &HrParams,
) -> Result<Refined, BaselineError> {
    let mut refiner = Refiner::storing(surfaces, params, params.max_links);
    let mut offsets = Vec::with_capacity(surfaces.len() + 1);
    let mut pairs = Vec::with_capacity(initial.len());
    offsets.push(0u32);
    let mut next = initial.links.iter().peekable();
    for i in 0..surfaces.len() {
        while let Some(link) = next.next_if(|l| l.sender as usize == i) {
            let root = refiner.link_pair(link);
            pairs.push((link.receiver, root));
        }
        offsets.push(pairs.len() as u32);
    }
    if refiner.over_cap() {
        return Err(BaselineError::RefinementTooLarge {
            f_eps: params.f_eps,
            max_links: params.max_links,
        });
    }
    Ok(Refined {
        offsets,
        pairs,
        nodes: refiner.nodes,
        pending: refiner.pending,
        links: refiner.links,
    })
}

#[cfg(test)]
mod tests {
    use super::super::Oracle;
    use super::*;
    use crate::test_support::blocker_kernel;
    use flatland_solve::{Reference, Representation, grid_point, relative_l2};
    use rand::RngExt;

    #[test]
    fn error_falls_as_f_eps_falls() {
        let kernel = blocker_kernel();
        let reference = Reference::new(&kernel, 128, 4000, 5);
        for oracle in [Oracle::Weighted, Oracle::FormFactor] {
            let mut last = (f64::INFINITY, 0);
            for f_eps in [0.3, 0.1, 0.03, 0.01] {
                let params = HrParams {
                    f_eps,
                    oracle,
                    ..HrParams::default()
                };
                let hr = HierarchicalRadiosity::build(&kernel, &params, 3).unwrap();
                let e = reference.errors(&hr);
                assert!(
                    e.grid < last.0 && e.heldout.is_finite(),
                    "{params:?}: {e:?} after {last:?}"
                );
                assert!(hr.stats().links > last.1, "{params:?}: links must grow");
                last = (e.grid, hr.stats().links);
            }
        }
    }

    #[test]
    fn reported_error_equals_recomputation_from_the_links() {
        let kernel = blocker_kernel();
        let hr = HierarchicalRadiosity::build(
            &kernel,
            &HrParams {
                f_eps: 0.05,
                ..HrParams::default()
            },
            8,
        )
        .unwrap();
        let links = hr.links();
        assert_eq!(links.len(), hr.stats().links);
        let res = 64;
        let reference = Reference::new(&kernel, res, 300, 2);
        let mut approx = Vec::with_capacity(res * res);
        let mut exact = Vec::with_capacity(res * res);
        for k in 0..res * res {
            let (s, t) = grid_point(res, k);
            // Brute force: the links covering (s, t) — at most one, since they partition.
            let covering: Vec<&HrLink> = links
                .iter()
                .filter(|l| l.s[0] <= s && s < l.s[1] && l.t[0] <= t && t < l.t[1])
                .collect();
            assert!(
                covering.len() <= 1,
                "({s}, {t}) in {} links",
                covering.len()
            );
            let value = covering.first().map_or(0.0, |l| l.value);
            assert_eq!(value, hr.zeta(s, t), "lookup at ({s}, {t})");
            approx.push(value);
            exact.push(kernel.zeta(s, t));
        }
        let by_hand = relative_l2(&approx, &exact);
        let reported = reference.errors(&hr).grid;
        assert!(
            (by_hand - reported).abs() < 1e-12,
            "{by_hand} vs {reported}"
        );
    }

    #[test]
    fn links_cover_every_interacting_point() {
        // Wherever ζ > 0 some link must hold (s, t): the partition has no hole.
        let kernel = blocker_kernel();
        let hr = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 4).unwrap();
        let links = hr.links();
        let mut rng = flatland_testkit::rng(77);
        for _ in 0..3000 {
            let (s, t) = (rng.random::<f64>(), rng.random::<f64>());
            if kernel.zeta(s, t) > 0.0 {
                let n = links
                    .iter()
                    .filter(|l| l.s[0] <= s && s < l.s[1] && l.t[0] <= t && t < l.t[1])
                    .count();
                assert_eq!(n, 1, "({s}, {t})");
            }
        }
    }

    #[test]
    fn same_seed_same_links() {
        let kernel = blocker_kernel();
        let a = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 5).unwrap();
        let b = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 5).unwrap();
        assert_eq!(a.links(), b.links());
    }
}
