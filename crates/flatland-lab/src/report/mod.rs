//! Outputs shared by several subcommands, so no subcommand calls another's `run`: CSV and
//! tables, and the pictures of [`flatland_pictures`] with the data they are drawn from.

pub mod figure;
pub mod grid;
pub mod r4;
pub mod scaling;
pub mod solution;
pub mod timed;
pub mod walk;
