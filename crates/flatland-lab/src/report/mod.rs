//! Renderers shared by several subcommands, so no subcommand calls another's `run`.

pub mod bench;
pub mod figure;
pub mod grid;
pub mod lit;
pub mod scaling;
pub mod timed;
