//! The learned transport (work in progress).
#![deny(missing_docs)]

mod clusters;
mod columns;
mod error;
mod estimate;
mod file;
mod free;
mod local;
mod lowrank;
mod params;
mod probes;
mod query;
mod source;
mod transport;

pub use columns::Columns;
pub use error::TransportError;
pub use estimate::ErrorEstimate;
pub use file::{TRANSPORT_FORMAT, TRANSPORT_VERSION};
pub use flatland_solve::Stop;
pub use params::TransportParams;
pub use probes::{LightProbes, Placement, ProbeParams};
pub use query::{LaterBounces, Move, QueryBuffers};
pub use source::lit_source;
pub use transport::Transport;
