//! A link's oracle: the bound of its form factors (exact for two elements), its value from its
//! rays, and the visibility uncertainty those rays leave.

use super::clusters::{Hierarchy, Node};
use crate::hr::elements::{Elem, interacts};
use flatland_geom::{EdgeId, Kernel, PairClass};
use glam::DVec2;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The unoccluded transfer between two nodes as the oracle sees it: the form factors
/// `F_pq = I / L_p`, `F_qp = I / L_q` (exact for two elements, bounds otherwise).
#[derive(Clone, Copy, Debug)]
pub(super) struct Transfer {
    pub(super) f_pq: f64,
    pub(super) f_qp: f64,
    /// `I = ∫_P ∫_Q G` when both ends are elements (Hottel's crossed strings), else `None`.
    pub(super) exact: Option<f64>,
}

/// What a link's rays found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Estimate {
    /// The mean of `G · V` over `P × Q` (arc length): `ζ̃ = E'(sender) · ρ(receiver) · g`.
    pub(super) g: f64,
    /// In (0, 1]: the chance the link hides visibility it has not seen (0 where geometry
    /// decides it is hidden).
    pub(super) uncertainty: f64,
    /// Rays cast, counted as HR counts them.
    pub(super) rays: u64,
    /// How geometry decides the visibility of the two elements' edges (`None` for a cluster
    /// at an end): their links' children share it, so each edge pair is classified once.
    pub(super) class: Option<PairClass>,
}

/// The form factors between nodes `p` and `q` (distinct, or one cluster with itself), or
/// `None` when they cannot interact: a sender without light or receiver without reflectance,
/// two elements not in front of each other, or a one-sided element with the other node's
/// whole box behind it.
pub(super) fn transfer(h: &Hierarchy, p: u32, q: u32) -> Option<Transfer> {
    let (np, nq) = (&h.nodes[p as usize], &h.nodes[q as usize]);
    if np.max_weight <= 0.0 || nq.max_rho <= 0.0 {
        return None;
    }
    if let (Some(ep), Some(eq)) = (np.element(), nq.element()) {
        if p == q || h.parent_edge[ep.ord] == h.parent_edge[eq.ord] {
            return None; // one straight edge sends nothing to itself
        }
        let i = h.surfaces.transfer(ep, eq);
        return interacts(i, ep, eq).then(|| Transfer {
            f_pq: i / ep.length(),
            f_qp: i / eq.length(),
            exact: Some(i),
        });
    }
    if behind(h, np, nq) || behind(h, nq, np) {
        return None;
    }
    let pairs = h.edges_in(p) * h.edges_in(q);
    if pairs <= EXACT_PAIRS {
        let i = exact_transfer(h, p, q);
        return (i / np.length.min(nq.length) > INTERACTION_FLOOR).then(|| Transfer {
            f_pq: i / np.length,
            f_qp: i / nq.length,
            exact: Some(i),
        });
    }
    Some(Transfer {
        f_pq: form_factor_bound(np, nq),
        f_qp: form_factor_bound(nq, np),
        exact: None,
    })
}

/// Up to this many pairs of edges between two nodes, their unoccluded transfer is summed
/// exactly (crossed strings per pair, some 20 times cheaper than a ray each: about the cost of
/// the link's rays); beyond, the oracle bounds it and the rays estimate it.
const EXACT_PAIRS: usize = 256;

/// A transfer below this, relative to the shorter end, is numerical residue (HR's floor).
const INTERACTION_FLOOR: f64 = 1e-9;

/// `∫_P ∫_Q G` without occlusion, summed over the pairs of their edges (pieces of one parent
/// edge never interact).
fn exact_transfer(h: &Hierarchy, p: u32, q: u32) -> f64 {
    let (ep, eq) = (h.elements_of(p), h.elements_of(q));
    let mut total = 0.0;
    for a in &ep {
        for b in &eq {
            if h.parent_edge[a.ord] != h.parent_edge[b.ord] {
                total += h.surfaces.transfer(a, b);
            }
        }
    }
    total
}

/// Whether `from` is an element and all of `other`'s box lies behind its line (or on it):
/// nothing there faces it.
fn behind(h: &Hierarchy, from: &Node, other: &Node) -> bool {
    let Some(e) = from.element() else {
        return false;
    };
    let n = h.surfaces.normal[e.ord];
    let corners = [
        other.lo,
        other.hi,
        DVec2::new(other.lo.x, other.hi.y),
        DVec2::new(other.hi.x, other.lo.y),
    ];
    corners.iter().all(|c| n.dot(*c - e.a) <= 0.0)
}

/// A bound of `F_pq`, the share of `P`'s light that reaches `Q`, from their boxes alone. From
/// any point x of P: at most what its front half-plane takes (1); at most
/// `Δ/2` where Δ is the angle Q's bounding circle subtends (`(1/2)∫ cos θ dθ ≤ Δ/2`); and at
/// most `|Q| / (2 d)` with d the distance between the boxes (`G ≤ 1 / (2r)`).
fn form_factor_bound(p: &Node, q: &Node) -> f64 {
    let gap = box_distance(p, q);
    let centre = 0.5 * (q.lo + q.hi);
    let radius = 0.5 * q.extent();
    let to_centre = point_box_distance(centre, p);
    let angle = if to_centre > radius {
        (radius / to_centre).asin()
    } else {
        f64::INFINITY
    };
    let length = if gap > 0.0 {
        q.length / (2.0 * gap)
    } else {
        f64::INFINITY
    };
    angle.min(length).min(1.0)
}

fn box_distance(p: &Node, q: &Node) -> f64 {
    let gap = (p.lo - q.hi).max(q.lo - p.hi).max(DVec2::ZERO);
    gap.length()
}

fn point_box_distance(x: DVec2, b: &Node) -> f64 {
    (b.lo - x).max(x - b.hi).max(DVec2::ZERO).length()
}

/// The value and visibility uncertainty of link `(p, q)` from `rays` rays at Latin-hypercube
/// points of `P × Q` (one per stratum of each end, by length), from its own `seed`.
///
/// Where the unoccluded transfer `I` is known (two elements, or few pairs of edges): HR's
/// estimate, the exact unoccluded mean `I / (L_p L_q)` times the `G`-weighted visible fraction
/// of the rays, with no ray where geometry decides two elements' visibility
/// ([`Kernel::pair_class`]). Otherwise the plain mean of `G · V` over the points, which also
/// counts the pairs of edges that face away (`G = 0`).
pub(super) fn estimate(
    kernel: &Kernel,
    h: &Hierarchy,
    (p, q): (u32, u32),
    t: &Transfer,
    (rays, seed): (usize, u64),
    known: Option<PairClass>,
) -> Estimate {
    let (np, nq) = (&h.nodes[p as usize], &h.nodes[q as usize]);
    let mut class = None;
    if let (Some(ep), Some(eq)) = (np.element(), nq.element()) {
        let mean = t.exact.unwrap_or(0.0) / (ep.length() * eq.length());
        let c = known.unwrap_or_else(|| element_class(kernel, ep, eq));
        let decided = |g, uncertainty| Estimate {
            g,
            uncertainty,
            rays: 0,
            class: Some(c),
        };
        match c {
            PairClass::Visible => return decided(mean, 1.0),
            PairClass::Hidden | PairClass::Zero => return decided(0.0, 0.0),
            PairClass::Varies => class = Some(c),
        }
    }
    let sums = sample(kernel, h, (p, q), rays, seed);
    let g = match t.exact {
        // The exact unoccluded mean times the G-weighted visible fraction (1 if no ray faced).
        Some(i) => {
            let visible = if sums.g > 0.0 {
                sums.visible_g / sums.g
            } else {
                1.0
            };
            i / (np.length * nq.length) * visible
        }
        // A few rays' mean of G (singular where the ends come close) can exceed what any
        // two nodes can exchange; the bounds of F_pq and F_qp cap it, so no link makes light.
        None => (sums.visible_g / rays as f64)
            .min(t.f_pq / nq.length)
            .min(t.f_qp / np.length),
    };
    Estimate {
        g,
        uncertainty: uncertainty(sums.facing, sums.seen),
        // Every facing evaluation: for two elements they are HR's rays (their pair varies);
        // a cluster's spans many edge pairs, not classified (that costs more than a ray), so
        // all count — at most what HR's rule would count.
        rays: u64::from(sums.facing),
        class,
    }
}

/// How geometry decides the visibility between the edges of two elements.
fn element_class(kernel: &Kernel, p: &Elem, q: &Elem) -> PairClass {
    let u = kernel.unoccluded(0.5 * (p.s0 + p.s1), 0.5 * (q.s0 + q.s1));
    kernel.pair_class(u.sender, u.receiver)
}

/// The chance that a link whose `facing` rays (those with `G > 0`) saw `seen` times hides
/// something: 1 while a ray saw through or none faced (the kernel varies over the link, or
/// nothing is known), and `1 / (facing + 2)` when every facing ray was blocked — Laplace's rule
/// of succession for the next ray getting through.
pub(super) fn uncertainty(facing: u32, seen: u32) -> f64 {
    if facing > 0 && seen == 0 {
        1.0 / (f64::from(facing) + 2.0)
    } else {
        1.0
    }
}

/// What a link's rays add up to.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    g: f64,
    visible_g: f64,
    facing: u32,
    seen: u32,
}

/// `n` evaluations of `G` and `V` at Latin-hypercube points of `P × Q`.
fn sample(kernel: &Kernel, h: &Hierarchy, (p, q): (u32, u32), n: usize, seed: u64) -> Sums {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut perm: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        perm.swap(k, rng.random_range(0..=k));
    }
    let s = &h.surfaces;
    let mut sums = Sums::default();
    for (k, &pk) in perm.iter().enumerate() {
        let (ox, _, x) = h.point(p, (k as f64 + rng.random::<f64>()) / n as f64);
        let (oy, _, y) = h.point(q, (pk as f64 + rng.random::<f64>()) / n as f64);
        if h.parent_edge[ox] == h.parent_edge[oy] {
            continue;
        }
        let g = geometry((x, s.normal[ox]), (y, s.normal[oy]));
        if g <= 0.0 {
            continue;
        }
        sums.facing += 1;
        sums.g += g;
        let (ex, ey) = (EdgeId::new(s.edge[ox]), EdgeId::new(s.edge[oy]));
        if kernel.visible(x, ex, y, ey) {
            sums.seen += 1;
            sums.visible_g += g;
        }
    }
    sums
}

/// `G(x, y) = cos_x cos_y / (2r)`, each cosine clamped at 0 behind its edge, as the kernel
/// defines it.
fn geometry((x, nx): (DVec2, DVec2), (y, ny): (DVec2, DVec2)) -> f64 {
    let d = y - x;
    let r2 = d.length_squared();
    if r2 <= 0.0 {
        return 0.0;
    }
    let r = r2.sqrt();
    let (cx, cy) = ((nx.dot(d) / r).max(0.0), (-ny.dot(d) / r).max(0.0));
    cx * cy / (2.0 * r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{blocker_kernel, box_kernel};

    #[test]
    fn geometry_matches_the_kernel() {
        let kernel = blocker_kernel();
        let h = Hierarchy::new(&kernel, 1.0 / 256.0);
        let s = &h.surfaces;
        let mut rng = flatland_testkit::rng(4);
        for _ in 0..2000 {
            let (i, j) = (rng.random_range(0..s.len()), rng.random_range(0..s.len()));
            if i == j {
                continue;
            }
            let (ux, uy) = (rng.random::<f64>(), rng.random::<f64>());
            let (sx, sy) = (
                s.s0[i] + (s.s1[i] - s.s0[i]) * ux,
                s.s0[j] + (s.s1[j] - s.s0[j]) * uy,
            );
            let sample = kernel.eval(sx, sy);
            let g = geometry(
                (sample.x.position, s.normal[i]),
                (sample.y.position, s.normal[j]),
            );
            assert!(
                (g - sample.geometry).abs() <= 1e-9 * (1.0 + g),
                "{g} vs {}",
                sample.geometry
            );
        }
    }

    #[test]
    fn bounds_hold_the_exact_form_factors() {
        // Every pair of nodes of the box's hierarchy: the bound of a cluster pair is at least
        // the exact form factor summed over its edge pairs.
        let kernel = box_kernel();
        let h = Hierarchy::new(&kernel, 1.0 / 256.0);
        for p in 0..h.nodes.len() as u32 {
            for q in 0..h.nodes.len() as u32 {
                let exact = exact_transfer(&h, p, q);
                let lp = h.nodes[p as usize].length;
                match transfer(&h, p, q) {
                    Some(t) => assert!(t.f_pq >= exact / lp * (1.0 - 1e-12), "{p} {q}"),
                    None => assert!(exact == 0.0, "{p} {q}: {exact}"),
                }
            }
        }
    }

    /// `∫_P ∫_Q G` over every pair of edges of two nodes (distinct edges only).
    fn exact_transfer(h: &Hierarchy, p: u32, q: u32) -> f64 {
        let edges = |i: u32| -> Vec<usize> {
            (0..h.surfaces.len())
                .filter(|&o| h.holds(i, o, h.surfaces.s0[o]))
                .collect()
        };
        let mut total = 0.0;
        for a in edges(p) {
            for b in edges(q) {
                if a != b {
                    total += h
                        .surfaces
                        .transfer(&h.surfaces.whole(a), &h.surfaces.whole(b));
                }
            }
        }
        total
    }

    #[test]
    fn blocked_rays_lower_the_uncertainty_by_the_rule_of_succession() {
        assert_eq!(uncertainty(0, 0), 1.0);
        assert_eq!(uncertainty(20, 3), 1.0);
        assert_eq!(uncertainty(20, 20), 1.0);
        assert_eq!(uncertainty(18, 0), 0.05);
    }

    #[test]
    fn estimates_of_a_cluster_pair_approach_its_mean() {
        // The root's two halves of the empty box: no occluder, so the mean G · V over them is
        // their exact unoccluded transfer over their lengths.
        let kernel = box_kernel();
        let h = Hierarchy::new(&kernel, 1.0 / 256.0);
        let [a, b] = [1, 2];
        let t = transfer(&h, a, b).unwrap();
        let est = estimate(&kernel, &h, (a, b), &t, (4000, 9), None);
        let exact =
            exact_transfer(&h, a, b) / (h.nodes[a as usize].length * h.nodes[b as usize].length);
        assert!(
            (est.g - exact).abs() < 1e-12 * exact,
            "{} vs {exact}",
            est.g
        );
        assert_eq!(est.uncertainty, 1.0);
        // Here every pair of walls across the halves faces: each evaluation counts.
        assert!(
            est.rays > 3900 && est.rays <= 4000,
            "facing evaluations: {}",
            est.rays
        );
    }
}
