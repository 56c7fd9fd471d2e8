//! Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991) as a representation of ζ.
//!
//! **Elements** are parameter intervals of surface edges; an element's children are its two
//! halves. An element of sender edge i covers an s-interval, one of receiver edge j a t-interval,
//! so a link (p, q) covers the rectangle `[s-interval of p] × [t-interval of q]` of the (s, t)
//! square, and the links of one edge pair partition that pair's rectangle.
//!
//! **Initial linking.** Every ordered pair (i, j) of surface edges that can interact gets one
//! initial link: `i ≠ j`, the sender's source weight E'(i) > 0, the receiver's ρ(j) > 0, and the
//! unoccluded form factor is not zero — i.e. some part of j lies strictly in front of i and some
//! part of i strictly in front of j (either side for a two-sided edge). Occlusion is *not* used to
//! cull initial links (Hanrahan links first and asks visibility per link). Pieces of one straight
//! wall never interact (cos = 0); their floating-point residue is cut by treating a form factor
//! below 1e-9 as no interaction. On the closed box this rule gives 4 · 3 = 12 links.
//! [`count_initial_links`] counts them in O(n²) time and O(1) memory, so the count for a scene
//! subdivided ×1000 (R3) needs no link in memory; building HR there is refused by
//! [`HrParams::max_links`].
//!
//! **Oracle.** For a candidate link (p, q) compute the exact unoccluded transfer
//! `I = ∫_p ∫_q G dx dy` (Hottel's crossed strings on the parts of p and q in front of each other)
//! and the two form factors `F_pq = I / L_p`, `F_qp = I / L_q`. With [`Oracle::Weighted`]
//! (default) both are multiplied by `E'(i) ρ(j) / max E'` — what the link contributes to ζ, the
//! analogue of Hanrahan's brightness-weighted ("BF") refinement; [`Oracle::FormFactor`] uses them
//! as they are. (On `fig3` at 400 links the weighted oracle halves the error: ζ's emitter rows
//! are 100× the floor-weighted ones, and plain F refinement spends most links on rows that hardly
//! count.) If both estimates are below F_ε the link is kept. Otherwise the element seen under the
//! larger form factor is halved (F_pq > F_qp means q looks larger from p: split q; a tie splits
//! q), unless it is shorter than twice the minimum length, in which case the other one is halved;
//! if neither can be, the link is kept. Like Hanrahan's, the oracle ignores occlusion and casts
//! no ray (so shadowed regions refine like lit ones; [`HrStats::zero_links`] counts the links
//! found wholly blocked). The link count for a given F_ε is therefore found without rays, and the
//! settings giving a target count by bisection on log F_ε ([`f_eps_for_budget`],
//! [`hr_params_for_budget`]).
//!
//! **Link value.** Each kept link (with I > 0) is one basis function holding the mean ζ over its
//! rectangle, estimated from `rays_per_link` kernel evaluations (default 20, as the paper
//! compares) at Latin-hypercube points of the rectangle. [`LinkEstimate::FormFactorVisibility`]
//! (default, Hanrahan's form factor times visibility) uses
//! `E'(i) ρ(j) · I / (L_p L_q) · V̂`, with `V̂ = Σ G V / Σ G` over the rays (1 if no ray hit the
//! mutually facing part); [`LinkEstimate::SampleMean`] uses the plain mean of ζ over the rays.
//! Sub-element pairs that cannot interact are empty leaves (ζ̃ = 0, no rays, not counted).
//!
//! **Evaluation** of ζ̃(s, t): binary search of the sender and receiver edges, binary search of
//! the receiver among the sender's linked edges, then a descent of that pair's refinement tree
//! (depth ≤ 2 log₂(edge length / min length)).

use crate::{BaselineError, BaselineRun, seeds};
use flatland_geom::{Kernel, PairClass};
use flatland_solve::{
    KernelRectangle, Mesh, RectangleOperator, Representation, SolveError, SolveParams, Stop,
    TransferOperator, inverse_source_weights,
};
use glam::DVec2;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::time::Instant;

/// A form factor below this is numerical residue (pieces of one straight wall), not transfer.
const INTERACTION_FLOOR: f64 = 1e-9;

/// How a link's mean ζ is estimated from its rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum LinkEstimate {
    /// Exact unoccluded mean times a G-weighted visible fraction from the rays (Hanrahan's
    /// form factor × visibility). Exact for unoccluded links.
    FormFactorVisibility,
    /// Plain mean of ζ over the rays.
    SampleMean,
}

/// What the refinement oracle compares with F_ε.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Oracle {
    /// The unoccluded form factors `F_pq`, `F_qp` (Hanrahan's F refinement).
    FormFactor,
    /// The form factors times `E'(i) ρ(j) / max E'`: the transfer the link carries into ζ,
    /// the analogue of Hanrahan's brightness-weighted ("BF") refinement for the target ζ, whose
    /// emitter rows are 100× the others'.
    Weighted,
}

/// Settings of hierarchical radiosity.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HrParams {
    /// Form-factor threshold F_ε of the oracle, > 0. Smaller refines more.
    pub f_eps: f64,
    /// Minimum element length as a fraction of the total surface length L, in (0, 1).
    pub min_length: f64,
    /// Rays per final link (default 20, the paper's comparison).
    pub rays_per_link: usize,
    /// What the oracle compares with F_ε.
    pub oracle: Oracle,
    /// How a link's value is estimated from its rays.
    pub estimate: LinkEstimate,
    /// Refuse to build more links than this (the ×1000 scene needs ~10⁷ initial links).
    pub max_links: usize,
}

impl Default for HrParams {
    fn default() -> Self {
        HrParams {
            f_eps: 0.05,
            min_length: 1.0 / 1024.0,
            rays_per_link: 20,
            oracle: Oracle::Weighted,
            estimate: LinkEstimate::FormFactorVisibility,
            max_links: 2_000_000,
        }
    }
}

impl HrParams {
    /// The one place these values are checked.
    pub fn check(&self) -> Result<(), BaselineError> {
        if !(self.f_eps.is_finite() && self.f_eps > 0.0) {
            return Err(BaselineError::InvalidParameter {
                name: "f_eps",
                value: self.f_eps.to_string(),
                valid: "positive and finite",
            });
        }
        if !(self.min_length > 0.0 && self.min_length < 1.0) {
            return Err(BaselineError::InvalidParameter {
                name: "min_length",
                value: self.min_length.to_string(),
                valid: "a fraction of the total surface length in (0, 1)",
            });
        }
        if self.rays_per_link == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "rays_per_link",
                value: self.rays_per_link.to_string(),
                valid: "at least 1",
            });
        }
        if self.max_links == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "max_links",
                value: self.max_links.to_string(),
                valid: "at least 1",
            });
        }
        Ok(())
    }
}

/// What one HR build did.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HrStats {
    /// The F_ε used.
    pub f_eps: f64,
    /// The minimum element length used, as a fraction of L.
    pub min_length: f64,
    /// Initial links (ordered surface-edge pairs that can interact).
    pub initial_links: usize,
    /// Final links with transfer: the basis functions.
    pub links: usize,
    /// Of those, links whose every ray was blocked (value 0, still a link).
    pub zero_links: usize,
    /// Rays cast (`links · rays_per_link`).
    pub rays: u64,
    /// Refinement-tree nodes stored.
    pub nodes: usize,
}

/// One final link, as exported for plots and checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HrLink {
    /// Sender edge (index into `Scene::edges`).
    pub sender: usize,
    /// Receiver edge (index into `Scene::edges`).
    pub receiver: usize,
    /// The sender element's s-interval `[s0, s1)`.
    pub s: [f64; 2],
    /// The receiver element's t-interval `[t0, t1)`.
    pub t: [f64; 2],
    /// The stored mean ζ.
    pub value: f64,
}

/// Hierarchical-radiosity approximation of ζ: a refinement tree per linked edge pair.
#[derive(Clone, Debug)]
pub struct HierarchicalRadiosity {
    surfaces: Surfaces,
    /// `pairs[offsets[i]..offsets[i + 1]]` are sender ordinal i's (receiver ordinal, root node),
    /// sorted by receiver.
    offsets: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    nodes: Vec<Node>,
    stats: HrStats,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Node {
    /// A link: its mean ζ.
    Leaf(f64),
    /// A sub-rectangle where the elements cannot interact.
    Empty,
    /// Halved: children at `first` (lower half) and `first + 1`.
    Split { sender: bool, first: u32 },
}

/// The surface edges in parameter order, with what refinement needs of each.
#[derive(Clone, Debug)]
struct Surfaces {
    edge: Vec<usize>,
    s0: Vec<f64>,
    s1: Vec<f64>,
    a: Vec<DVec2>,
    b: Vec<DVec2>,
    normal: Vec<DVec2>,
    two_sided: Vec<bool>,
    reflectance: Vec<f64>,
    source_weight: Vec<f64>,
    total_length: f64,
}

impl Surfaces {
    fn new(kernel: &Kernel) -> Surfaces {
        let scene = kernel.scene();
        let n = scene.surface_edges().len();
        let mut out = Surfaces {
            edge: Vec::with_capacity(n),
            s0: Vec::with_capacity(n),
            s1: Vec::with_capacity(n),
            a: Vec::with_capacity(n),
            b: Vec::with_capacity(n),
            normal: Vec::with_capacity(n),
            two_sided: Vec::with_capacity(n),
            reflectance: Vec::with_capacity(n),
            source_weight: Vec::with_capacity(n),
            total_length: scene.total_length(),
        };
        for &e in scene.surface_edges() {
            let edge = &scene.edges()[e];
            let (s0, s1) = scene
                .edge_param_range(e)
                .expect("a surface edge has a parameter range");
            out.edge.push(e);
            out.s0.push(s0);
            out.s1.push(s1);
            out.a.push(edge.a);
            out.b.push(edge.b);
            out.normal.push(edge.normal());
            out.two_sided.push(edge.two_sided);
            out.reflectance.push(edge.reflectance);
            out.source_weight.push(kernel.source_weight(e));
        }
        out
    }

    fn len(&self) -> usize {
        self.edge.len()
    }

    /// The ordinal of the surface edge whose `[s0, s1)` holds `s`.
    fn locate(&self, s: f64) -> Option<usize> {
        let k = self.s0.partition_point(|&s0| s0 <= s);
        (k > 0 && s < self.s1[k - 1]).then(|| k - 1)
    }

    fn whole(&self, i: usize) -> Elem {
        Elem {
            ord: i,
            s0: self.s0[i],
            s1: self.s1[i],
            a: self.a[i],
            b: self.b[i],
        }
    }

    /// Whether ordered pair (i, j) gets an initial link, and its unoccluded transfer.
    fn initial(&self, i: usize, j: usize) -> Option<f64> {
        if i == j || self.source_weight[i] <= 0.0 || self.reflectance[j] <= 0.0 {
            return None;
        }
        let transfer = self.transfer(&self.whole(i), &self.whole(j));
        interacts(transfer, &self.whole(i), &self.whole(j)).then_some(transfer)
    }

    /// `∫_p ∫_q G dx dy` without occlusion, G = cos cos / (2r).
    fn transfer(&self, p: &Elem, q: &Elem) -> f64 {
        let (np, nq) = (self.normal[p.ord], self.normal[q.ord]);
        let mut total = 0.0;
        for &sp in sides(self.two_sided[p.ord]) {
            // cos_x > 0 ⇔ y strictly in front of p's line.
            let Some(qc) = clip(q.a, q.b, sp * np, p.a) else {
                continue;
            };
            for &sq in sides(self.two_sided[q.ord]) {
                // cos_y > 0 ⇔ x strictly in front of q's line.
                let Some(pc) = clip(p.a, p.b, sq * nq, q.a) else {
                    continue;
                };
                total += crossed_strings(pc, qc);
            }
        }
        total
    }
}

/// An element: a parameter interval of a surface edge and its end points.
#[derive(Clone, Copy, Debug)]
struct Elem {
    ord: usize,
    s0: f64,
    s1: f64,
    a: DVec2,
    b: DVec2,
}

impl Elem {
    fn length(&self) -> f64 {
        (self.b - self.a).length()
    }

    fn halves(&self) -> [Elem; 2] {
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

fn interacts(transfer: f64, p: &Elem, q: &Elem) -> bool {
    transfer / p.length().min(q.length()) > INTERACTION_FLOOR
}

fn sides(two_sided: bool) -> &'static [f64] {
    if two_sided { &[1.0, -1.0] } else { &[1.0] }
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

/// A link waiting for its rays.
#[derive(Clone, Copy, Debug)]
struct Pending {
    slot: u32,
    p: Elem,
    q: Elem,
    transfer: f64,
}

/// The ray-free refinement: builds the trees (or only counts links, with a cap).
struct Refiner<'a> {
    surfaces: &'a Surfaces,
    f_eps: f64,
    min_len: f64,
    /// Multiplies `E'(i) ρ(j)` into the oracle's estimate; `None` for plain form factors.
    weight_scale: Option<f64>,
    store: bool,
    cap: usize,
    links: usize,
    nodes: Vec<Node>,
    pending: Vec<Pending>,
}

impl<'a> Refiner<'a> {
    fn new(surfaces: &'a Surfaces, params: &HrParams, store: bool, cap: usize) -> Self {
        Refiner {
            surfaces,
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
            store,
            cap,
            links: 0,
            nodes: Vec::new(),
            pending: Vec::new(),
        }
    }

    fn over_cap(&self) -> bool {
        self.links > self.cap
    }

    /// Refines the initial link (i, j); returns its root slot when storing.
    fn link_pair(&mut self, i: usize, j: usize, transfer: f64) -> u32 {
        let slot = self.alloc(1);
        self.refine(
            slot,
            self.surfaces.whole(i),
            self.surfaces.whole(j),
            transfer,
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
        let (lp, lq) = (p.length(), q.length());
        let weight = self.weight_scale.map_or(1.0, |scale| {
            scale * self.surfaces.source_weight[p.ord] * self.surfaces.reflectance[q.ord]
        });
        let (f_pq, f_qp) = (weight * transfer / lp, weight * transfer / lq);
        let (can_p, can_q) = (lp >= 2.0 * self.min_len, lq >= 2.0 * self.min_len);
        let split_sender = if f_pq.max(f_qp) < self.f_eps {
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
        };
        match split_sender {
            None => {
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
            Some(sender) => {
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
    }
}

/// The ordered surface-edge pairs HR links initially (see the module docs for the rule).
///
/// O(n²) time over the n surface edges, in parallel, and no memory per link: on `fig3`
/// subdivided ×1000 this is the paper's "10⁶ default basis functions" (R3).
pub fn count_initial_links(kernel: &Kernel) -> u64 {
    let surfaces = Surfaces::new(kernel);
    let n = surfaces.len();
    (0..n)
        .into_par_iter()
        .map(|i| (0..n).filter(|&j| surfaces.initial(i, j).is_some()).count() as u64)
        .sum()
}

/// Links HR would build at `params.f_eps`, found without rays; `None` when more than `cap`.
fn count_links(surfaces: &Surfaces, params: &HrParams, cap: usize) -> Option<usize> {
    let mut refiner = Refiner::new(surfaces, params, false, cap);
    for i in 0..surfaces.len() {
        for j in 0..surfaces.len() {
            if let Some(t) = surfaces.initial(i, j) {
                refiner.link_pair(i, j, t);
                if refiner.over_cap() {
                    return None;
                }
            }
        }
    }
    Some(refiner.links)
}

/// The F_ε whose link count is closest to `budget`, and that count (bisection on log F_ε; the
/// count is monotone in F_ε because a smaller threshold only refines further). When even the
/// initial linking exceeds `budget`, that is the answer (F_ε above every form factor).
pub fn f_eps_for_budget(
    kernel: &Kernel,
    budget: usize,
    params: &HrParams,
) -> Result<(f64, usize), BaselineError> {
    params.check()?;
    let surfaces = Surfaces::new(kernel);
    search_f_eps(&surfaces, budget, params)
}

fn search_f_eps(
    surfaces: &Surfaces,
    budget: usize,
    params: &HrParams,
) -> Result<(f64, usize), BaselineError> {
    let cap = budget.saturating_mul(8).max(64).min(params.max_links);
    let count = |f_eps: f64| count_links(surfaces, &HrParams { f_eps, ..*params }, cap);
    // Form factors never exceed 1: above it no link is refined.
    let mut hi = 1.5;
    let hi_count = count(hi).ok_or_else(|| too_many_links(params))?;
    if hi_count >= budget {
        return Ok((hi, hi_count));
    }
    let (mut best, mut best_count) = (hi, hi_count);
    let mut lo = 1e-12;
    for _ in 0..80 {
        let mid = (lo * hi).sqrt();
        match count(mid) {
            Some(c) => {
                if c.abs_diff(budget) < best_count.abs_diff(budget)
                    || (c.abs_diff(budget) == best_count.abs_diff(budget) && c < best_count)
                {
                    (best, best_count) = (mid, c);
                }
                if c == budget {
                    break;
                }
                if c > budget { lo = mid } else { hi = mid }
            }
            None => lo = mid,
        }
        if hi / lo < 1.0 + 1e-9 {
            break;
        }
    }
    Ok((best, best_count))
}

/// How many times [`hr_params_for_budget`] doubles the minimum length.
const MIN_LENGTH_DOUBLINGS: u32 = 6;

/// `params` with F_ε and the minimum length chosen so the link count is as close to `budget` as
/// HR can get, and that count.
///
/// Why both: F_ε alone moves the count in jumps. Two elements meeting at a corner have a form
/// factor that does not shrink when both are halved (≈ 0.29 for a right angle), so once F_ε
/// drops below it every corner refines down to the minimum length at once — on a symmetric room
/// that is a jump of over a hundred links. So F_ε is searched ([`f_eps_for_budget`]) for the
/// minimum lengths `params.min_length · 2^k`, `k = 0..=6` (while below 1), finest first, and the
/// first within 5 % of `budget` wins: a finer minimum length resolves the `1/r` corners, which
/// dominate the L2 error (measured on `fig3`, `maze`, `corners`: the finest candidate within
/// tolerance was best or within 10 % of best). If none is within 5 %, the closest count wins.
pub fn hr_params_for_budget(
    kernel: &Kernel,
    budget: usize,
    params: &HrParams,
) -> Result<(HrParams, usize), BaselineError> {
    params.check()?;
    let surfaces = Surfaces::new(kernel);
    let tolerance = (budget / 20).max(1);
    let mut best: Option<(HrParams, usize)> = None;
    for k in 0..=MIN_LENGTH_DOUBLINGS {
        let min_length = params.min_length * f64::from(1u32 << k);
        if min_length >= 1.0 {
            break;
        }
        let candidate = HrParams {
            min_length,
            ..*params
        };
        let (f_eps, count) = search_f_eps(&surfaces, budget, &candidate)?;
        if best.is_none_or(|(_, c)| count.abs_diff(budget) < c.abs_diff(budget)) {
            best = Some((HrParams { f_eps, ..candidate }, count));
        }
        if count.abs_diff(budget) <= tolerance {
            break;
        }
    }
    Ok(best.expect("the first minimum length is below 1 (checked)"))
}

fn too_many_links(params: &HrParams) -> BaselineError {
    BaselineError::InvalidParameter {
        name: "max_links",
        value: params.max_links.to_string(),
        valid: "at least the number of links HR needs (the initial linking alone exceeds it)",
    }
}

impl HierarchicalRadiosity {
    /// Refines at `params.f_eps`, then casts `rays_per_link` rays per link (in parallel,
    /// deterministic: each link's rays come from its own seed stream).
    pub fn build(
        kernel: &Kernel,
        params: &HrParams,
        seed: u64,
    ) -> Result<HierarchicalRadiosity, BaselineError> {
        params.check()?;
        let surfaces = Surfaces::new(kernel);
        let n = surfaces.len();
        let mut refiner = Refiner::new(&surfaces, params, true, params.max_links);
        let mut offsets = Vec::with_capacity(n + 1);
        let mut pairs = Vec::new();
        let mut initial_links = 0;
        offsets.push(0u32);
        for i in 0..n {
            for j in 0..n {
                if let Some(t) = surfaces.initial(i, j) {
                    initial_links += 1;
                    if initial_links > params.max_links {
                        return Err(too_many_links(params));
                    }
                    let root = refiner.link_pair(i, j, t);
                    pairs.push((j as u32, root));
                }
            }
            offsets.push(pairs.len() as u32);
        }
        if refiner.over_cap() {
            return Err(too_many_links(params));
        }
        let Refiner {
            mut nodes,
            pending,
            links,
            ..
        } = refiner;

        let values: Vec<(f64, u64)> = pending
            .par_iter()
            .enumerate()
            .map(|(k, link)| estimate(kernel, &surfaces, link, params, seeds::item(seed, k as u64)))
            .collect();
        let mut rays = 0;
        let mut zero_links = 0;
        for (link, &(value, r)) in pending.iter().zip(&values) {
            nodes[link.slot as usize] = Node::Leaf(value);
            rays += r;
            zero_links += usize::from(value == 0.0);
        }
        let stats = HrStats {
            f_eps: params.f_eps,
            min_length: params.min_length,
            initial_links,
            links,
            zero_links,
            rays,
            nodes: nodes.len(),
        };
        Ok(HierarchicalRadiosity {
            surfaces,
            offsets,
            pairs,
            nodes,
            stats,
        })
    }

    /// What the build did.
    pub fn stats(&self) -> &HrStats {
        &self.stats
    }

    /// Every final link with its rectangle and value, by traversing the trees (for plots and
    /// checks; the representation itself stores only the trees).
    pub fn links(&self) -> Vec<HrLink> {
        let mut out = Vec::with_capacity(self.stats.links);
        for i in 0..self.surfaces.len() {
            for &(j, root) in &self.pairs[self.offsets[i] as usize..self.offsets[i + 1] as usize] {
                let j = j as usize;
                let s = [self.surfaces.s0[i], self.surfaces.s1[i]];
                let t = [self.surfaces.s0[j], self.surfaces.s1[j]];
                self.collect(root, (i, j), s, t, &mut out);
            }
        }
        out
    }

    fn collect(
        &self,
        slot: u32,
        ij: (usize, usize),
        s: [f64; 2],
        t: [f64; 2],
        out: &mut Vec<HrLink>,
    ) {
        match self.nodes[slot as usize] {
            Node::Leaf(value) => out.push(HrLink {
                sender: self.surfaces.edge[ij.0],
                receiver: self.surfaces.edge[ij.1],
                s,
                t,
                value,
            }),
            Node::Empty => {}
            Node::Split {
                sender: true,
                first,
            } => {
                let mid = 0.5 * (s[0] + s[1]);
                self.collect(first, ij, [s[0], mid], t, out);
                self.collect(first + 1, ij, [mid, s[1]], t, out);
            }
            Node::Split {
                sender: false,
                first,
            } => {
                let mid = 0.5 * (t[0] + t[1]);
                self.collect(first, ij, s, [t[0], mid], out);
                self.collect(first + 1, ij, s, [mid, t[1]], out);
            }
        }
    }
}

/// One link's mean ζ from its rays, and the rays cast.
fn estimate(
    kernel: &Kernel,
    surfaces: &Surfaces,
    link: &Pending,
    params: &HrParams,
    seed: u64,
) -> (f64, u64) {
    let n = params.rays_per_link;
    let (p, q) = (&link.p, &link.q);
    let weight = surfaces.source_weight[p.ord] * surfaces.reflectance[q.ord];
    let unoccluded_mean = weight * link.transfer / (p.length() * q.length());
    if params.estimate == LinkEstimate::FormFactorVisibility {
        // Where geometry decides the visibility of the whole edge pair, V̂ needs no ray.
        let mid = kernel.unoccluded((p.s0 + p.s1) / 2.0, (q.s0 + q.s1) / 2.0);
        match kernel.pair_class(mid.sender, mid.receiver) {
            PairClass::Visible => return (unoccluded_mean, 0),
            PairClass::Hidden | PairClass::Zero => return (0.0, 0),
            PairClass::Varies => {}
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Latin hypercube: one ray per s-stratum and per t-stratum.
    let mut perm: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        perm.swap(k, rng.random_range(0..=k));
    }
    let inside =
        |lo: f64, hi: f64, u: f64| (lo + (hi - lo) * u).clamp(lo, f64::from_bits(hi.to_bits() - 1));
    let (mut sum_g, mut sum_gv, mut sum_zeta) = (0.0, 0.0, 0.0);
    let mut rays = 0;
    for (k, &pk) in perm.iter().enumerate() {
        let s = inside(p.s0, p.s1, (k as f64 + rng.random::<f64>()) / n as f64);
        let t = inside(q.s0, q.s1, (pk as f64 + rng.random::<f64>()) / n as f64);
        rays += u64::from(kernel.casts_ray(s, t));
        let sample = kernel.eval(s, t);
        sum_g += sample.geometry;
        if sample.visible {
            sum_gv += sample.geometry;
        }
        sum_zeta += sample.zeta;
    }
    let value = match params.estimate {
        LinkEstimate::SampleMean => sum_zeta / n as f64,
        LinkEstimate::FormFactorVisibility => {
            let visible = if sum_g > 0.0 { sum_gv / sum_g } else { 1.0 };
            unoccluded_mean * visible
        }
    };
    (value, rays)
}

/// HR: ζ̃ by descent of a pair's refinement tree; for a solve, its own links, each a rectangle
/// of constant `ζ̃ / E'(sender edge)` (links never straddle an edge), applied by gather and
/// push–pull ([`RectangleOperator`]).
impl Representation for HierarchicalRadiosity {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        let (Some(i), Some(j)) = (self.surfaces.locate(s), self.surfaces.locate(t)) else {
            return 0.0;
        };
        let pairs = &self.pairs[self.offsets[i] as usize..self.offsets[i + 1] as usize];
        let Ok(k) = pairs.binary_search_by_key(&(j as u32), |&(r, _)| r) else {
            return 0.0;
        };
        let (mut s0, mut s1) = (self.surfaces.s0[i], self.surfaces.s1[i]);
        let (mut t0, mut t1) = (self.surfaces.s0[j], self.surfaces.s1[j]);
        let mut slot = pairs[k].1;
        loop {
            match self.nodes[slot as usize] {
                Node::Leaf(value) => return value,
                Node::Empty => return 0.0,
                Node::Split {
                    sender: true,
                    first,
                } => {
                    let mid = 0.5 * (s0 + s1);
                    if s < mid {
                        (s1, slot) = (mid, first)
                    } else {
                        (s0, slot) = (mid, first + 1)
                    }
                }
                Node::Split {
                    sender: false,
                    first,
                } => {
                    let mid = 0.5 * (t0 + t1);
                    if t < mid {
                        (t1, slot) = (mid, first)
                    } else {
                        (t0, slot) = (mid, first + 1)
                    }
                }
            }
        }
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(self.stats.links)
    }

    fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.nodes.len() * size_of::<Node>()
            + self.offsets.len() * size_of::<u32>()
            + self.pairs.len() * size_of::<(u32, u32)>()
            + self.surfaces.len() * 3 * size_of::<f64>() // edge id and parameter range
    }

    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        let inverse = inverse_source_weights(mesh)?;
        if stop() {
            return Err(SolveError::Interrupted);
        }
        let rectangles = self.links().into_iter().map(|link| {
            let sender = mesh.elements()[mesh.element_at(0.5 * (link.s[0] + link.s[1]))];
            KernelRectangle {
                s: link.s,
                t: link.t,
                k: link.value * inverse[sender.mesh_edge],
            }
        });
        Ok(Box::new(RectangleOperator::new(mesh, rectangles)))
    }
}

/// HR at `params.f_eps`. Refuses (error naming `max_links`) a scene whose initial linking alone
/// exceeds `params.max_links`, before building anything.
pub fn run_hr(
    kernel: &Kernel,
    params: &HrParams,
    seed: u64,
) -> Result<BaselineRun<HierarchicalRadiosity>, BaselineError> {
    params.check()?;
    if count_initial_links(kernel) > params.max_links as u64 {
        return Err(too_many_links(params));
    }
    let start = Instant::now();
    let hr = HierarchicalRadiosity::build(kernel, params, seed)?;
    let wall = start.elapsed();
    let rays = hr.stats.rays;
    Ok(BaselineRun::new(hr, rays, wall))
}

/// HR at about `budget` links: the settings of [`hr_params_for_budget`], then [`run_hr`]. The
/// search casts no ray and is not part of the reported wall time; the chosen F_ε and minimum
/// length are in `run.approx.stats()`.
pub fn run_hr_at_budget(
    kernel: &Kernel,
    budget: usize,
    seed: u64,
    params: &HrParams,
) -> Result<BaselineRun<HierarchicalRadiosity>, BaselineError> {
    params.check()?;
    if count_initial_links(kernel) > params.max_links as u64 {
        return Err(too_many_links(params));
    }
    let (tuned, _) = hr_params_for_budget(kernel, budget, params)?;
    run_hr(kernel, &tuned, seed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{blocker_kernel, box_edges, box_kernel, kernel, surface};
    use flatland_solve::{Reference, grid_point, relative_l2};

    #[test]
    fn closed_box_links_twelve_ordered_pairs() {
        // Each wall of a convex room sees the three others, never itself.
        let kernel = box_kernel();
        assert_eq!(count_initial_links(&kernel), 12);
        // F_ε above every form factor: the initial links are the final ones.
        let hr = HierarchicalRadiosity::build(
            &kernel,
            &HrParams {
                f_eps: 2.0,
                ..HrParams::default()
            },
            1,
        )
        .unwrap();
        assert_eq!(hr.stats().initial_links, 12);
        assert_eq!(hr.stats().links, 12);
        assert_eq!(hr.links().len(), 12);
    }

    #[test]
    fn black_receivers_and_back_faces_are_not_linked() {
        let mut edges = box_edges();
        edges[2].reflectance = 0.0; // nothing reflects at the ceiling: no link into it
        assert_eq!(count_initial_links(&kernel(edges)), 12 - 3);
        // Two segments back to back cannot interact; face to face they do, both ways.
        let back = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([0.0, 1.0], [1.0, 1.0], 0.5, 0.0),
        ]);
        assert_eq!(count_initial_links(&back), 0);
        let facing = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([1.0, 1.0], [0.0, 1.0], 0.5, 0.0),
        ]);
        assert_eq!(count_initial_links(&facing), 2);
        // Pieces of one straight wall never link, however they were cut.
        let wall = kernel(vec![
            surface([0.0, 0.0], [0.1, 0.0], 0.5, 1.0),
            surface([0.1, 0.0], [0.7, 0.0], 0.5, 0.0),
            surface([0.7, 0.0], [1.0, 0.0], 0.5, 0.0),
        ]);
        assert_eq!(count_initial_links(&wall), 0);
    }

    #[test]
    fn subdividing_multiplies_initial_links() {
        // 4 walls of m pieces: each piece sees the 3m pieces of the other walls.
        let scene = box_kernel().scene().subdivide(10).unwrap();
        assert_eq!(count_initial_links(&Kernel::new(scene)), 40 * 30);
    }

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
        // and it sees only the floor right of it), and a two-sided post seen from both sides.
        let one_sided = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([0.5, 0.6], [0.5, -0.4], 0.8, 0.0),
        ]);
        check(&one_sided, &[(0, 1), (1, 0)]);
        let mut post = surface([0.5, 0.2], [0.5, 1.0], 0.8, 0.5);
        post.two_sided = true;
        let two_sided = kernel(vec![surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0), post]);
        check(&two_sided, &[(0, 1), (1, 0)]);
    }

    #[test]
    fn error_falls_as_f_eps_falls() {
        let kernel = blocker_kernel();
        let reference = Reference::new(&kernel, 128, 4000, 5);
        for oracle in [Oracle::Weighted, Oracle::FormFactor] {
            let mut last = (f64::INFINITY, 0);
            for f_eps in [0.3, 0.1, 0.03, 0.01] {
                let params = HrParams {
                    f_eps,
                    oracle,
                    ..HrParams::default()
                };
                let hr = HierarchicalRadiosity::build(&kernel, &params, 3).unwrap();
                let e = reference.errors(&hr);
                assert!(
                    e.grid < last.0 && e.heldout.is_finite(),
                    "{params:?}: {e:?} after {last:?}"
                );
                assert!(hr.stats().links > last.1, "{params:?}: links must grow");
                last = (e.grid, hr.stats().links);
            }
        }
    }

    #[test]
    fn fig3_initial_links_scale_with_the_square_of_the_subdivision() {
        // fig3: six surface edges; the three ceiling pieces are collinear (the light among them),
        // so of the 30 ordered pairs 6 cannot interact. Every other pair faces fully, so
        // subdividing by m multiplies the count by m² (R3: ×1000 gives 24 · 10⁶).
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/fig3.ron");
        let scene = flatland_geom::Scene::load(path).unwrap();
        assert_eq!(count_initial_links(&Kernel::new(scene.clone())), 24);
        let scene = scene.subdivide(20).unwrap();
        assert_eq!(count_initial_links(&Kernel::new(scene)), 24 * 400);
    }

    #[test]
    fn reported_error_equals_recomputation_from_the_links() {
        let kernel = blocker_kernel();
        let hr = HierarchicalRadiosity::build(
            &kernel,
            &HrParams {
                f_eps: 0.05,
                ..HrParams::default()
            },
            8,
        )
        .unwrap();
        let links = hr.links();
        assert_eq!(links.len(), hr.stats().links);
        let res = 64;
        let reference = Reference::new(&kernel, res, 300, 2);
        let mut approx = Vec::with_capacity(res * res);
        let mut exact = Vec::with_capacity(res * res);
        for k in 0..res * res {
            let (s, t) = grid_point(res, k);
            // Brute force: the links covering (s, t) — at most one, since they partition.
            let covering: Vec<&HrLink> = links
                .iter()
                .filter(|l| l.s[0] <= s && s < l.s[1] && l.t[0] <= t && t < l.t[1])
                .collect();
            assert!(
                covering.len() <= 1,
                "({s}, {t}) in {} links",
                covering.len()
            );
            let value = covering.first().map_or(0.0, |l| l.value);
            assert_eq!(value, hr.zeta(s, t), "lookup at ({s}, {t})");
            approx.push(value);
            exact.push(kernel.zeta(s, t));
        }
        let by_hand = relative_l2(&approx, &exact);
        let reported = reference.errors(&hr).grid;
        assert!(
            (by_hand - reported).abs() < 1e-12,
            "{by_hand} vs {reported}"
        );
    }

    #[test]
    fn links_cover_every_interacting_point() {
        // Wherever ζ > 0 some link must hold (s, t): the partition has no hole.
        let kernel = blocker_kernel();
        let hr = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 4).unwrap();
        let links = hr.links();
        let mut rng = ChaCha8Rng::seed_from_u64(77);
        for _ in 0..3000 {
            let (s, t) = (rng.random::<f64>(), rng.random::<f64>());
            if kernel.zeta(s, t) > 0.0 {
                let n = links
                    .iter()
                    .filter(|l| l.s[0] <= s && s < l.s[1] && l.t[0] <= t && t < l.t[1])
                    .count();
                assert_eq!(n, 1, "({s}, {t})");
            }
        }
    }

    #[test]
    fn rays_are_counted_and_values_finite() {
        let kernel = blocker_kernel();
        for estimate in [LinkEstimate::FormFactorVisibility, LinkEstimate::SampleMean] {
            let params = HrParams {
                f_eps: 0.02,
                rays_per_link: 7,
                estimate,
                ..HrParams::default()
            };
            let run = run_hr(&kernel, &params, 9).unwrap();
            let stats = *run.approx.stats();
            assert_eq!(run.rays, stats.rays);
            assert_eq!(stats.rays, 7 * stats.links as u64);
            assert_eq!(run.basis_functions, stats.links);
            assert!(
                stats.zero_links > 0,
                "the blocker must hide some links entirely"
            );
            assert!(run.memory_bytes > 0);
            for link in run.approx.links() {
                assert!(link.value.is_finite() && link.value >= 0.0, "{link:?}");
            }
        }
    }

    #[test]
    fn unoccluded_links_are_exact_in_the_default_estimate() {
        // In the empty box no ray is blocked: every link holds exactly E'ρ I / (L_p L_q).
        let kernel = box_kernel();
        let hr = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 1).unwrap();
        let surfaces = Surfaces::new(&kernel);
        for link in hr.links() {
            let ord = |e| surfaces.edge.iter().position(|&x| x == e).unwrap();
            let (i, j) = (ord(link.sender), ord(link.receiver));
            let elem = |o: usize, [u0, u1]: [f64; 2]| {
                let f = |u| {
                    surfaces.a[o]
                        + (surfaces.b[o] - surfaces.a[o])
                            * ((u - surfaces.s0[o]) / (surfaces.s1[o] - surfaces.s0[o]))
                };
                Elem {
                    ord: o,
                    s0: u0,
                    s1: u1,
                    a: f(u0),
                    b: f(u1),
                }
            };
            let (p, q) = (elem(i, link.s), elem(j, link.t));
            let exact =
                surfaces.source_weight[i] * surfaces.reflectance[j] * surfaces.transfer(&p, &q)
                    / (p.length() * q.length());
            assert!(
                (link.value - exact).abs() <= 1e-9 * exact,
                "{link:?} vs {exact}"
            );
        }
    }

    #[test]
    fn budget_search_lands_near_the_target() {
        let kernel = blocker_kernel();
        let params = HrParams::default();
        for budget in [50, 200, 400, 800] {
            let (tuned, count) = hr_params_for_budget(&kernel, budget, &params).unwrap();
            let run = run_hr(&kernel, &tuned, 1).unwrap();
            assert_eq!(run.basis_functions, count);
            // The box is symmetric: counts move in steps of 8 (4 corners, both directions).
            assert!(
                count.abs_diff(budget) <= budget * 3 / 20,
                "budget {budget}: {count} links, {tuned:?}"
            );
            let again = run_hr_at_budget(&kernel, budget, 1, &params).unwrap();
            assert_eq!(again.approx.links(), run.approx.links());
            // With the minimum length fixed the count is monotone in F_eps.
            let (f_eps, fixed) = f_eps_for_budget(&kernel, budget, &params).unwrap();
            let finer = count_links(
                &Surfaces::new(&kernel),
                &HrParams {
                    f_eps: f_eps * 0.5,
                    ..params
                },
                usize::MAX,
            );
            assert!(finer.unwrap() >= fixed);
        }
        // Below the initial linking the initial links are the answer.
        let (_, count) = hr_params_for_budget(&kernel, 3, &params).unwrap();
        assert_eq!(count, 12);
    }

    #[test]
    fn oversized_linking_is_refused_and_bad_params_named() {
        let kernel = box_kernel();
        let err = run_hr(
            &kernel,
            &HrParams {
                max_links: 5,
                ..HrParams::default()
            },
            1,
        )
        .unwrap_err();
        assert!(err.to_string().contains("max_links"), "{err}");
        for (params, name) in [
            (
                HrParams {
                    f_eps: 0.0,
                    ..HrParams::default()
                },
                "f_eps",
            ),
            (
                HrParams {
                    f_eps: f64::NAN,
                    ..HrParams::default()
                },
                "f_eps",
            ),
            (
                HrParams {
                    min_length: 1.0,
                    ..HrParams::default()
                },
                "min_length",
            ),
            (
                HrParams {
                    rays_per_link: 0,
                    ..HrParams::default()
                },
                "rays_per_link",
            ),
        ] {
            let err = HierarchicalRadiosity::build(&kernel, &params, 1).unwrap_err();
            assert!(err.to_string().contains(name), "{err}");
        }
    }

    #[test]
    fn same_seed_same_links() {
        let kernel = blocker_kernel();
        let a = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 5).unwrap();
        let b = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 5).unwrap();
        assert_eq!(a.links(), b.links());
    }
}
