//! The pairs of surface edges whose visibility varies, found without classifying every pair:
//! a walk over pairs of clusters of surface edges that settles a whole bundle of pairs at once
//! where geometry decides it, and classifies one by one only the pairs an occluder may cut in
//! part.
//!
//! A pair's visibility varies only where an occluder's end point, or its crossing with the
//! pair's edges, lies in the convex hull of the two edges (docs/ALGORITHM.md §2.1): then the
//! occluder meets the hull's interior. So a bundle whose hull's interior no edge meets holds no
//! such pair (in a convex room the walls lie on every hull's boundary), nor does one that a
//! single edge cuts through (every segment between its two clusters crosses that edge), nor
//! one whose edges on one side all have the other side behind them (no pair faces).
//!
//! The walk costs what its tests cost, so each is made to look at little: the edge that cuts
//! a bundle is sought by the tree among the edges crossing one short probe between the two
//! clusters, and the edges that may meet a bundle's interior are passed down as the part of
//! the parent's list after the first one found inside (a bundle is settled only when none is,
//! so the search usually stops at that first one).

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec2;

use super::{Kernel, PairClass};
use crate::SurfaceRank;
use crate::visibility::{Hull, cuts_bundle, orient};

/// What [`Kernel::varying_pairs`] found, and the work it took.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VaryingPairs {
    /// The pairs of surface ranks `(a, b)`, `a < b`, whose [`Kernel::pair_class`] is
    /// [`PairClass::Varies`], in increasing order.
    pub pairs: Vec<(SurfaceRank, SurfaceRank)>,
    /// Pairs of surface edges classified one by one (the others were settled in bundles).
    pub classified: usize,
    /// Bundles of pairs tested at once.
    pub bundles: usize,
}

impl VaryingPairs {
    fn merge(mut self, other: VaryingPairs) -> VaryingPairs {
        self.pairs.extend(other.pairs);
        self.classified += other.classified;
        self.bundles += other.bundles;
        self
    }
}

/// Bundles of at least this many pairs walk their parts on both threads of a `rayon::join`.
const PARALLEL_PAIRS: usize = 1 << 12;

/// A bundle is tested for one edge cutting all of it while its clusters' hulls have at most
/// this many pairs of vertices (the test takes one orientation per pair).
const MAX_CUT_TEST: usize = 1 << 10;

/// A bundle is tested for one edge cutting all of it only while one of its clusters has at
/// most this many edges: between two large ones a single edge rarely cuts every segment, and
/// the probe for it is long (on a floor plan of 10⁴ edges this takes a fifth off the walk).
const MAX_CUT_CLUSTER: usize = 8;

/// A cluster is tested for hiding the other of its bundle while it has at most this many edges.
const MAX_HIDING_TEST: usize = 4;

/// A single pair is classified at once, rather than first looking for an edge inside its hull,
/// when more than this many edges may be there (classifying takes the tree's few).
const MAX_PAIR_SCAN: usize = 64;

/// A cluster of surface edges: a node of a median-split tree over the surface ranks.
struct Cluster {
    /// Its ranks: `Tree::ranks[first..first + len]`.
    first: usize,
    len: usize,
    /// The convex hull of its edges' end points (2 points for one edge).
    hull: Hull,
    /// Its two halves (`None` for one edge).
    halves: Option<(usize, usize)>,
}

impl Cluster {
    fn is_one_edge(&self) -> bool {
        self.halves.is_none()
    }
}

/// The clusters of a scene's surface edges, `clusters[0]` all of them.
struct Tree {
    ranks: Vec<SurfaceRank>,
    clusters: Vec<Cluster>,
}

impl Kernel {
    /// The pairs of parent surface edges whose visibility varies ([`PairClass::Varies`]),
    /// exactly those a loop over all pairs finds, at a cost that grows with the pairs near an
    /// occluder's end point rather than with all pairs: bundles of pairs (two clusters of
    /// nearby edges) are settled at once where no edge meets the interior of the convex hull
    /// of their end points, one edge cuts every segment between them, or no pair faces; only
    /// the pairs left are classified (and kept, as [`Kernel::pair_class`] keeps them). A convex
    /// room of `n` walls and a box classifies `O(n)` pairs, not `n²` (4096 walls: 8220 pairs,
    /// every one of them varying); a floor plan, where rooms see each other through doors,
    /// about as many as vary (1032 edges: 16 343 for 15 445).
    ///
    /// Listed once per kernel and kept (8 bytes a pair).
    #[must_use]
    pub fn varying_pairs(&self) -> &VaryingPairs {
        self.varying_pairs_counting(&AtomicU64::new(0))
    }

    /// [`Kernel::varying_pairs`], adding to `decided` the pairs of surface edges decided as the
    /// walk goes (from another thread, `decided / ` [`Kernel::surface_pairs`] is its
    /// progress). Nothing is added when the pairs were listed before.
    pub fn varying_pairs_counting(&self, decided: &AtomicU64) -> &VaryingPairs {
        self.varying.get_or_init(|| {
            if self.surface_parents.is_empty() {
                return VaryingPairs::default();
            }
            let tree = Tree::new(self);
            let near: Vec<u32> = (0..self.segments.len() as u32).collect();
            let mut found = tree.walk(self, 0, 0, &near, decided);
            found.pairs.sort_unstable();
            found
        })
    }

    /// The unordered pairs of distinct surface parents, `n (n − 1) / 2`.
    #[must_use]
    pub fn surface_pairs(&self) -> u64 {
        let n = self.surface_parents.len() as u64;
        n * n.saturating_sub(1) / 2
    }
}

impl Tree {
    fn new(kernel: &Kernel) -> Tree {
        let mut ranks: Vec<SurfaceRank> = kernel.surface_ranks().collect();
        let mut clusters = Vec::with_capacity(2 * ranks.len());
        split(kernel, &mut ranks, 0, &mut clusters);
        Tree { ranks, clusters }
    }

    /// The pairs of bundle `(a, b)` (of cluster `a` with itself when `a == b`).
    fn pairs(&self, a: usize, b: usize) -> u64 {
        let (la, lb) = (self.clusters[a].len as u64, self.clusters[b].len as u64);
        if a == b { la * (la - 1) / 2 } else { la * lb }
    }

    /// The varying pairs between clusters `a` and `b` (within `a` when `a == b`); `near` holds
    /// every edge that may meet the interior of their hull (a tail of the list of the bundle
    /// this one is part of). The pairs settled are added to `decided`.
    fn walk(
        &self,
        kernel: &Kernel,
        a: usize,
        b: usize,
        near: &[u32],
        decided: &AtomicU64,
    ) -> VaryingPairs {
        let (ca, cb) = (&self.clusters[a], &self.clusters[b]);
        if a == b && ca.is_one_edge() {
            return VaryingPairs::default(); // an edge with itself: k = 0
        }
        let mut found = VaryingPairs {
            bundles: 1,
            ..VaryingPairs::default()
        };
        let Some(near) = self.unsettled(kernel, a, b, near) else {
            decided.fetch_add(self.pairs(a, b), Ordering::Relaxed);
            return found;
        };
        let parts: Vec<(usize, usize)> = match (ca.halves, cb.halves) {
            _ if a == b => {
                let (l, r) = ca.halves.expect("a cluster of one edge returned above");
                vec![(l, l), (l, r), (r, r)]
            }
            (None, None) => {
                let (r0, r1) = (self.ranks[ca.first], self.ranks[cb.first]);
                found.classified = 1;
                if kernel.pair_class(r0, r1) == PairClass::Varies {
                    found.pairs.push((r0.min(r1), r0.max(r1)));
                }
                decided.fetch_add(1, Ordering::Relaxed);
                return found;
            }
            // Halve both clusters where they are of a size, else the larger.
            (Some((al, ar)), Some((bl, br))) if ca.len <= 2 * cb.len && cb.len <= 2 * ca.len => {
                vec![(al, bl), (al, br), (ar, bl), (ar, br)]
            }
            (Some(_), Some((l, r))) if cb.len > ca.len => vec![(a, l), (a, r)],
            (None, Some((l, r))) => vec![(a, l), (a, r)],
            (Some((l, r)), _) => vec![(l, b), (r, b)],
        };
        let parallel = ca.len * cb.len >= PARALLEL_PAIRS;
        found.merge(self.walk_parts(kernel, &parts, near, parallel, decided))
    }

    /// The tail of `near` from the first edge that meets the interior of the hull of bundle
    /// `(a, b)` (every later edge that does is in it), or `None` when geometry settles every
    /// pair in it: no pair faces, one edge cuts all of them (every pair is hidden or never
    /// faces), or no edge meets the hull's interior (every pair is clear or never faces).
    fn unsettled<'n>(
        &self,
        kernel: &Kernel,
        a: usize,
        b: usize,
        near: &'n [u32],
    ) -> Option<&'n [u32]> {
        let (ca, cb) = (&self.clusters[a], &self.clusters[b]);
        if a != b && (self.hides(kernel, ca, &cb.hull) || self.hides(kernel, cb, &ca.hull)) {
            return None;
        }
        // An edge that cuts the bundle crosses every segment from one cluster to the other, so
        // the tree finds the few worth the full test along the shortest between two vertices.
        if a != b
            && ca.hull.points().len() * cb.hull.points().len() <= MAX_CUT_TEST
            && ca.len.min(cb.len) <= MAX_CUT_CLUSTER
        {
            let (u, v) = closest_vertices(&ca.hull, &cb.hull);
            let cut = |_, s| cuts_bundle(&ca.hull, &cb.hull, s);
            if kernel.bvh.any_hit_where(u, v, cut) {
                return None;
            }
        }
        if ca.is_one_edge() && cb.is_one_edge() && near.len() > MAX_PAIR_SCAN {
            return Some(near);
        }
        let joint;
        let hull = if a == b {
            &ca.hull
        } else {
            joint = ca.hull.join(&cb.hull);
            &joint
        };
        // Every edge before the first inside is outside the parent's hull too, which holds
        // this one's: its children need not look at them again.
        let first = near
            .iter()
            .position(|&i| hull.meets_interior(kernel.segments[i as usize]))?;
        Some(&near[first..])
    }

    /// Whether every edge of the (small) cluster `c` has all of `hull` on or behind its line,
    /// where no facing segment reaches: then no pair of theirs faces.
    fn hides(&self, kernel: &Kernel, c: &Cluster, hull: &Hull) -> bool {
        c.len <= MAX_HIDING_TEST
            && self.ranks[c.first..c.first + c.len].iter().all(|&r| {
                let (a, b) = kernel.surface_parent(r);
                hull.points().iter().all(|&p| orient(a, b, p) <= 0.0)
            })
    }

    /// [`Tree::walk`] over `parts`, on both threads when `parallel`.
    fn walk_parts(
        &self,
        kernel: &Kernel,
        parts: &[(usize, usize)],
        near: &[u32],
        parallel: bool,
        decided: &AtomicU64,
    ) -> VaryingPairs {
        match parts {
            [] => VaryingPairs::default(),
            [(a, b)] => self.walk(kernel, *a, *b, near, decided),
            [(a, b), rest @ ..] if parallel => {
                let (first, others) = rayon::join(
                    || self.walk(kernel, *a, *b, near, decided),
                    || self.walk_parts(kernel, rest, near, parallel, decided),
                );
                first.merge(others)
            }
            [(a, b), rest @ ..] => self
                .walk(kernel, *a, *b, near, decided)
                .merge(self.walk_parts(kernel, rest, near, parallel, decided)),
        }
    }
}

/// The vertices of `a` and of `b` nearest each other: the ends of the shortest probe for an
/// edge that cuts the bundle between them (a short probe meets few boxes of the tree).
fn closest_vertices(a: &Hull, b: &Hull) -> (DVec2, DVec2) {
    let mut best = (a.points()[0], b.points()[0]);
    let mut nearest = f64::INFINITY;
    for &u in a.points() {
        for &v in b.points() {
            let d = u.distance_squared(v);
            if d < nearest {
                (best, nearest) = ((u, v), d);
            }
        }
    }
    best
}

/// Appends the cluster of `ranks` (which start at `first` in the tree's order) and those below
/// it, halving at the median of the edges' midpoints along the longer side of their bounding
/// box; returns its index.
fn split(
    kernel: &Kernel,
    ranks: &mut [SurfaceRank],
    first: usize,
    clusters: &mut Vec<Cluster>,
) -> usize {
    let index = clusters.len();
    let (a, b) = kernel.surface_parent(ranks[0]);
    clusters.push(Cluster {
        first,
        len: ranks.len(),
        hull: Hull::of(&[a, b]),
        halves: None,
    });
    if ranks.len() == 1 {
        return index;
    }
    let middle = |r: SurfaceRank| {
        let (a, b) = kernel.surface_parent(r);
        (a + b) * 0.5
    };
    let (lo, hi) = ranks
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &r| {
            (lo.min(middle(r)), hi.max(middle(r)))
        });
    let axis = usize::from(hi.y - lo.y > hi.x - lo.x);
    let half = ranks.len() / 2;
    // Ties by rank: the same scene always gives the same tree.
    ranks.select_nth_unstable_by(half, |&p, &q| {
        middle(p)[axis].total_cmp(&middle(q)[axis]).then(p.cmp(&q))
    });
    let (left, right) = ranks.split_at_mut(half);
    let l = split(kernel, left, first, clusters);
    let r = split(kernel, right, first + half, clusters);
    clusters[index].hull = clusters[l].hull.join(&clusters[r].hull);
    clusters[index].halves = Some((l, r));
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, random_scene};
    use crate::{Edge, Scene};
    use flatland_testkit::rooms;

    /// What a loop over all pairs finds.
    fn every_pair(kernel: &Kernel) -> Vec<(SurfaceRank, SurfaceRank)> {
        kernel
            .surface_ranks()
            .flat_map(|a| {
                kernel
                    .surface_ranks()
                    .filter(move |&b| b > a)
                    .map(move |b| (a, b))
            })
            .filter(|&(a, b)| kernel.pair_class(a, b) == PairClass::Varies)
            .collect()
    }

    /// Issue 20's convex room: `n` inward walls on a circle of radius 10 around a box of 4
    /// blockers off the centre.
    fn convex_room(n: usize) -> Scene {
        let mut edges = Edge::polygon(&rooms::regular_polygon(n, 10.0), 0.5);
        edges[0].emission = 1.0;
        let c = rooms::off_centre_box();
        edges.extend((0..4).map(|i| Edge::blocker(c[i], c[(i + 1) % 4])));
        Scene::new(edges).unwrap()
    }

    #[test]
    fn the_walk_finds_what_every_pair_finds_on_the_bundled_scenes() {
        for name in crate::bundled::names() {
            let kernel = Kernel::new(bundled(name));
            let found = kernel.varying_pairs();
            assert_eq!(found.pairs, every_pair(&kernel), "{name}");
        }
    }

    #[test]
    fn the_walk_decides_every_pair_once_and_lists_once() {
        for name in ["floorplan", "maze", "fig3"] {
            let kernel = Kernel::new(bundled(name));
            let decided = AtomicU64::new(0);
            let first = kernel.varying_pairs_counting(&decided).clone();
            assert_eq!(
                decided.load(Ordering::Relaxed),
                kernel.surface_pairs(),
                "{name}"
            );
            // The second call returns the kept list and counts nothing.
            assert_eq!(kernel.varying_pairs_counting(&decided), &first, "{name}");
            assert_eq!(
                decided.load(Ordering::Relaxed),
                kernel.surface_pairs(),
                "{name}"
            );
        }
        let kernel = Kernel::new(convex_room(96));
        let decided = AtomicU64::new(0);
        kernel.varying_pairs_counting(&decided);
        assert_eq!(decided.into_inner(), 96 * 95 / 2);
    }

    #[test]
    fn the_walk_finds_what_every_pair_finds_on_random_scenes() {
        for seed in 0..3000 {
            let kernel = Kernel::new(random_scene(seed, seed % 2 == 0));
            assert_eq!(
                kernel.varying_pairs().pairs,
                every_pair(&kernel),
                "seed {seed}"
            );
        }
    }

    #[test]
    fn the_walk_finds_what_every_pair_finds_on_generated_plans() {
        for seed in 0..4 {
            let scene = crate::generate::floor_plan(120, seed).unwrap();
            let kernel = Kernel::new(scene);
            assert_eq!(
                kernel.varying_pairs().pairs,
                every_pair(&kernel),
                "seed {seed}"
            );
        }
        let kernel = Kernel::new(convex_room(96));
        let found = kernel.varying_pairs();
        assert!(!found.pairs.is_empty(), "the box casts shadows");
        assert_eq!(found.pairs, every_pair(&kernel));
    }

    /// The guard of issue 20: in the convex room the pairs classified one by one grow with the
    /// walls, not with the pairs of walls (n² / 2 = 2 million at 2048 walls).
    #[test]
    fn a_convex_room_classifies_pairs_in_proportion_to_its_walls() {
        let (small, large) = (
            Kernel::new(convex_room(256)),
            Kernel::new(convex_room(2048)),
        );
        let (small, large) = (small.varying_pairs(), large.varying_pairs());
        // Eight times the walls: about eight times the varying pairs and the work.
        let ratio = large.classified as f64 / small.classified as f64;
        assert!(
            ratio < 12.0,
            "{} → {} classified",
            small.classified,
            large.classified
        );
        assert!(
            large.classified < 40 * 2048,
            "{} classified",
            large.classified
        );
        assert!(large.bundles < 200 * 2048, "{} bundles", large.bundles);
        assert!(large.pairs.len() > 4 * small.pairs.len());
    }
}
