//! Ranges shared by every entry point (the CLI, model and checkpoint files), so a value is
//! accepted or refused the same way everywhere, and refused before anything is allocated.

use std::ops::RangeInclusive;

/// Resolution `R` of a reference or evaluation grid (`R²` values are held in memory).
pub const GRID_RES: RangeInclusive<usize> = 16..=4096;

/// Held-out points of a reference.
pub const HELDOUT: RangeInclusive<usize> = 16..=1 << 20;

/// Largest sample count a file may ask for at once (`|S₀|`, the smallest resampled set).
pub const MAX_SET_SIZE: usize = 10_000_000;

/// Largest target cell count a file may hold.
pub const MAX_CELLS: usize = 10_000_000;

/// Largest step or ray count a file may hold (2⁵⁰: decades of training), so counting on from it
/// cannot overflow.
pub const MAX_COUNT: u64 = 1 << 50;

/// The seed of the held-out points of every reference the tools build (`flatland fit`, `eval`,
/// `figure`, `bench`, `results`, the viewer, a resumed checkpoint): the same points whatever the
/// fit's own seed, so fits with different seeds are measured on the same points and a documented
/// command reproduces the number a document reports.
pub const REFERENCE_SEED: u64 = 0;
