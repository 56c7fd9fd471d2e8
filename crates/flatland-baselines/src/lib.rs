//! Baselines the SGCS fit is compared against: a uniform grid, hierarchical radiosity (with and
//! without clustering) and a light tracer.
//!
//! Both approximate the same target as the network, ζ(s, t) over `[0, 1)²` (s = sender,
//! t = receiver, docs/ALGORITHM.md §1), and both implement [`Representation`], so
//! [`Reference::errors`](flatland_solve::Reference::errors) measures them exactly as it measures
//! SGCS and [`flatland_solve::solve`] lights a scene with them.
//!
//! - [`UniformGrid`]: a g × g piecewise-constant grid over (s, t); each block holds the mean ζ
//!   of `m` random rays inside it. g² basis functions, g²·m rays.
//! - [`HierarchicalRadiosity`]: Hanrahan, Salzman & Aupperle (1991) in Flatland. Elements are
//!   intervals of surface edges, refined by halving; each final link is one basis function holding
//!   the mean ζ over its (s, t) rectangle. See the `hr` module docs below for the linking rule, the
//!   oracle and the link estimate.
//!
//! The `run_*` functions are what `flatland bench` loops over: each returns a [`BaselineRun`] with
//! the approximation, rays cast, wall time, basis-function count and memory, and a
//! [`BudgetNote`] when the count built is not within [`budget_tolerance`] of the budget asked
//! for (below HR's initial linking, where HR's count jumps, or a grid that is not square).
//!
//! **Rays.** Every kernel evaluation a baseline makes counts as one ray, whether or not the
//! geometry layer needed to trace it (it may skip back-facing or unoccludable pairs): that is the
//! same accounting the SGCS fit uses for its samples.
//!
//! The crate's one job: the methods the learner is compared against, as representations of ζ.
//! It knows the solver and the error measures (`flatland_solve`) but not the learner.
//!
//! ```
//! use flatland_baselines::{HrParams, UniformParams, run_hr_at_budget, run_uniform};
//! use flatland_geom::Kernel;
//! use flatland_solve::Reference;
//!
//! let kernel = Kernel::new(flatland_geom::bundled::scene("fig3")?);
//! let reference = Reference::new(&kernel, 64, 1024, 1);
//! let hr = run_hr_at_budget(&kernel, 100, 7, &HrParams::default())?;
//! let uniform = run_uniform(&kernel, 100, 7, &UniformParams::default())?;
//! assert_eq!(uniform.basis_functions, 100);
//! // At the same budget the adaptive links beat the blind grid.
//! let (hr_error, uniform_error) = (
//!     reference.errors(&hr.approx).grid,
//!     reference.errors(&uniform.approx).grid,
//! );
//! assert!(hr_error < uniform_error, "HR {hr_error}, uniform {uniform_error}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

mod clustered;
mod error;
mod hr;
mod seeds;
#[cfg(test)]
mod solve_tests;
mod tracer;
mod uniform;

pub use error::BaselineError;

pub use clustered::{
    ClusteredLink, ClusteredParams, ClusteredRadiosity, ClusteredStats, DEFAULT_LINKS_PER_EDGE,
    LinkEnd, run_clustered,
};
pub use hr::{
    HierarchicalRadiosity, HrLink, HrParams, HrStats, LinkEstimate, Oracle, count_initial_links,
    f_eps_for_budget, hr_params_for_budget, run_hr, run_hr_at_budget,
};
pub use tracer::{LightTracer, Lighting, PowerBalance, TraceBudget, TraceParams, Traced, trace};
pub use uniform::{BlockValue, UniformGrid, UniformParams, run_uniform};

use flatland_solve::Representation;
use std::fmt;
use std::time::Duration;

/// One baseline run: what `flatland bench` records per method, budget and seed.
#[derive(Clone, Debug)]
pub struct BaselineRun<A> {
    /// The approximation built.
    pub approx: A,
    /// Kernel evaluations (rays) spent building it.
    pub rays: u64,
    /// Wall time of the build (not of any parameter search that chose its settings).
    pub wall: Duration,
    /// Number of basis functions (blocks, links).
    pub basis_functions: usize,
    /// Bytes of the representation.
    pub memory_bytes: usize,
    /// Why `basis_functions` is not the budget asked for, when it is outside
    /// [`budget_tolerance`] of it (`None` for runs without a budget).
    pub note: Option<BudgetNote>,
}

impl<A: Representation> BaselineRun<A> {
    fn new(approx: A, rays: u64, wall: Duration, note: Option<BudgetNote>) -> Self {
        let basis_functions = approx
            .basis_functions()
            .expect("a baseline counts its basis functions");
        let memory_bytes = approx.memory_bytes();
        BaselineRun {
            approx,
            rays,
            wall,
            basis_functions,
            memory_bytes,
            note,
        }
    }
}

/// How far a baseline's basis-function count may be from its budget and still count as met:
/// 5 % of it, at least 1.
#[must_use]
pub fn budget_tolerance(budget: usize) -> usize {
    (budget / 20).max(1)
}

/// Why a run built a count outside [`budget_tolerance`] of the budget asked for. Its text is
/// what `flatland solve` prints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[non_exhaustive]
pub enum BudgetNote {
    /// The budget is below HR's initial linking (one link per interacting surface-edge pair),
    /// the least HR can build; that was built.
    InitialLinking {
        /// Links asked for.
        asked: usize,
        /// Links built: the initial linking.
        built: usize,
    },
    /// The budget is above HR's finest linking (every interacting element pair down to the
    /// minimum length), the most HR can build; that was built.
    Finest {
        /// Links asked for.
        asked: usize,
        /// Links built: the finest linking.
        built: usize,
    },
    /// HR's count jumps past the budget (many equal corners refine at one F_ε): no F_ε and
    /// minimum length comes within tolerance, and the nearest count was built.
    Nearest {
        /// Links asked for.
        asked: usize,
        /// Links built.
        built: usize,
    },
    /// Clustered HR ran out of links to split (every one at the minimum length, or certain)
    /// below the budget; that was built.
    ClusteredFinest {
        /// Links asked for.
        asked: usize,
        /// Links built.
        built: usize,
    },
    /// The uniform grid is g × g: the nearest square to the budget was built.
    Square {
        /// Blocks asked for.
        asked: usize,
        /// Blocks built, g².
        built: usize,
    },
}

impl fmt::Display for BudgetNote {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BudgetNote::InitialLinking { asked, built } => write!(
                f,
                "HR's initial linking needs {} links; built that instead of {}",
                grouped(built),
                grouped(asked)
            ),
            BudgetNote::Finest { asked, built } => write!(
                f,
                "HR's finest linking (every element down to `min_length`) has {} links; built \
                 that instead of {} (a smaller `min_length` allows more)",
                grouped(built),
                grouped(asked)
            ),
            BudgetNote::Nearest { asked, built } => {
                let tolerance = budget_tolerance(asked);
                write!(
                    f,
                    "HR's link count jumps past {} (no F_ε or minimum length gives {}–{} \
                     links); built the nearest, {}",
                    grouped(asked),
                    grouped(asked.saturating_sub(tolerance)),
                    grouped(asked + tolerance),
                    grouped(built)
                )
            }
            BudgetNote::ClusteredFinest { asked, built } => write!(
                f,
                "clustered HR's finest linking (every link at `min_length` or certain) has {} \
                 links; built that instead of {} (a smaller `min_length` allows more)",
                grouped(built),
                grouped(asked)
            ),
            BudgetNote::Square { asked, built } => {
                let g = built.isqrt();
                write!(
                    f,
                    "the uniform grid is g × g blocks: built {} ({g} × {g}) instead of {}",
                    grouped(built),
                    grouped(asked)
                )
            }
        }
    }
}

/// `n` with its thousands grouped by spaces ("25 600"), as the messages print counts.
pub(crate) fn grouped(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// Shared by the tests of both baselines: small scenes built in code, seeded.
#[cfg(test)]
pub(crate) mod test_support {
    use flatland_geom::{Edge, Kernel, Role, Scene};
    use flatland_testkit::rooms;
    use glam::DVec2;

    /// A surface edge from `a` to `b` (front = left of a→b).
    pub fn surface(a: [f64; 2], b: [f64; 2], reflectance: f64, emission: f64) -> Edge {
        Edge {
            a: DVec2::from(a),
            b: DVec2::from(b),
            reflectance,
            emission,
            role: Role::Surface,
            two_sided: false,
        }
    }

    /// The closed unit box, counter-clockwise (facing in), the floor emitting; each wall
    /// reflects differently (0.5, 0.7, 0.6, 0.8 from the floor round).
    pub fn box_edges() -> Vec<Edge> {
        let mut edges = Edge::polygon(&rooms::unit_square(), 0.0);
        for (edge, rho) in edges.iter_mut().zip([0.5, 0.7, 0.6, 0.8]) {
            edge.reflectance = rho;
        }
        edges[0].emission = 1.0;
        edges
    }

    /// The closed unit box.
    pub fn box_kernel() -> Kernel {
        kernel(box_edges())
    }

    /// The unit box with a floating two-sided blocker casting shadows (like the paper's Fig. 3).
    pub fn blocker_kernel() -> Kernel {
        let mut edges = box_edges();
        let [a, b] = rooms::box_blocker();
        edges.push(Edge {
            a,
            b,
            reflectance: 0.5,
            emission: 0.0,
            role: Role::Blocker,
            two_sided: true,
        });
        kernel(edges)
    }

    /// A kernel over `edges` (which must be valid).
    pub fn kernel(edges: Vec<Edge>) -> Kernel {
        Kernel::new(Scene::new(edges).expect("valid test scene"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_grouped_by_thousands() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(400), "400");
        assert_eq!(grouped(1_000), "1 000");
        assert_eq!(grouped(25_600), "25 600");
        assert_eq!(grouped(2_000_000), "2 000 000");
    }

    #[test]
    fn the_tolerance_is_five_percent_and_at_least_one() {
        assert_eq!(budget_tolerance(1), 1);
        assert_eq!(budget_tolerance(50), 2);
        assert_eq!(budget_tolerance(400), 20);
    }
}
