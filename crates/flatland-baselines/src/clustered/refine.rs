//! The refinement: from the root cluster's link with itself, the link with the largest oracle
//! value is split at the end with the larger extent, until the links reach the budget.

use super::ClusteredParams;
use super::clusters::Hierarchy;
use super::oracle::{estimate, transfer};
use super::solve::Gather;
use super::weights;
use crate::seeds;
use flatland_geom::{Kernel, PairClass};
use flatland_solve::{Mesh, SolveError, never};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// One link of the refinement: sender node, receiver node, its value and oracle.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate {
    pub(super) p: u32,
    pub(super) q: u32,
    pub(super) g: f64,
    /// `max(F_pq, F_qp) · uncertainty`: the oracle before the sender's weight and ρ.
    base: f64,
    pub(super) priority: f64,
    pub(super) alive: bool,
    /// Two elements' edge-pair class, which their children's links share.
    class: Option<PairClass>,
}

/// A link waiting to be split, largest oracle value first, then the oldest.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    priority: f64,
    id: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.priority
            .total_cmp(&other.priority)
            .then(other.id.cmp(&self.id))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// What the refinement made.
#[derive(Clone, Debug)]
pub(super) struct Refined {
    /// Every link made, `alive` the final ones.
    pub(super) links: Vec<Candidate>,
    pub(super) rays: u64,
    /// The oracle value of the next link that would have been split (the F_ε the budget
    /// amounts to); 0 when none was left.
    pub(super) f_eps: f64,
    /// Whether nothing was left to split (every link at the minimum length or certain).
    pub(super) finest: bool,
}

/// The refinement state.
struct Refiner<'a> {
    kernel: &'a Kernel,
    h: &'a mut Hierarchy,
    params: &'a ClusteredParams,
    seed: u64,
    /// Each node's sender weight in [0, 1] (nodes made since take their parent's).
    weights: Vec<f64>,
    links: Vec<Candidate>,
    heap: BinaryHeap<Entry>,
    count: usize,
    rays: u64,
}

/// The link counts the rounds stop at: `budget / 4^k` for `k = rounds, …, 1, 0`.
fn round_targets(budget: usize, rounds: usize) -> Vec<usize> {
    (0..=rounds)
        .rev()
        .map(|k| (budget >> (2 * k).min(63)).max(1))
        .collect()
}

/// Refines from the root's link with itself until `budget` links (or nothing is left to
/// split). The oracle of a link is `w(P) ρ(Q) · max(F_pq, F_qp) · uncertainty`, capped at its
/// parent link's so that refining greedily to a count is refining to a threshold F_ε (a
/// link's value never rises above the one it was split from). `w` is E' relative to its
/// largest until the first of `params.bf_rounds` rounds, then the radiosity the links so far
/// solve for: each round stops at a quarter of the next one's count, solves, re-weighs.
pub(super) fn refine(
    kernel: &Kernel,
    h: &mut Hierarchy,
    budget: usize,
    params: &ClusteredParams,
    seed: u64,
) -> Result<Refined, SolveError> {
    let mut r = Refiner {
        kernel,
        weights: weights::emission(h),
        h,
        params,
        seed,
        links: Vec::new(),
        heap: BinaryHeap::new(),
        count: 0,
        rays: 0,
    };
    if let Some(root) = r.h.root() {
        r.add((root, root), f64::INFINITY, None);
    }
    let targets = round_targets(budget, params.bf_rounds);
    let mut mesh = None;
    for (k, &target) in targets.iter().enumerate() {
        if k > 0 {
            let mesh = match &mesh {
                Some(m) => m,
                None => mesh.insert(weights::mesh(kernel)?),
            };
            r.reweigh(mesh)?;
        }
        while r.count < target {
            let Some(top) = r.heap.pop() else { break };
            r.split(top.id);
        }
    }
    let f_eps = r.heap.peek().map_or(0.0, |e| e.priority);
    Ok(Refined {
        finest: r.heap.is_empty(),
        links: r.links,
        rays: r.rays,
        f_eps,
    })
}

impl Refiner<'_> {
    /// Makes link `(p, q)` if the two can interact: casts its rays, and queues it when it can
    /// be split and its oracle is above 0.
    fn add(&mut self, (p, q): (u32, u32), cap: f64, class: Option<PairClass>) {
        let Some(t) = transfer(self.h, p, q) else {
            return;
        };
        let id = self.links.len() as u32;
        let e = estimate(
            self.kernel,
            self.h,
            (p, q),
            &t,
            (
                self.params.rays_per_link,
                seeds::item(self.seed, u64::from(id)),
            ),
            class,
        );
        self.rays += e.rays;
        let base = t.f_pq.max(t.f_qp) * e.uncertainty;
        let mut link = Candidate {
            p,
            q,
            g: e.g,
            base,
            priority: 0.0,
            alive: true,
            class: e.class,
        };
        link.priority = self.oracle(&link).min(cap);
        self.links.push(link);
        self.count += 1;
        self.queue(id);
    }

    /// Queues link `id` if it can be split and its oracle is above 0.
    fn queue(&mut self, id: u32) {
        let Candidate { p, q, priority, .. } = self.links[id as usize];
        if priority > 0.0 && (self.h.splittable(p) || self.h.splittable(q)) {
            self.heap.push(Entry { priority, id });
        }
    }

    /// A link's oracle value: infinite for a cluster's link with itself (always split).
    fn oracle(&self, link: &Candidate) -> f64 {
        if link.p == link.q {
            return f64::INFINITY;
        }
        self.weight(link.p) * self.h.nodes[link.q as usize].max_rho * link.base
    }

    /// Node `i`'s sender weight: its own, or its nearest ancestor's if it is newer than the
    /// weights (a part is at most as bright as the whole's brightest part).
    fn weight(&self, mut i: u32) -> f64 {
        while i as usize >= self.weights.len() {
            i = self.h.nodes[i as usize].parent;
        }
        self.weights[i as usize]
    }

    /// Solves with the links so far, weighs the senders by that radiosity and re-ranks every
    /// link waiting to be split.
    fn reweigh(&mut self, mesh: &Mesh) -> Result<(), SolveError> {
        let live: Vec<Gather> = self
            .links
            .iter()
            .filter(|l| l.alive)
            .map(|l| Gather {
                p: l.p,
                q: l.q,
                g: l.g,
            })
            .collect();
        self.weights = weights::radiosity(self.h, live, mesh, &never)?;
        let waiting: Vec<u32> = self.heap.drain().map(|e| e.id).collect();
        for id in waiting {
            let priority = self.oracle(&self.links[id as usize]);
            self.links[id as usize].priority = priority;
            self.queue(id);
        }
        Ok(())
    }

    /// Replaces link `id` by the links of its split end's children (both ends' for a link of
    /// a cluster with itself).
    fn split(&mut self, id: u32) {
        let Candidate {
            p,
            q,
            priority,
            class,
            ..
        } = self.links[id as usize];
        self.links[id as usize].alive = false;
        self.count -= 1;
        if p == q {
            let [a, b] = self.h.children(p);
            for (x, y) in [(a, a), (a, b), (b, a), (b, b)] {
                self.add((x, y), priority, None);
            }
            return;
        }
        if self.split_sender(p, q) {
            for c in self.h.children(p) {
                self.add((c, q), priority, class);
            }
        } else {
            for c in self.h.children(q) {
                self.add((p, c), priority, class);
            }
        }
    }

    /// Whether the sender end is split: the end with the larger extent (the receiver on a
    /// tie), unless only the other one can be.
    fn split_sender(&self, p: u32, q: u32) -> bool {
        let (can_p, can_q) = (self.h.splittable(p), self.h.splittable(q));
        let larger_p = self.h.nodes[p as usize].extent() > self.h.nodes[q as usize].extent();
        can_p && (larger_p || !can_q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::blocker_kernel;

    #[test]
    fn rounds_stop_at_quarters_of_the_budget() {
        assert_eq!(round_targets(1000, 0), [1000]);
        assert_eq!(round_targets(1000, 2), [62, 250, 1000]);
        assert_eq!(round_targets(3, 2), [1, 1, 3]);
    }

    #[test]
    fn the_budget_is_met_and_links_partition_the_interacting_pairs() {
        let kernel = blocker_kernel();
        for budget in [1, 10, 100, 1000] {
            let mut h = Hierarchy::new(&kernel, 1.0 / 256.0);
            let r = refine(&kernel, &mut h, budget, &ClusteredParams::default(), 3).unwrap();
            let count = r.links.iter().filter(|l| l.alive).count();
            assert!(count >= budget && count <= budget + 3, "{budget}: {count}");
            // Each pair of surface points that face each other lies in exactly one final link.
            let s = &h.surfaces;
            let mut rng = flatland_testkit::rng(budget as u64);
            for _ in 0..500 {
                use rand::RngExt;
                let (i, j) = (rng.random_range(0..s.len()), rng.random_range(0..s.len()));
                let si = s.s0[i] + (s.s1[i] - s.s0[i]) * rng.random::<f64>();
                let sj = s.s0[j] + (s.s1[j] - s.s0[j]) * rng.random::<f64>();
                if kernel.unoccluded(si, sj).k == 0.0 {
                    continue;
                }
                let holding = r
                    .links
                    .iter()
                    .filter(|l| l.alive && h.holds(l.p, i, si) && h.holds(l.q, j, sj))
                    .count();
                assert_eq!(holding, 1, "budget {budget}: ({i} {si}, {j} {sj})");
            }
        }
    }

    #[test]
    fn priorities_never_rise_down_the_refinement() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(120, 2).unwrap());
        let mut h = Hierarchy::new(&kernel, 1.0 / 256.0);
        let params = ClusteredParams {
            bf_rounds: 0,
            ..ClusteredParams::default()
        };
        let r = refine(&kernel, &mut h, 3000, &params, 1).unwrap();
        // Every link split had a priority at least the F_ε the budget stopped at (within one
        // round: a re-weighing re-ranks them).
        let split_min = r
            .links
            .iter()
            .filter(|l| !l.alive)
            .map(|l| l.priority)
            .fold(f64::INFINITY, f64::min);
        assert!(split_min >= r.f_eps, "{split_min} < {}", r.f_eps);
        assert!(r.rays > 0 && !r.finest);
    }
}
