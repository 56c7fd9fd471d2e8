//! The surface edges nearest a point, by a tree of boxes over them: what the labeller asks for
//! each cell that moves, in about `log n` steps rather than one distance per edge.

use flatland_geom::DVec2;

/// Edges per leaf of the tree.
const LEAF: usize = 4;

/// A node of [`NearestEdges`]: the bounding box of its edges, and either its leaf's ranks or
/// its two children.
#[derive(Clone, Debug)]
struct Node {
    lo: DVec2,
    hi: DVec2,
    /// Leaf: its ranks are `order[first..first + count]`; inner: its children are
    /// `nodes[first]` and `nodes[first + 1]`, and `count` is 0.
    first: u32,
    count: u32,
}

/// The edges of a scene by rank (their end points), with a median-split tree of boxes.
#[derive(Clone, Debug)]
pub(crate) struct NearestEdges {
    edges: Vec<(DVec2, DVec2)>,
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// Box distances within this of a bound still count: rounding of the distances (a millionth
    /// of the edges' extent, far above it) cannot make the search skip an edge it must find.
    margin: f64,
}

impl NearestEdges {
    pub(crate) fn new(edges: Vec<(DVec2, DVec2)>) -> NearestEdges {
        let (lo, hi) = bounds(&edges, 0..edges.len() as u32);
        let extent = (hi - lo).max_element();
        let mut index = NearestEdges {
            order: (0..edges.len() as u32).collect(),
            edges,
            nodes: Vec::new(),
            margin: if extent.is_finite() {
                1e-6 * extent
            } else {
                0.0
            },
        };
        if !index.edges.is_empty() {
            index.nodes.push(Node {
                lo,
                hi,
                first: 0,
                count: 0,
            });
            index.split(0, 0, index.edges.len());
        }
        index
    }

    /// Makes node `node` (over `order[first..end]`) a leaf, or halves it at the median of the
    /// edges' midpoints along its longer side and appends its children.
    fn split(&mut self, node: usize, first: usize, end: usize) {
        if end - first <= LEAF {
            self.nodes[node].first = first as u32;
            self.nodes[node].count = (end - first) as u32;
            return;
        }
        let Node { lo, hi, .. } = self.nodes[node];
        let axis = usize::from(hi.y - lo.y > hi.x - lo.x);
        let edges = &self.edges;
        let middle = |r: u32| {
            let (a, b) = edges[r as usize];
            (a + b)[axis]
        };
        let half = (first + end) / 2;
        self.order[first..end].select_nth_unstable_by(half - first, |&p, &q| {
            middle(p).total_cmp(&middle(q)).then(p.cmp(&q))
        });
        let children = self.nodes.len();
        self.nodes[node].first = children as u32;
        for (from, to) in [(first, half), (half, end)] {
            let (lo, hi) = bounds(&self.edges, self.order[from..to].iter().copied());
            self.nodes.push(Node {
                lo,
                hi,
                first: 0,
                count: 0,
            });
        }
        self.split(children, first, half);
        self.split(children + 1, half, end);
    }

    /// The ranks, ascending, whose distance from `p` is at most the least distance plus `tie`:
    /// exactly those a scan of every edge with [`distance_to_segment`] finds.
    pub(crate) fn within_tie(&self, p: DVec2, tie: f64) -> Vec<usize> {
        let mut best = f64::INFINITY;
        let mut found: Vec<(usize, f64)> = Vec::new();
        let mut stack: Vec<u32> = Vec::new();
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            // `best` only falls, so a box beyond it now stays beyond it.
            if box_distance(p, node.lo, node.hi) > best + tie + self.margin {
                continue;
            }
            if node.count == 0 {
                let (l, r) = (node.first, node.first + 1);
                let near = |c: u32| {
                    let c = &self.nodes[c as usize];
                    box_distance(p, c.lo, c.hi)
                };
                // The nearer child last, so it is searched first.
                if near(l) <= near(r) {
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
                }
                continue;
            }
            let leaf = node.first as usize..(node.first + node.count) as usize;
            for &rank in &self.order[leaf] {
                let (a, b) = self.edges[rank as usize];
                let d = distance_to_segment(p, a, b);
                best = best.min(d);
                if d <= best + tie {
                    found.push((rank as usize, d));
                }
            }
        }
        let mut ranks: Vec<usize> = found
            .into_iter()
            .filter(|&(_, d)| d <= best + tie)
            .map(|(r, _)| r)
            .collect();
        ranks.sort_unstable();
        ranks
    }

    /// Each edge by rank: its end points.
    pub(crate) fn edge(&self, rank: usize) -> (DVec2, DVec2) {
        self.edges[rank]
    }
}

/// The bounding box of the edges `ranks`.
fn bounds(edges: &[(DVec2, DVec2)], ranks: impl IntoIterator<Item = u32>) -> (DVec2, DVec2) {
    ranks
        .into_iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), r| {
            let (a, b) = edges[r as usize];
            (lo.min(a).min(b), hi.max(a).max(b))
        })
}

/// The distance from `p` to the box `[lo, hi]` (0 inside).
fn box_distance(p: DVec2, lo: DVec2, hi: DVec2) -> f64 {
    (lo - p).max(p - hi).max(DVec2::ZERO).length()
}

/// The distance from `p` to the segment `[a, b]`.
fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let u = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * u)
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    /// What a scan of every edge finds.
    fn scan(edges: &[(DVec2, DVec2)], p: DVec2, tie: f64) -> Vec<usize> {
        let distance = |&(a, b): &(DVec2, DVec2)| distance_to_segment(p, a, b);
        let nearest = edges.iter().map(distance).fold(f64::INFINITY, f64::min);
        (0..edges.len())
            .filter(|&r| distance(&edges[r]) <= nearest + tie)
            .collect()
    }

    /// Random edges, many sharing end points and lying on one grid (ties), and points on and
    /// near them: the tree finds exactly what the scan finds.
    #[test]
    fn the_tree_finds_what_a_scan_finds() {
        let mut rng = crate::seeds::stream(21, 0);
        for case in 0..200 {
            let n = rng.random_range(1..300);
            let snap = |x: f64| (x * 8.0).round() / 8.0;
            let point = |rng: &mut rand_chacha::ChaCha8Rng| {
                DVec2::new(
                    snap(rng.random_range(-4.0..4.0)),
                    snap(rng.random_range(-4.0..4.0)),
                )
            };
            let mut edges: Vec<(DVec2, DVec2)> = Vec::new();
            while edges.len() < n {
                let a = match edges.last() {
                    Some(&(_, b)) if rng.random_bool(0.5) => b,
                    _ => point(&mut rng),
                };
                let b = point(&mut rng);
                if a != b {
                    edges.push((a, b));
                }
            }
            let index = NearestEdges::new(edges.clone());
            for _ in 0..200 {
                let p = match rng.random_range(0..3) {
                    0 => point(&mut rng),
                    1 => {
                        let (a, b) = edges[rng.random_range(0..n)];
                        a + (b - a) * rng.random::<f64>()
                    }
                    _ => DVec2::new(rng.random_range(-6.0..6.0), rng.random_range(-6.0..6.0)),
                };
                let tie = [0.0, 1e-12, 0.3][rng.random_range(0..3)];
                assert_eq!(
                    index.within_tie(p, tie),
                    scan(&edges, p, tie),
                    "case {case}"
                );
            }
        }
        assert!(
            NearestEdges::new(Vec::new())
                .within_tie(DVec2::ZERO, 0.0)
                .is_empty()
        );
    }
}
