//! The hierarchy refinement walks: a binary tree of clusters over the surface edges (a BVH
//! split at the median of the longer axis, one whole edge per leaf) and, below each edge, its
//! elements, halved on demand. A node's children are created after it, so every child's index
//! is larger than its parent's: pulling runs backwards over the nodes, pushing forwards.

use crate::hr::elements::{Elem, Surfaces};
use flatland_geom::{EdgeId, Kernel};
use glam::DVec2;

/// No node (no parent, no children yet).
pub(super) const NONE: u32 = u32::MAX;

/// What a node covers.
#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    /// The surface edges at leaf positions `lo..hi` of [`Hierarchy::leaf_edge`].
    Cluster { lo: u32, hi: u32 },
    /// An interval of one surface edge (the whole edge at a leaf of the cluster tree).
    Element(Elem),
}

/// One node: a cluster of edges or an element, with what the oracle needs of it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    /// Its bounding box.
    pub(super) lo: DVec2,
    pub(super) hi: DVec2,
    /// Total surface length in it.
    pub(super) length: f64,
    pub(super) parent: u32,
    /// The first of its two children (consecutive), [`NONE`] while it has none.
    pub(super) first_child: u32,
    pub(super) kind: Kind,
    /// The largest source weight E' of its edges.
    pub(super) max_weight: f64,
    /// The largest reflectance ρ of its edges.
    pub(super) max_rho: f64,
}

impl Node {
    /// The diagonal of its box: the extent that decides which end of a link is split.
    pub(super) fn extent(&self) -> f64 {
        (self.hi - self.lo).length()
    }

    /// The element it is, if it is one.
    pub(super) fn element(&self) -> Option<&Elem> {
        match &self.kind {
            Kind::Element(e) => Some(e),
            Kind::Cluster { .. } => None,
        }
    }
}

/// The clusters and elements of one scene.
#[derive(Clone, Debug)]
pub(super) struct Hierarchy {
    pub(super) surfaces: Surfaces,
    pub(super) nodes: Vec<Node>,
    /// The surface ordinal at each leaf position.
    pub(super) leaf_edge: Vec<u32>,
    /// The leaf position of each surface ordinal.
    pub(super) leaf_pos: Vec<u32>,
    /// The node of each whole surface edge.
    pub(super) edge_node: Vec<u32>,
    /// Surface length before each leaf position (`n + 1` entries): a cluster's points by length.
    pub(super) cum: Vec<f64>,
    /// The first piece of each surface edge's parent edge: pieces of one parent never interact.
    pub(super) parent_edge: Vec<u32>,
    /// The minimum element length, in scene units.
    pub(super) min_len: f64,
}

impl Hierarchy {
    /// The cluster tree over `kernel`'s surface edges; `min_length` is a fraction of the mean
    /// surface-edge length.
    pub(super) fn new(kernel: &Kernel, min_length: f64) -> Hierarchy {
        let surfaces = Surfaces::new(kernel);
        let n = surfaces.len();
        let scene = kernel.scene();
        let parent_edge = surfaces
            .edge
            .iter()
            .map(|&e| {
                let parent = scene.parent_pieces(EdgeId::new(e));
                parent.map_or(e, |r| r.start.index()) as u32
            })
            .collect();
        let mut h = Hierarchy {
            nodes: Vec::with_capacity(2 * n),
            leaf_edge: vec![0; n],
            leaf_pos: vec![0; n],
            edge_node: vec![0; n],
            cum: vec![0.0; n + 1],
            parent_edge,
            min_len: min_length * surfaces.total_length / n.max(1) as f64,
            surfaces,
        };
        if n > 0 {
            let mut order: Vec<u32> = (0..n as u32).collect();
            h.nodes.push(h.edge_leaf(0, NONE)); // the root's slot, filled by `build`
            h.build(&mut order, 0, 0, NONE);
            for (k, &ord) in h.leaf_edge.iter().enumerate() {
                h.cum[k + 1] = h.cum[k] + h.surfaces.whole(ord as usize).length();
            }
        }
        h
    }

    /// Fills `slot` with the cluster of the edges `order` (at leaf positions from `offset`).
    fn build(&mut self, order: &mut [u32], offset: usize, slot: u32, parent: u32) {
        if let [ord] = *order {
            self.leaf_edge[offset] = ord;
            self.leaf_pos[ord as usize] = offset as u32;
            self.edge_node[ord as usize] = slot;
            self.nodes[slot as usize] = self.edge_leaf(ord as usize, parent);
            return;
        }
        let centre = |o: u32| 0.5 * (self.surfaces.a[o as usize] + self.surfaces.b[o as usize]);
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &o in order.iter() {
            (lo, hi) = (lo.min(centre(o)), hi.max(centre(o)));
        }
        let axis = usize::from(hi.y - lo.y > hi.x - lo.x);
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |&p, &q| {
            centre(p)[axis].total_cmp(&centre(q)[axis]).then(p.cmp(&q))
        });
        let first = self.nodes.len() as u32;
        let placeholder = self.nodes[slot as usize];
        self.nodes.extend([placeholder; 2]);
        let (left, right) = order.split_at_mut(mid);
        self.build(left, offset, first, slot);
        self.build(right, offset + mid, first + 1, slot);
        let (a, b) = (self.nodes[first as usize], self.nodes[first as usize + 1]);
        self.nodes[slot as usize] = Node {
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
            length: a.length + b.length,
            parent,
            first_child: first,
            kind: Kind::Cluster {
                lo: offset as u32,
                hi: (offset + order.len()) as u32,
            },
            max_weight: a.max_weight.max(b.max_weight),
            max_rho: a.max_rho.max(b.max_rho),
        };
    }

    /// The node of a whole surface edge.
    fn edge_leaf(&self, ord: usize, parent: u32) -> Node {
        self.element_node(self.surfaces.whole(ord), parent)
    }

    fn element_node(&self, e: Elem, parent: u32) -> Node {
        let s = &self.surfaces;
        Node {
            lo: e.a.min(e.b),
            hi: e.a.max(e.b),
            length: e.length(),
            parent,
            first_child: NONE,
            kind: Kind::Element(e),
            max_weight: s.source_weight[e.ord],
            max_rho: s.reflectance[e.ord],
        }
    }

    /// The root, if the scene has a surface edge.
    pub(super) fn root(&self) -> Option<u32> {
        (!self.nodes.is_empty()).then_some(0)
    }

    /// Whether refinement may split node `i`: a cluster always, an element while it is at
    /// least twice the minimum length.
    pub(super) fn splittable(&self, i: u32) -> bool {
        let node = &self.nodes[i as usize];
        node.first_child != NONE
            || node
                .element()
                .is_some_and(|e| e.length() >= 2.0 * self.min_len)
    }

    /// Node `i`'s two children, halving an element the first time it is asked.
    pub(super) fn children(&mut self, i: u32) -> [u32; 2] {
        let node = self.nodes[i as usize];
        if node.first_child == NONE {
            let e = *node.element().expect("a cluster has children");
            let first = self.nodes.len() as u32;
            let [l, r] = e.halves();
            self.nodes.push(self.element_node(l, i));
            self.nodes.push(self.element_node(r, i));
            self.nodes[i as usize].first_child = first;
        }
        let first = self.nodes[i as usize].first_child;
        [first, first + 1]
    }

    /// The point of node `i` at fraction `u ∈ [0, 1)` of its length: its surface ordinal,
    /// parameter and position.
    pub(super) fn point(&self, i: u32, u: f64) -> (usize, f64, DVec2) {
        let at = |e: &Elem, f: f64| (e.ord, e.s0 + (e.s1 - e.s0) * f, e.a + (e.b - e.a) * f);
        match &self.nodes[i as usize].kind {
            Kind::Element(e) => at(e, u),
            Kind::Cluster { lo, hi } => {
                let (lo, hi) = (*lo as usize, *hi as usize);
                let target = self.cum[lo] + u * (self.cum[hi] - self.cum[lo]);
                // The leaf whose length interval holds `target`, within the cluster's leaves.
                let k = (lo + self.cum[lo + 1..=hi].partition_point(|&c| c <= target)).min(hi - 1);
                let e = self.surfaces.whole(self.leaf_edge[k] as usize);
                let f = ((target - self.cum[k]) / (self.cum[k + 1] - self.cum[k])).clamp(0.0, 1.0);
                // Keep s inside the edge's half-open interval.
                let (ord, s, p) = at(&e, f);
                (ord, s.min(f64::from_bits(e.s1.to_bits() - 1)), p)
            }
        }
    }

    /// How many surface edges node `i` touches.
    pub(super) fn edges_in(&self, i: u32) -> usize {
        match self.nodes[i as usize].kind {
            Kind::Cluster { lo, hi } => (hi - lo) as usize,
            Kind::Element(_) => 1,
        }
    }

    /// Node `i` as elements: the whole edges of a cluster, or the element itself.
    pub(super) fn elements_of(&self, i: u32) -> Vec<Elem> {
        match self.nodes[i as usize].kind {
            Kind::Cluster { lo, hi } => (lo..hi)
                .map(|k| self.surfaces.whole(self.leaf_edge[k as usize] as usize))
                .collect(),
            Kind::Element(e) => vec![e],
        }
    }

    /// Whether node `i` holds the point of surface ordinal `ord` at parameter `s`.
    pub(super) fn holds(&self, i: u32, ord: usize, s: f64) -> bool {
        match &self.nodes[i as usize].kind {
            Kind::Element(e) => e.ord == ord && e.s0 <= s && s < e.s1,
            Kind::Cluster { lo, hi } => (*lo..*hi).contains(&self.leaf_pos[ord]),
        }
    }

    /// Heap bytes of the hierarchy (part of `memory_bytes`).
    pub(super) fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.nodes.capacity() * size_of::<Node>()
            + (self.leaf_edge.capacity()
                + self.leaf_pos.capacity()
                + self.edge_node.capacity()
                + self.parent_edge.capacity())
                * size_of::<u32>()
            + self.cum.capacity() * size_of::<f64>()
            + self.surfaces.heap_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::box_kernel;

    #[test]
    fn clusters_cover_their_edges_and_children_follow_parents() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(120, 3).unwrap());
        let h = Hierarchy::new(&kernel, 1.0 / 256.0);
        let n = h.surfaces.len();
        assert_eq!(h.nodes.len(), 2 * n - 1, "a binary tree over {n} leaves");
        for (i, node) in h.nodes.iter().enumerate() {
            if node.parent != NONE {
                assert!((node.parent as usize) < i);
            }
            if let Kind::Cluster { lo, hi } = node.kind {
                let [a, b] = [node.first_child, node.first_child + 1].map(|c| h.nodes[c as usize]);
                assert!(node.first_child as usize > i);
                assert!((node.length - a.length - b.length).abs() < 1e-9 * node.length);
                let total: f64 = (lo..hi)
                    .map(|k| h.surfaces.whole(h.leaf_edge[k as usize] as usize).length())
                    .sum();
                assert!((node.length - total).abs() < 1e-9 * total);
                // Every edge of the cluster lies in its box.
                for k in lo..hi {
                    let o = h.leaf_edge[k as usize] as usize;
                    for p in [h.surfaces.a[o], h.surfaces.b[o]] {
                        assert!(p.cmpge(node.lo).all() && p.cmple(node.hi).all());
                    }
                }
            }
        }
        for ord in 0..n {
            let leaf = h.edge_node[ord];
            assert!(h.holds(0, ord, h.surfaces.s0[ord]));
            assert!(h.holds(leaf, ord, h.surfaces.s0[ord]));
            assert_eq!(h.leaf_edge[h.leaf_pos[ord] as usize] as usize, ord);
        }
    }

    #[test]
    fn points_of_a_cluster_are_spread_by_length_and_lie_on_its_edges() {
        let kernel = box_kernel();
        let mut h = Hierarchy::new(&kernel, 1.0 / 256.0);
        // The root spans the 4 unit walls: u = (k + ½)/4 lands mid-wall on each in leaf order.
        for k in 0..4 {
            let (ord, s, p) = h.point(0, (k as f64 + 0.5) / 4.0);
            assert_eq!(ord, h.leaf_edge[k] as usize);
            let mid = 0.5 * (h.surfaces.a[ord] + h.surfaces.b[ord]);
            assert!(p.distance(mid) < 1e-12, "{p} vs {mid}");
            assert!(h.holds(0, ord, s));
            assert!(kernel.scene().point(s).position.distance(p) < 1e-9);
        }
        // An element halves on demand, its halves hold their own parameters only.
        let leaf = h.edge_node[0];
        assert!(h.splittable(leaf));
        let [l, r] = h.children(leaf);
        assert_eq!(h.children(leaf), [l, r], "halved once");
        let (s0, s1) = (h.surfaces.s0[0], h.surfaces.s1[0]);
        let mid = 0.5 * (s0 + s1);
        assert!(h.holds(l, 0, s0) && !h.holds(l, 0, mid));
        assert!(h.holds(r, 0, mid) && !h.holds(r, 0, s0));
        assert_eq!(h.nodes[l as usize].parent, leaf);
    }
}
