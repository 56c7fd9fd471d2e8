//! Spatial index over the cells' positions: a bounding-volume k-d tree with conservative bounds.
//!
//! The tree is built by median splits along the widest axis. Between rebuilds it is kept
//! *conservative*, never exact: when a cell moves, its leaf's box and the boxes above it grow to
//! contain the new position. Each node also keeps a *reach box*, the bounding box of its cells'
//! activation balls `|x − w_c| ≤ R δ_c` (`R² = ln(1/cutoff)`), grown the same way when a cell moves
//! or widens. A cell with a wide support only widens the boxes that hold it, so wide cells at the
//! border do not spoil pruning elsewhere. Boxes never shrink until the next rebuild, so pruning with them never drops a cell that
//! belongs to a result: queries are exact, only their cost degrades, and a periodic rebuild
//! restores it. Results never depend on the tree's shape (callers sort by cell id), so when and
//! how the tree is rebuilt cannot change a network's behaviour.

const LEAF_SIZE: usize = 8;
const NONE: u32 = u32::MAX;

#[derive(Clone, Debug)]
enum Kind {
    Inner { left: u32, right: u32 },
    Leaf { cells: Vec<u32> },
}

#[derive(Clone, Debug)]
struct Node {
    parent: u32,
    /// At least the largest width below (conservative like the boxes).
    max_width: f64,
    kind: Kind,
}

#[derive(Clone, Debug, Default)]
pub(crate) struct Index {
    n: usize,
    /// `R`: a cell reaches `R δ_c` from its centre (infinite without cutoff).
    reach: f64,
    nodes: Vec<Node>,
    /// Per node `4n` values: the position box's lower and upper corners, then the reach box's.
    bounds: Vec<f64>,
    leaf_of: Vec<u32>,
    built_len: usize,
    steps_since_build: u64,
    /// A leaf has grown past `4 · LEAF_SIZE` by insertions.
    overfull: bool,
}

impl Index {
    /// Builds the tree over all cells.
    pub(crate) fn build(n: usize, reach: f64, pos: &[f64], width: &[f64]) -> Index {
        let len = width.len();
        let mut index = Index {
            n,
            reach,
            nodes: Vec::with_capacity(2 * len / LEAF_SIZE + 2),
            bounds: Vec::new(),
            leaf_of: vec![NONE; len],
            built_len: len,
            steps_since_build: 0,
            overfull: false,
        };
        let mut ids: Vec<u32> = (0..len as u32).collect();
        index.build_node(&mut ids, NONE, pos, width);
        index
    }

    fn build_node(&mut self, ids: &mut [u32], parent: u32, pos: &[f64], width: &[f64]) -> u32 {
        let n = self.n;
        let me = self.nodes.len() as u32;
        let mut lo = vec![f64::INFINITY; n];
        let mut hi = vec![f64::NEG_INFINITY; n];
        let mut rlo = vec![f64::INFINITY; n];
        let mut rhi = vec![f64::NEG_INFINITY; n];
        let mut max_width = 0.0f64;
        for &c in ids.iter() {
            max_width = max_width.max(width[c as usize]);
            let p = &pos[c as usize * n..(c as usize + 1) * n];
            let rho = self.rho(width[c as usize]);
            for d in 0..n {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
                rlo[d] = rlo[d].min(p[d] - rho);
                rhi[d] = rhi[d].max(p[d] + rho);
            }
        }
        self.bounds.extend_from_slice(&lo);
        self.bounds.extend_from_slice(&hi);
        self.bounds.extend_from_slice(&rlo);
        self.bounds.extend_from_slice(&rhi);
        self.nodes.push(Node {
            parent,
            max_width,
            kind: Kind::Leaf { cells: Vec::new() },
        });
        if ids.len() <= LEAF_SIZE {
            for &c in ids.iter() {
                self.leaf_of[c as usize] = me;
            }
            self.nodes[me as usize].kind = Kind::Leaf {
                cells: ids.to_vec(),
            };
            return me;
        }
        let axis = (0..n)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        let mid = ids.len() / 2;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            pos[a as usize * n + axis]
                .total_cmp(&pos[b as usize * n + axis])
                .then(a.cmp(&b))
        });
        let (left_ids, right_ids) = ids.split_at_mut(mid);
        let left = self.build_node(left_ids, me, pos, width);
        let right = self.build_node(right_ids, me, pos, width);
        self.nodes[me as usize].kind = Kind::Inner { left, right };
        me
    }

    /// Whether the tree has degraded enough (growth or drift) to be worth rebuilding.
    pub(crate) fn wants_rebuild(&self, len: usize) -> bool {
        self.overfull
            || len > self.built_len + self.built_len / 4 + 8
            || self.steps_since_build > 1_000 + 8 * self.built_len as u64
    }

    pub(crate) fn tick(&mut self) {
        self.steps_since_build += 1;
    }

    fn lo(&self, node: u32) -> &[f64] {
        let k = node as usize * 4 * self.n;
        &self.bounds[k..k + self.n]
    }

    fn hi(&self, node: u32) -> &[f64] {
        let k = node as usize * 4 * self.n;
        &self.bounds[k + self.n..k + 2 * self.n]
    }

    /// The reach-box half width of a cell: `R δ`, padded by a relative 1e-9 so rounding can never
    /// make the box test stricter than the exact activation test it guards.
    fn rho(&self, width: f64) -> f64 {
        self.reach * width * (1.0 + 1e-9)
    }

    /// Whether `x` lies in the node's reach box (some cell below may be active at `x`).
    fn reaches(&self, node: u32, x: &[f64]) -> bool {
        let n = self.n;
        let k = node as usize * 4 * n + 2 * n;
        let (rlo, rhi) = (&self.bounds[k..k + n], &self.bounds[k + n..k + 2 * n]);
        (0..n).all(|d| rlo[d] <= x[d] && x[d] <= rhi[d])
    }

    /// Squared distance from `x` to the node's box.
    #[inline]
    fn box_dist_sq(&self, node: u32, x: &[f64]) -> f64 {
        let (lo, hi) = (self.lo(node), self.hi(node));
        if let (Ok(lo), Ok(hi), Ok(x)) = (
            <&[f64; 4]>::try_from(lo),
            <&[f64; 4]>::try_from(hi),
            <&[f64; 4]>::try_from(x),
        ) {
            // The kernel's dimension, unrolled and branch-free (the tree is walked on every
            // step; this is its inner test).
            return (0..4).map(|d| gap(lo[d], hi[d], x[d])).map(|v| v * v).sum();
        }
        (0..self.n)
            .map(|d| gap(lo[d], hi[d], x[d]))
            .map(|v| v * v)
            .sum()
    }

    /// Grows the position boxes from `c`'s leaf upwards so they contain `p` (its new position).
    pub(crate) fn moved(&mut self, c: usize, p: &[f64]) {
        let n = self.n;
        let mut node = self.leaf_of[c];
        while node != NONE {
            let k = node as usize * 4 * n;
            let mut grew = false;
            for d in 0..n {
                if p[d] < self.bounds[k + d] {
                    self.bounds[k + d] = p[d];
                    grew = true;
                }
                if p[d] > self.bounds[k + n + d] {
                    self.bounds[k + n + d] = p[d];
                    grew = true;
                }
            }
            if !grew {
                break; // every ancestor's box contains this one
            }
            node = self.nodes[node as usize].parent;
        }
    }

    /// Grows the reach boxes from `c`'s leaf upwards to hold the ball of radius `R · width`
    /// around `p` (the cell's position).
    pub(crate) fn reach_to(&mut self, c: usize, p: &[f64], width: f64) {
        let n = self.n;
        let rho = self.rho(width);
        let mut node = self.leaf_of[c];
        while node != NONE {
            let k = node as usize * 4 * n + 2 * n;
            let mut grew = false;
            let nd = &mut self.nodes[node as usize];
            if nd.max_width < width {
                nd.max_width = width;
                grew = true;
            }
            for d in 0..n {
                if p[d] - rho < self.bounds[k + d] {
                    self.bounds[k + d] = p[d] - rho;
                    grew = true;
                }
                if p[d] + rho > self.bounds[k + n + d] {
                    self.bounds[k + n + d] = p[d] + rho;
                    grew = true;
                }
            }
            if !grew {
                break;
            }
            node = self.nodes[node as usize].parent;
        }
    }

    /// Adds the new cell `c` (its id is the next one) to the leaf of cell `near`.
    pub(crate) fn insert(&mut self, c: usize, near: usize, p: &[f64], w: f64) {
        debug_assert_eq!(c, self.leaf_of.len());
        let leaf = self.leaf_of[near];
        self.leaf_of.push(leaf);
        if let Kind::Leaf { cells } = &mut self.nodes[leaf as usize].kind {
            cells.push(c as u32);
            self.overfull |= cells.len() > 4 * LEAF_SIZE;
        }
        self.moved(c, p);
        self.reach_to(c, p, w);
    }

    /// The nearest cell to `x`; ties go to the lowest id (so the answer is the brute-force one).
    pub(crate) fn nearest(&self, x: &[f64], pos: &[f64], stack: &mut Vec<u32>) -> usize {
        let n = self.n;
        let mut best = (f64::INFINITY, usize::MAX);
        stack.clear();
        stack.push(0);
        while let Some(node) = stack.pop() {
            if self.box_dist_sq(node, x) > best.0 {
                continue;
            }
            match &self.nodes[node as usize].kind {
                Kind::Leaf { cells } => {
                    for &c in cells {
                        let c = c as usize;
                        let d2 = dist_sq(&pos[c * n..(c + 1) * n], x);
                        if d2 < best.0 || (d2 == best.0 && c < best.1) {
                            best = (d2, c);
                        }
                    }
                }
                Kind::Inner { left, right } => {
                    let (dl, dr) = (self.box_dist_sq(*left, x), self.box_dist_sq(*right, x));
                    // Push the farther child first so the nearer one is searched first.
                    if dl <= dr {
                        stack.push(*right);
                        stack.push(*left);
                    } else {
                        stack.push(*left);
                        stack.push(*right);
                    }
                }
            }
        }
        best.1
    }

    /// Appends every cell with `|x − w_c|² ≤ reach_sq · δ_c²`, in tree order.
    pub(crate) fn within(
        &self,
        x: &[f64],
        pos: &[f64],
        width: &[f64],
        reach_sq: f64,
        stack: &mut Vec<u32>,
        found: &mut Vec<u32>,
    ) {
        let n = self.n;
        stack.clear();
        stack.push(0);
        while let Some(node) = stack.pop() {
            let nd = &self.nodes[node as usize];
            // Two conservative tests: the reach box (tight where widths vary), and the distance to
            // the position box against the widest cell (tight for round neighbourhoods).
            if !self.reaches(node, x)
                || self.box_dist_sq(node, x) > reach_sq * (nd.max_width * nd.max_width)
            {
                continue;
            }
            match &nd.kind {
                Kind::Leaf { cells } => {
                    for &c in cells {
                        let ci = c as usize;
                        let d2 = dist_sq(&pos[ci * n..(ci + 1) * n], x);
                        if is_active(d2, width[ci], reach_sq) {
                            found.push(c);
                        }
                    }
                }
                Kind::Inner { left, right } => {
                    stack.push(*right);
                    stack.push(*left);
                }
            }
        }
    }

    /// Checks that every cell is in exactly one leaf and that boxes and widths are conservative.
    pub(crate) fn check(&self, pos: &[f64], width: &[f64]) -> Result<(), String> {
        let n = self.n;
        let len = width.len();
        if self.leaf_of.len() != len {
            return Err(format!(
                "index knows {} cells, network has {len}",
                self.leaf_of.len()
            ));
        }
        let mut seen = vec![false; len];
        for (i, nd) in self.nodes.iter().enumerate() {
            if let Kind::Leaf { cells } = &nd.kind {
                for &c in cells {
                    let c = c as usize;
                    if c >= len || seen[c] || self.leaf_of[c] as usize != i {
                        return Err(format!("index: cell {c} misplaced in leaf {i}"));
                    }
                    seen[c] = true;
                    // Every ancestor must bound the cell.
                    let mut node = i as u32;
                    while node != NONE {
                        let p = &pos[c * n..(c + 1) * n];
                        let rho = self.rho(width[c]);
                        let k = node as usize * 4 * n + 2 * n;
                        let in_reach = (0..n).all(|d| {
                            self.bounds[k + d] <= p[d] - rho && p[d] + rho <= self.bounds[k + n + d]
                        });
                        if self.box_dist_sq(node, p) > 0.0
                            || !in_reach
                            || self.nodes[node as usize].max_width < width[c]
                        {
                            return Err(format!("index: node {node} does not bound cell {c}"));
                        }
                        node = self.nodes[node as usize].parent;
                    }
                }
            }
        }
        if let Some(c) = seen.iter().position(|s| !s) {
            return Err(format!("index: cell {c} is in no leaf"));
        }
        Ok(())
    }
}

/// How far `x` lies outside `[lo, hi]` (0 inside).
#[inline]
fn gap(lo: f64, hi: f64, x: f64) -> f64 {
    (lo - x).max(x - hi).max(0.0)
}

/// The activation test shared by the tree and the brute-force path, so both select the same cells.
#[inline]
pub(crate) fn is_active(d2: f64, width: f64, reach_sq: f64) -> bool {
    d2 <= reach_sq * (width * width)
}

#[inline]
pub(crate) fn dist_sq(a: &[f64], b: &[f64]) -> f64 {
    if let (Ok(a), Ok(b)) = (<&[f64; 4]>::try_from(a), <&[f64; 4]>::try_from(b)) {
        // The kernel's dimension, unrolled; summed in the same order, so the same bits.
        return (0..4).map(|d| (a[d] - b[d]) * (a[d] - b[d])).sum();
    }
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}
