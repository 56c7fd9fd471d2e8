//! What the workspace's tests share, as a dev-dependency only: [`assert_close!`] (relative and
//! absolute tolerance, a message naming both values), the seeded generator of every test
//! ([`rng`], the project's seed rule), and small rooms as corner lists ([`rooms`]: turned into
//! edges by `flatland_geom::Edge::polygon`).
//!
//! It depends on no crate of the workspace, so even the bottom crates (`flatland-geom`, `sgcs`)
//! use it in their unit tests without a second copy of themselves.

#![deny(missing_docs)]

mod close;
pub mod rooms;
mod seeded;

pub use close::{close_failed, is_close};
pub use seeded::{rng, stream};
