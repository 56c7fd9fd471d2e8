//! Hierarchical radiosity with clustering (Smits, Arvo & Greenberg 1994; Sillion 1995) as a
//! representation of ζ: a baseline whose cost grows like the scene, not its square.
//!
//! **Hierarchy** (`clusters`). A binary tree of clusters over the surface edges, split at the
//! median of the longer axis of their centres (a BVH with one whole edge per leaf); below each
//! edge its elements, halved on demand down to `min_length` (a fraction of the mean edge
//! length). Each node keeps its box, its surface length, and the largest E' and ρ of its
//! edges.
//!
//! **Refinement** (`refine`). It starts from one link, the root cluster with itself — there is
//! no initial linking over pairs of edges. A cluster's link with itself is always split, into
//! its children's four links (a straight edge sends nothing to itself, so an edge's link with
//! itself is dropped); any other link (P, Q) is split at the end with the larger extent (box
//! diagonal; the other end when that one cannot be split), and its children's links replace
//! it. Links that cannot interact are never made (`oracle::transfer`). The link with the
//! largest oracle value is split first until the links reach the budget.
//!
//! **Oracle** (`oracle`): transfer estimate × visibility uncertainty,
//! `E'(P) ρ(Q) / max E' · max(F_pq, F_qp) · u` — HR's weighted oracle, with
//! - `F` exact for two elements (Hottel's crossed strings on the parts in front of each other,
//!   as HR), and for a cluster a conservative bound from the boxes: from any point of the
//!   other end at most its front half-plane (1), at most half the angle
//!   the cluster's bounding circle subtends, and at most `|Q| / (2d)` (G ≤ 1/(2r));
//! - `u`, the visibility uncertainty of the link's own rays: 1 while a ray got through or no
//!   ray faced, `1 / (m + 2)` when all `m` facing rays were blocked (Laplace's rule of
//!   succession), 0 where geometry proves two elements hidden.
//!
//! A link's value is capped at its parent link's, so splitting the largest first to a count is
//! refining to a threshold: the parameter rule is HR's (F_ε set by the budget of links), found
//! exactly rather than by bisection, and [`ClusteredStats::f_eps`] reports it.
//!
//! **Link value** (`oracle::estimate`). Each link made casts `rays_per_link` rays (20) at
//! Latin-hypercube points of P × Q, counted as HR counts them ([`Kernel::casts_ray`]). Two
//! elements: HR's estimate, the exact unoccluded mean times the G-weighted visible fraction
//! (no ray where geometry decides the edge pair's visibility). A cluster at either end: the
//! plain mean of `G · V` over the points (isotropic: every receiver in Q gets the same
//! irradiance, times its own ρ). The rays of links refined away are spent too
//! ([`ClusteredStats::links_made`]).
//!
//! **Solving** (`solve`). `K b` is applied matrix-free: `∫ B` of every node pulled up from the
//! mesh's prefix sums through the clusters, each link gathering `g · ∫_P B` into its receiver,
//! and what a node gathered pushed down to the collocation points under it, times their ρ:
//! O(links + nodes + elements) per product, no N × N matrix.
//!
//! [`Kernel::casts_ray`]: flatland_geom::Kernel::casts_ray

mod clusters;
mod oracle;
mod params;
mod refine;
mod represent;
mod run;
mod solve;
mod weights;

pub use params::{ClusteredParams, DEFAULT_LINKS_PER_EDGE};
pub use represent::{ClusteredLink, ClusteredRadiosity, ClusteredStats, LinkEnd};
pub use run::run_clustered;
