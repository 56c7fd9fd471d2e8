//! The learned transport (work in progress).
#![deny(missing_docs)]

mod clusters;
mod columns;
mod error;
mod estimate;
mod free;
mod local;
mod lowrank;
mod params;
mod source;
mod transport;

pub use columns::Columns;
pub use error::TransportError;
pub use estimate::ErrorEstimate;
pub use flatland_solve::Stop;
pub use params::TransportParams;
pub use source::lit_source;
pub use transport::Transport;
