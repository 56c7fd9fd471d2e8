//! The oracle and the ray-free refinement: an initial link is halved on the side seen under the
//! larger (weighted) form factor until both fall below F_ε, building the tree or only counting.

use super::elements::{Elem, Surfaces, interacts};
use super::linking::{InitialLink, InitialLinks};
use super::{HrParams, Oracle};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A node of a pair's refinement tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Node {
    /// A link: its mean ζ.
    Leaf(f64),
    /// A sub-rectangle where the elements cannot interact.
    Empty,
    /// Halved: children at `first` (lower half) and `first + 1`.
    Split { sender: bool, first: u32 },
}

/// A link waiting for its rays.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pending {
    pub(super) slot: u32,
    pub(super) p: Elem,
    pub(super) q: Elem,
    pub(super) transfer: f64,
}

/// What the oracle compares, fixed for one refinement.
#[derive(Clone, Copy, Debug)]
struct Rule {
    f_eps: f64,
    min_len: f64,
    /// Multiplies `E'(i) ρ(j)` into the oracle's estimate; `None` for plain form factors.
    weight_scale: Option<f64>,
}

impl Rule {
    fn new(surfaces: &Surfaces, params: &HrParams) -> Rule {
        Rule {
            f_eps: params.f_eps,
            min_len: params.min_length * surfaces.total_length,
            weight_scale: match params.oracle {
                Oracle::FormFactor => None,
                Oracle::Weighted => {
                    let max = surfaces
                        .source_weight
                        .iter()
                        .fold(0.0_f64, |m, &w| m.max(w));
                    Some(if max > 0.0 { 1.0 / max } else { 0.0 })
                }
            },
        }
    }

    /// The oracle: `None` keeps the link, `Some(true)` halves the sender element p,
    /// `Some(false)` the receiver element q.
    fn split(&self, surfaces: &Surfaces, p: &Elem, q: &Elem, transfer: f64) -> Option<bool> {
        let (lp, lq) = (p.length(), q.length());
        let weight = self.weight_scale.map_or(1.0, |scale| {
            scale * surfaces.source_weight[p.ord] * surfaces.reflectance[q.ord]
        });
        let (f_pq, f_qp) = (weight * transfer / lp, weight * transfer / lq);
        let (can_p, can_q) = (lp >= 2.0 * self.min_len, lq >= 2.0 * self.min_len);
        if f_pq.max(f_qp) < self.f_eps {
            None
        } else if f_pq >= f_qp {
            // q looks larger from p: split q, else p.
            if can_q {
                Some(false)
            } else {
                can_p.then_some(true)
            }
        } else if can_p {
            Some(true)
        } else {
            can_q.then_some(false)
        }
    }
}

/// The refinement of initial links: builds the trees (or only counts links, with a cap).
pub(super) struct Refiner<'a> {
    surfaces: &'a Surfaces,
    rule: Rule,
    store: bool,
    cap: usize,
    pub(super) links: usize,
    pub(super) nodes: Vec<Node>,
    pub(super) pending: Vec<Pending>,
}

impl<'a> Refiner<'a> {
    /// A refiner that stores trees and pending links, refusing to go past `cap` links.
    pub(super) fn storing(surfaces: &'a Surfaces, params: &HrParams, cap: usize) -> Self {
        Self::with_rule(surfaces, Rule::new(surfaces, params), true, cap)
    }

    fn with_rule(surfaces: &'a Surfaces, rule: Rule, store: bool, cap: usize) -> Self {
        Refiner {
            surfaces,
            rule,
            store,
            cap,
            links: 0,
            nodes: Vec::new(),
            pending: Vec::new(),
        }
    }

    pub(super) fn over_cap(&self) -> bool {
        self.links > self.cap
    }

    /// Refines one initial link; returns its root slot when storing.
    pub(super) fn link_pair(&mut self, link: &InitialLink) -> u32 {
        let slot = self.alloc(1);
        let (i, j) = (link.sender as usize, link.receiver as usize);
        self.refine(
            slot,
            self.surfaces.whole(i),
            self.surfaces.whole(j),
            link.transfer,
        );
        slot
    }

    fn alloc(&mut self, n: usize) -> u32 {
        let first = self.nodes.len() as u32;
        if self.store {
            self.nodes.extend(std::iter::repeat_n(Node::Empty, n));
        }
        first
    }

    fn refine(&mut self, slot: u32, p: Elem, q: Elem, transfer: f64) {
        if self.over_cap() {
            return;
        }
        if !interacts(transfer, &p, &q) {
            return; // the slot stays Empty
        }
        match self.rule.split(self.surfaces, &p, &q, transfer) {
            None => self.keep(slot, p, q, transfer),
            Some(sender) => self.halve(slot, p, q, sender),
        }
    }

    fn keep(&mut self, slot: u32, p: Elem, q: Elem, transfer: f64) {
        self.links += 1;
        if self.store {
            self.pending.push(Pending {
                slot,
                p,
                q,
                transfer,
            });
        }
    }

    fn halve(&mut self, slot: u32, p: Elem, q: Elem, sender: bool) {
        let first = self.alloc(2);
        if self.store {
            self.nodes[slot as usize] = Node::Split { sender, first };
        }
        if sender {
            for (k, half) in p.halves().into_iter().enumerate() {
                let t = self.surfaces.transfer(&half, &q);
                self.refine(first + k as u32, half, q, t);
            }
        } else {
            for (k, half) in q.halves().into_iter().enumerate() {
                let t = self.surfaces.transfer(&p, &half);
                self.refine(first + k as u32, p, half, t);
            }
        }
    }
}

/// Links HR would build at `params.f_eps`, found without rays; `None` when more than `cap`.
///
/// The initial links refine independently, so they are counted in parallel; the total is
/// the same sum in any order, and `None` exactly when it exceeds `cap` (the count stops early
/// once the running total is past it).
pub(super) fn count_links(
    surfaces: &Surfaces,
    initial: &InitialLinks,
    params: &HrParams,
    cap: usize,
) -> Option<usize> {
    let rule = Rule::new(surfaces, params);
    let total = AtomicUsize::new(0);
    // Small scenes stay on one thread: the bisection counts some 80 times.
    initial
        .links
        .par_iter()
        .with_min_len(512)
        .try_for_each(|link| {
            let mut refiner = Refiner::with_rule(surfaces, rule, false, cap);
            refiner.link_pair(link);
            let now = total.fetch_add(refiner.links, Ordering::Relaxed) + refiner.links;
            (now <= cap).then_some(())
        })?;
    Some(total.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::blocker_kernel;

    #[test]
    fn parallel_counts_equal_the_stored_refinement() {
        // The count the budget search uses is the number of links a build stores.
        let kernel = blocker_kernel();
        let surfaces = Surfaces::new(&kernel);
        let initial = InitialLinks::within(&surfaces, usize::MAX).unwrap();
        for f_eps in [1.5, 0.3, 0.05, 0.01] {
            let params = HrParams {
                f_eps,
                ..HrParams::default()
            };
            let mut refiner = Refiner::storing(&surfaces, &params, usize::MAX);
            for link in &initial.links {
                refiner.link_pair(link);
            }
            let count = count_links(&surfaces, &initial, &params, usize::MAX);
            assert_eq!(count, Some(refiner.links), "F_ε = {f_eps}");
            assert_eq!(refiner.pending.len(), refiner.links);
            let links = refiner.links;
            assert_eq!(
                count_links(&surfaces, &initial, &params, links),
                Some(links)
            );
            assert_eq!(count_links(&surfaces, &initial, &params, links - 1), None);
        }
    }
}
