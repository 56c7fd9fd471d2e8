//! The crate's one error type.

use crate::grouped;

/// Everything a baseline can refuse; each message names the limit and what to change.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BaselineError {
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` is {value}, but must be {valid}")]
    InvalidParameter {
        /// The parameter's name as the CLI and files spell it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range in words.
        valid: &'static str,
    },
    /// HR's initial linking alone (the least HR can build) is more than `max_links`.
    #[error(
        "HR's initial linking needs {}{} links (one per ordered pair of the scene's {} surface \
         edges that face each other), more than `max_links` = {}: raise `max_links` or use a \
         scene with fewer surface edges",
        if *complete { "" } else { "at least " },
        grouped(*needed as usize),
        grouped(*surfaces),
        grouped(*max_links)
    )]
    InitialLinkingTooLarge {
        /// Initial links counted (all of them when `complete`).
        needed: u64,
        /// Whether the count ran to the end (it stops once past `max_links`).
        complete: bool,
        /// Surface edges of the scene.
        surfaces: usize,
        /// The limit.
        max_links: usize,
    },
    /// HR's refinement at a given F_ε goes past `max_links`.
    #[error(
        "HR at F_ε = {f_eps} refines past `max_links` = {} links: raise F_ε (fewer links) or \
         `max_links`",
        grouped(*max_links)
    )]
    RefinementTooLarge {
        /// The threshold refined at.
        f_eps: f64,
        /// The limit.
        max_links: usize,
    },
    /// A scene or its lights refused (a lighting's light on an edge, named by its index).
    #[error(transparent)]
    Geom(#[from] flatland_geom::GeomError),
    /// A solve a baseline makes on its way failed (clustered HR's weighting solves).
    #[error(transparent)]
    Solve(#[from] flatland_solve::SolveError),
    /// HR was asked for more links than `max_links` allows.
    #[error(
        "a budget of {} links is more than `max_links` = {}: ask for at most {} links or raise \
         `max_links`",
        grouped(*budget),
        grouped(*max_links),
        grouped(*max_links)
    )]
    BudgetAboveMaxLinks {
        /// The budget asked for.
        budget: usize,
        /// The limit.
        max_links: usize,
    },
}
