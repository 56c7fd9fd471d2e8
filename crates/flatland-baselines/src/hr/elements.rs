//! Elements and their unoccluded transfer: the surface edges in parameter order, halving, and
//! Hottel's crossed strings on the parts of two elements in front of each other.

use flatland_geom::Kernel;
use glam::DVec2;

/// A form factor below this is numerical residue (pieces of one straight wall), not transfer.
const INTERACTION_FLOOR: f64 = 1e-9;

/// The surface edges in parameter order, with what refinement needs of each.
#[derive(Clone, Debug)]
pub(crate) struct Surfaces {
    /// Each one's scene edge, as an index (what [`Surfaces::heap_bytes`] counts).
    pub(crate) edge: Vec<usize>,
    pub(crate) s0: Vec<f64>,
    pub(crate) s1: Vec<f64>,
    pub(crate) a: Vec<DVec2>,
    pub(crate) b: Vec<DVec2>,
    pub(crate) normal: Vec<DVec2>,
    pub(crate) reflectance: Vec<f64>,
    pub(crate) source_weight: Vec<f64>,
    pub(crate) total_length: f64,
}

impl Surfaces {
    pub(crate) fn new(kernel: &Kernel) -> Surfaces {
        let scene = kernel.scene();
        let n = scene.surface_edges().len();
        let mut out = Surfaces {
            edge: Vec::with_capacity(n),
            s0: Vec::with_capacity(n),
            s1: Vec::with_capacity(n),
            a: Vec::with_capacity(n),
            b: Vec::with_capacity(n),
            normal: Vec::with_capacity(n),
            reflectance: Vec::with_capacity(n),
            source_weight: Vec::with_capacity(n),
            total_length: scene.total_length(),
        };
        for &e in scene.surface_edges() {
            let edge = scene.edge(e);
            let (s0, s1) = scene
                .edge_param_range(e)
                .expect("a surface edge has a parameter range");
            out.edge.push(e.index());
            out.s0.push(s0);
            out.s1.push(s1);
            out.a.push(edge.a);
            out.b.push(edge.b);
            out.normal.push(edge.normal());
            out.reflectance.push(edge.reflectance);
            out.source_weight.push(kernel.source_weight(e));
        }
        out
    }

    pub(crate) fn len(&self) -> usize {
        self.edge.len()
    }

    /// Heap bytes of these tables (part of HR's `memory_bytes`).
    pub(crate) fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.len() * (size_of::<usize>() + 5 * size_of::<f64>() + 3 * size_of::<DVec2>())
    }

    /// The ordinal of the surface edge whose `[s0, s1)` holds `s`.
    pub(crate) fn locate(&self, s: f64) -> Option<usize> {
        let k = self.s0.partition_point(|&s0| s0 <= s);
        (k > 0 && s < self.s1[k - 1]).then(|| k - 1)
    }

    pub(crate) fn whole(&self, i: usize) -> Elem {
        Elem {
            ord: i,
            s0: self.s0[i],
            s1: self.s1[i],
            a: self.a[i],
            b: self.b[i],
        }
    }

    /// `∫_p ∫_q G dx dy` without occlusion, G = cos cos / (2r).
    pub(crate) fn transfer(&self, p: &Elem, q: &Elem) -> f64 {
        let (np, nq) = (self.normal[p.ord], self.normal[q.ord]);
        // cos_x > 0 ⇔ y strictly in front of p's line; cos_y > 0 ⇔ x in front of q's.
        let Some(qc) = clip(q.a, q.b, np, p.a) else {
            return 0.0;
        };
        let Some(pc) = clip(p.a, p.b, nq, q.a) else {
            return 0.0;
        };
        crossed_strings(pc, qc)
    }
}

/// An element: a parameter interval of a surface edge and its end points.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Elem {
    pub(crate) ord: usize,
    pub(crate) s0: f64,
    pub(crate) s1: f64,
    pub(crate) a: DVec2,
    pub(crate) b: DVec2,
}

impl Elem {
    pub(crate) fn length(&self) -> f64 {
        (self.b - self.a).length()
    }

    pub(crate) fn halves(&self) -> [Elem; 2] {
        let (mid, m) = (0.5 * (self.s0 + self.s1), 0.5 * (self.a + self.b));
        [
            Elem {
                s1: mid,
                b: m,
                ..*self
            },
            Elem {
                s0: mid,
                a: m,
                ..*self
            },
        ]
    }
}

/// Whether `transfer` between `p` and `q` is real transfer rather than residue.
pub(crate) fn interacts(transfer: f64, p: &Elem, q: &Elem) -> bool {
    transfer / p.length().min(q.length()) > INTERACTION_FLOOR
}

/// The part of segment a–b strictly on the side `n · (z − o) > 0`.
fn clip(a: DVec2, b: DVec2, n: DVec2, o: DVec2) -> Option<(DVec2, DVec2)> {
    let (fa, fb) = (n.dot(a - o), n.dot(b - o));
    match (fa > 0.0, fb > 0.0) {
        (true, true) => Some((a, b)),
        (false, false) => None,
        (true, false) => Some((a, a + (b - a) * (fa / (fa - fb)))),
        (false, true) => Some((a + (b - a) * (fa / (fa - fb)), b)),
    }
}

/// Hottel's crossed strings: `∫∫ G dx dy` for two segments wholly in front of each other,
/// `(crossed − uncrossed) / 2`; the diagonals of the quadrilateral are the longer pair.
fn crossed_strings((a1, a2): (DVec2, DVec2), (b1, b2): (DVec2, DVec2)) -> f64 {
    let one = a1.distance(b2) + a2.distance(b1);
    let other = a1.distance(b1) + a2.distance(b2);
    0.5 * (one - other).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{box_kernel, kernel, surface};

    #[test]
    fn crossed_strings_match_the_kernel_integral() {
        // Mean ζ over an unoccluded edge pair: closed form vs a fine midpoint rule on the kernel.
        let check = |kernel: &Kernel, pairs: &[(usize, usize)]| {
            let surfaces = Surfaces::new(kernel);
            for &(i, j) in pairs {
                let (p, q) = (surfaces.whole(i), surfaces.whole(j));
                let exact =
                    surfaces.source_weight[i] * surfaces.reflectance[j] * surfaces.transfer(&p, &q)
                        / (p.length() * q.length());
                let n = 400;
                let mut sum = 0.0;
                for a in 0..n {
                    for b in 0..n {
                        let s = p.s0 + (p.s1 - p.s0) * (a as f64 + 0.5) / n as f64;
                        let t = q.s0 + (q.s1 - q.s0) * (b as f64 + 0.5) / n as f64;
                        sum += kernel.zeta(s, t);
                    }
                }
                let numeric = sum / (n * n) as f64;
                // Touching edges have a 1/r corner: the midpoint rule converges slowly there.
                assert!(exact > 0.0, "pair ({i},{j})");
                assert!(
                    (numeric - exact).abs() < 5e-3 * exact,
                    "pair ({i},{j}): {numeric} vs {exact}"
                );
            }
        };
        check(&box_kernel(), &[(0, 2), (0, 1), (3, 1)]);
        // Clipping: a one-sided post crossing the floor's line (only its upper half is seen,
        // and it sees only the floor right of it), and a thin post (two faces back to back),
        // each face seen from its side.
        let one_sided = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([0.5, 0.6], [0.5, -0.4], 0.8, 0.0),
        ]);
        check(&one_sided, &[(0, 1), (1, 0)]);
        let thin = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([0.5, 0.2], [0.5, 1.0], 0.8, 0.5),
            surface([0.5, 1.0], [0.5, 0.2], 0.8, 0.5),
        ]);
        check(&thin, &[(0, 1), (1, 0), (0, 2), (2, 0)]);
    }
}
