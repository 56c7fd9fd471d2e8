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

    /// Of the edges whose distance from `p` is at most the least distance plus `tie`, the
    /// lowest rank that `prefer` accepts, else the lowest rank (`None` without edges): what a
    /// scan of every edge in rank order with [`distance_to_segment`] picks.
    pub(crate) fn nearest(
        &self,
        p: DVec2,
        tie: f64,
        prefer: impl Fn(usize) -> bool,
    ) -> Option<usize> {
        let mut best = f64::INFINITY;
        self.search(p, best, |_, d| {
            best = best.min(d);
            best
        });
        let bound = best + tie;
        let (mut preferred, mut first): (Option<usize>, Option<usize>) = (None, None);
        self.search(p, bound, |rank, d| {
            if d <= bound {
                let lower = |found: Option<usize>| Some(found.map_or(rank, |f| f.min(rank)));
                first = lower(first);
                if prefer(rank) {
                    preferred = lower(preferred);
                }
            }
            bound
        });
        preferred.or(first)
    }

    /// Visits the edges of the leaves whose boxes lie within `bound` of `p` (the margin
    /// added), the nearer child first; `edge` gets each edge's rank and distance and returns
    /// the bound from then on (it may only fall, so a box beyond it stays beyond it).
    fn search(&self, p: DVec2, mut bound: f64, mut edge: impl FnMut(usize, f64) -> f64) {
        if self.nodes.is_empty() {
            return;
        }
        // A median split of up to 2³² edges is at most 31 levels deep, and each level leaves
        // one node on the stack.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if box_distance(p, node.lo, node.hi) > bound + self.margin {
                continue;
            }
            if node.count == 0 {
                let (l, r) = (node.first, node.first + 1);
                let near = |c: u32| {
                    let c = &self.nodes[c as usize];
                    box_distance(p, c.lo, c.hi)
                };
                // The nearer child on top, so it is searched first.
                let (first, second) = if near(l) <= near(r) { (l, r) } else { (r, l) };
                stack[top] = second;
                stack[top + 1] = first;
                top += 2;
                continue;
            }
            let leaf = node.first as usize..(node.first + node.count) as usize;
            for &rank in &self.order[leaf] {
                let (a, b) = self.edges[rank as usize];
                bound = edge(rank as usize, distance_to_segment(p, a, b));
            }
        }
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

    /// What a scan of every edge picks.
    fn scan(
        edges: &[(DVec2, DVec2)],
        p: DVec2,
        tie: f64,
        prefer: impl Fn(usize) -> bool,
    ) -> Option<usize> {
        let distance = |&(a, b): &(DVec2, DVec2)| distance_to_segment(p, a, b);
        let nearest = edges.iter().map(distance).fold(f64::INFINITY, f64::min);
        let near = |r: &usize| distance(&edges[*r]) <= nearest + tie;
        (0..edges.len())
            .find(|r| near(r) && prefer(*r))
            .or_else(|| (0..edges.len()).find(near))
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
                // Preferring the edges whose fronts face a point, as the labeller does.
                let other = point(&mut rng);
                let faces = |r: usize| {
                    let (a, b) = edges[r];
                    (b - a).perp_dot(other - a) > 0.0
                };
                let picked = index.nearest(p, tie, faces);
                assert_eq!(picked, scan(&edges, p, tie, faces), "case {case}");
                assert_eq!(
                    index.nearest(p, tie, |_| false),
                    scan(&edges, p, tie, |_| false)
                );
            }
        }
        assert_eq!(
            NearestEdges::new(Vec::new()).nearest(DVec2::ZERO, 0.0, |_| true),
            None
        );
    }
}
