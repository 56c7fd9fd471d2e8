//! A bounding-volume hierarchy of boxes: which boxes a region touches (the mesh's junctions),
//! and the tree the visibility sweep walks nearest first.

use glam::DVec2;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Aabb {
    /// Lower-left corner.
    pub lo: DVec2,
    /// Upper-right corner.
    pub hi: DVec2,
}

impl Aabb {
    /// The box that holds nothing (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        lo: DVec2::INFINITY,
        hi: DVec2::NEG_INFINITY,
    };

    /// The box of segment `a–b`.
    pub fn of_segment(a: DVec2, b: DVec2) -> Aabb {
        Aabb {
            lo: a.min(b),
            hi: a.max(b),
        }
    }

    /// This box grown by `margin` on every side.
    pub fn expanded(self, margin: f64) -> Aabb {
        Aabb {
            lo: self.lo - DVec2::splat(margin),
            hi: self.hi + DVec2::splat(margin),
        }
    }

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// Whether the two boxes share a point (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.lo.x <= other.hi.x
            && other.lo.x <= self.hi.x
            && self.lo.y <= other.hi.y
            && other.lo.y <= self.hi.y
    }

    /// The distance from `p` to the nearest point of the box (0 inside).
    pub fn distance_to(&self, p: DVec2) -> f64 {
        (p.clamp(self.lo, self.hi) - p).length()
    }

    /// The corners, counter-clockwise from the lower left.
    pub fn corners(&self) -> [DVec2; 4] {
        [
            self.lo,
            DVec2::new(self.hi.x, self.lo.y),
            self.hi,
            DVec2::new(self.lo.x, self.hi.y),
        ]
    }

    fn center(&self) -> DVec2 {
        0.5 * (self.lo + self.hi)
    }
}

/// What a node holds: two children, or a run of items.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Contents {
    /// Child node indices.
    Inner { left: u32, right: u32 },
    /// `Bvh::items[first..first + count]`.
    Leaf { first: u32, count: u32 },
}

/// One node: the box of everything below it, and what it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node {
    /// The box of every item below.
    pub bounds: Aabb,
    /// Children or items.
    pub contents: Contents,
}

/// A static hierarchy over boxes (items are their indices in the slice it was built from),
/// split at the median of the box centres along the longer side; the same boxes give the same
/// tree on every machine.
#[derive(Clone, Debug)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
    /// The box of each entry of `items`, in the same order.
    boxes: Vec<Aabb>,
}

/// Most items in a leaf: a leaf's items are tested one by one, a node costs a box test.
const LEAF_SIZE: usize = 4;

impl Bvh {
    /// The hierarchy of `boxes`.
    pub fn new(boxes: &[Aabb]) -> Bvh {
        assert!(
            u32::try_from(boxes.len()).is_ok(),
            "a BVH indexes its items with u32"
        );
        let mut items: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len() / LEAF_SIZE + 1);
        if !boxes.is_empty() {
            build(boxes, &mut items, 0, &mut nodes);
        }
        let boxes = items.iter().map(|&i| boxes[i as usize]).collect();
        Bvh {
            nodes,
            items,
            boxes,
        }
    }

    /// The root node, `None` for an empty hierarchy.
    pub fn root(&self) -> Option<u32> {
        (!self.nodes.is_empty()).then_some(0)
    }

    /// Node `index`.
    pub fn node(&self, index: u32) -> &Node {
        &self.nodes[index as usize]
    }

    /// The items of a leaf.
    pub fn items(&self, first: u32, count: u32) -> &[u32] {
        &self.items[first as usize..(first + count) as usize]
    }

    /// Appends to `out` every item whose box overlaps `query` (touching counts), in the tree's
    /// order.
    pub fn overlapping(&self, query: &Aabb, out: &mut Vec<u32>) {
        let Some(root) = self.root() else {
            return;
        };
        let mut stack = vec![root];
        while let Some(index) = stack.pop() {
            let node = self.node(index);
            if !node.bounds.overlaps(query) {
                continue;
            }
            match node.contents {
                Contents::Inner { left, right } => stack.extend([right, left]),
                Contents::Leaf { first, count } => {
                    let range = first as usize..(first + count) as usize;
                    out.extend(
                        self.items[range.clone()]
                            .iter()
                            .zip(&self.boxes[range])
                            .filter(|(_, b)| b.overlaps(query))
                            .map(|(&i, _)| i),
                    );
                }
            }
        }
    }
}

/// Builds the subtree of `items` (offset `first` in the whole item list) and returns its index.
fn build(boxes: &[Aabb], items: &mut [u32], first: usize, nodes: &mut Vec<Node>) -> u32 {
    let bounds = items
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
    let index = nodes.len() as u32;
    nodes.push(Node {
        bounds,
        contents: Contents::Leaf {
            first: first as u32,
            count: items.len() as u32,
        },
    });
    if items.len() <= LEAF_SIZE {
        return index;
    }
    // Split along the longer side of the centres' box, at the median centre (ties by index).
    let centres = items.iter().fold(Aabb::EMPTY, |b, &i| {
        let c = boxes[i as usize].center();
        b.union(Aabb { lo: c, hi: c })
    });
    let extent = centres.hi - centres.lo;
    let key = |i: u32| {
        let c = boxes[i as usize].center();
        if extent.x >= extent.y { c.x } else { c.y }
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |&p, &q| key(p).total_cmp(&key(q)).then(p.cmp(&q)));
    let (low, high) = items.split_at_mut(mid);
    let left = build(boxes, low, first, nodes);
    let right = build(boxes, high, first + mid, nodes);
    nodes[index as usize].contents = Contents::Inner { left, right };
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut rng = flatland_testkit::rng(seed);
        (0..n)
            .map(|_| {
                let a = DVec2::new(rng.random_range(0.0..10.0), rng.random_range(0.0..10.0));
                let d = DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                Aabb::of_segment(a, a + d)
            })
            .collect()
    }

    #[test]
    fn overlap_queries_find_exactly_the_overlapping_boxes() {
        for (n, seed) in [(0, 1), (1, 2), (5, 3), (300, 4), (2000, 5)] {
            let boxes = random_boxes(n, seed);
            let bvh = Bvh::new(&boxes);
            for query in random_boxes(50, seed + 100) {
                let mut found = Vec::new();
                bvh.overlapping(&query, &mut found);
                found.sort_unstable();
                let expected: Vec<u32> = (0..n as u32)
                    .filter(|&i| boxes[i as usize].overlaps(&query))
                    .collect();
                assert_eq!(found, expected, "{n} boxes, query {query:?}");
            }
        }
    }

    #[test]
    fn every_item_sits_in_one_leaf_inside_every_box_above_it() {
        let boxes = random_boxes(777, 9);
        let bvh = Bvh::new(&boxes);
        let mut seen = vec![0; boxes.len()];
        let everything = Aabb {
            lo: DVec2::NEG_INFINITY,
            hi: DVec2::INFINITY,
        };
        let mut stack = vec![(bvh.root().unwrap(), everything)];
        while let Some((index, parent)) = stack.pop() {
            let node = bvh.node(index);
            assert!(parent.lo.cmple(node.bounds.lo).all() && node.bounds.hi.cmple(parent.hi).all());
            match node.contents {
                Contents::Inner { left, right } => {
                    stack.push((left, node.bounds));
                    stack.push((right, node.bounds));
                }
                Contents::Leaf { first, count } => {
                    assert!(count as usize <= LEAF_SIZE);
                    for &i in bvh.items(first, count) {
                        let b = boxes[i as usize];
                        assert_eq!(node.bounds.union(b), node.bounds);
                        seen[i as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
    }

    #[test]
    fn box_distances() {
        let b = Aabb {
            lo: DVec2::new(0.0, 0.0),
            hi: DVec2::new(2.0, 1.0),
        };
        assert_eq!(b.distance_to(DVec2::new(1.0, 0.5)), 0.0);
        assert_eq!(b.distance_to(DVec2::new(5.0, 5.0)), 5.0);
        assert_eq!(b.distance_to(DVec2::new(-1.0, 0.5)), 1.0);
    }
}
