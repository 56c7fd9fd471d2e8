//! Hierarchical radiosity (Hanrahan, Salzman & Aupperle 1991) as a representation of ζ.
//!
//! **Elements** are parameter intervals of surface edges; an element's children are its two
//! halves. An element of sender edge i covers an s-interval, one of receiver edge j a t-interval,
//! so a link (p, q) covers the rectangle `[s-interval of p] × [t-interval of q]` of the (s, t)
//! square, and the links of one edge pair partition that pair's rectangle.
//!
//! **Initial linking** (`linking`). Every ordered pair (i, j) of surface edges that can interact
//! gets one initial link: `i ≠ j`, the sender's source weight E'(i) > 0, the receiver's ρ(j) > 0,
//! and the unoccluded form factor is not zero — i.e. some part of j lies strictly in front of i
//! and some part of i strictly in front of j. Occlusion is
//! *not* used to cull initial links (Hanrahan links first and asks visibility per link). Pieces of
//! one straight wall never interact (cos = 0); their floating-point residue is cut by treating a
//! form factor below 1e-9 as no interaction. On the closed box this rule gives 4 · 3 = 12 links.
//! The initial linking is the least HR can build, and it is O(n²) in the n surface edges (fine
//! up to about 10³ edges: a generated floor plan of 300 edges needs 20 000–30 000).
//! [`count_initial_links`] counts it in O(n²) time and O(1) memory, so the count for a scene
//! subdivided ×1000 (R3) needs no link in memory; a build past [`HrParams::max_links`] is
//! refused, naming what it needs, before anything per link is allocated.
//!
//! **Oracle** (`refine`). For a candidate link (p, q) compute the exact unoccluded transfer
//! `I = ∫_p ∫_q G dx dy` (Hottel's crossed strings on the parts of p and q in front of each
//! other, `elements`) and the two form factors `F_pq = I / L_p`, `F_qp = I / L_q`. With
//! [`Oracle::Weighted`] (default) both are multiplied by `E'(i) ρ(j) / max E'` — what the link
//! contributes to ζ, the analogue of Hanrahan's brightness-weighted ("BF") refinement;
//! [`Oracle::FormFactor`] uses them as they are. (On `fig3` at 400 links the weighted oracle
//! halves the error: ζ's emitter rows are 100× the floor-weighted ones, and plain F refinement
//! spends most links on rows that hardly count.) If both estimates are below F_ε the link is
//! kept. Otherwise the element seen under the larger form factor is halved (F_pq > F_qp means q
//! looks larger from p: split q; a tie splits q), unless it is shorter than twice the minimum
//! length, in which case the other one is halved; if neither can be, the link is kept. Like
//! Hanrahan's, the oracle ignores occlusion and casts no ray (so shadowed regions refine like lit
//! ones; [`HrStats::zero_links`] counts the links found wholly blocked).
//!
//! **Budget** (`budget`). The link count for a given F_ε is therefore found without rays, and
//! the settings giving a target count by bisection on log F_ε ([`f_eps_for_budget`],
//! [`hr_params_for_budget`]). [`run_hr_at_budget`] serves any budget: below the initial linking
//! it builds the initial linking, and where no setting comes within
//! [`budget_tolerance`](crate::budget_tolerance) it builds the nearest count; either way
//! [`BaselineRun::note`](crate::BaselineRun::note) says so.
//!
//! **Link value** (`estimate`). Each kept link (with I > 0) is one basis function holding the
//! mean ζ over its rectangle, estimated from `rays_per_link` kernel evaluations (default 20, as
//! the paper compares) at Latin-hypercube points of the rectangle.
//! [`LinkEstimate::FormFactorVisibility`] (default, Hanrahan's form factor times visibility) uses
//! `E'(i) ρ(j) · I / (L_p L_q) · V̂`, with `V̂ = Σ G V / Σ G` over the rays (1 if no ray hit the
//! mutually facing part); [`LinkEstimate::SampleMean`] uses the plain mean of ζ over the rays.
//! Sub-element pairs that cannot interact are empty leaves (ζ̃ = 0, no rays, not counted).
//!
//! **Evaluation** (`tree`) of ζ̃(s, t): binary search of the sender and receiver edges, binary
//! search of the receiver among the sender's linked edges, then a descent of that pair's
//! refinement tree (depth ≤ 2 log₂(edge length / min length)). **Solving** (`operator`) applies
//! the links as rectangles by gather and push–pull.
//!
//! **Cost.** Refinement and evaluation are linear in the links; the representation keeps about
//! two 16-byte tree nodes per link (a leaf and the split above it, reported by `memory_bytes`),
//! and a build holds about 130 bytes more per link until its rays are cast.

mod budget;
pub(crate) mod elements;
mod estimate;
mod linking;
mod operator;
mod params;
mod refine;
mod run;
mod tree;

pub use budget::{f_eps_for_budget, hr_params_for_budget};
pub use linking::count_initial_links;
pub use params::{HrParams, LinkEstimate, Oracle};
pub use run::{run_hr, run_hr_at_budget};
pub use tree::{HierarchicalRadiosity, HrLink, HrStats};
