//! Learning driven by the light that flows: the light-driven learner of `flatland solve --kernel light`, which
//! alternates solving and learning until the lit scene meets a tolerance (docs/ALGORITHM.md §4a).
//! It needs the scene's geometry and the solver (`flatland_geom`, `flatland_solve`), not the
//! network of `kernel-fit`: its cells are probes along the surfaces, grown in one dimension.
//!
//! The paper weights what is learned by the first shot `E'` only; its future work is to couple
//! the learner to the energy transfer. Here the coupling is the loop itself. On a mesh of the
//! scene the learner's cells are **probes**: the exact view of one receiver element's midpoint
//! (what it sees, by the visibility sweep), kept as positions along the surfaces it sees so
//! that the elements between two probes of a section can borrow both views (module `probes`).
//! Their rows blend the two, exact where the views agree, and carry a *doubt* where they
//! disagree (module `rows`). Each **round**:
//!
//! 1. solves `B = E + K B` with the current operator (warm-started from the last round's B);
//! 2. estimates the error of `B − E` the doubt leaves — each row's uncertain light
//!    `δ_i = Σ_j doubt_ij B_j`, carried through the bounces by one more solve of
//!    `(I − K) e = δ`, relative to `‖B − E‖` — and stops when it is within the tolerance;
//! 3. ranks the gaps between neighbouring probes by the uncertain power inside them
//!    (`Σ δ_i L_i`) and probes the middle element of the largest, twice as many as the round
//!    before (near the tolerance only as many as carry the share `1 − tol / (2 · estimate)` of
//!    that power); then rebuilds the rows of those gaps.
//!
//! Light that flows through doors into a dark room raises that room's B in the next solve, so
//! the gaps whose views disagree about that door rise in the ranking: the loop follows the
//! bounces, not just the lamps. A probe costs one sweep (about `log n` plus what the point
//! sees), a borrowed row a closed form per stretch seen, so nothing is quadratic in the edges.
//!
//! ```
//! use std::sync::Arc;
//! use flatland_geom::{Kernel, generate};
//! use flatland_light::{LightFit, LightParams, LightStop};
//! use flatland_solve::{Mesh, never};
//!
//! // A generated floor plan of about 80 edges, meshed as `flatland solve` meshes it.
//! let kernel = Arc::new(Kernel::new(generate::floor_plan(80, 1)?));
//! let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene()))?;
//! let mut fit = LightFit::new(kernel, mesh, LightParams::default())?;
//! let stopped = fit.run(&never, |_| {})?;
//! // It stops at the default tolerance (1 % of B − E, as it estimates it) or has no doubt left.
//! assert!(matches!(stopped, LightStop::Tolerance | LightStop::Exact));
//! assert!(fit.estimated_error().unwrap() <= 0.01);
//! assert!(fit.radiosity().iter().all(|&b| b >= 0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

mod driver;
mod error;
mod estimate;
mod probes;
mod represent;
mod rows;

use flatland_solve::{Mesh, ProbeBuffers, SeenSpan, Stop, Sweep};
use rayon::prelude::*;

pub use driver::LightFit;
pub use error::LightError;
pub use estimate::LightEstimate;
pub use probes::ProbeCell;

use probes::{Bracket, Probes};
use rows::{Entry, Rows};

/// Settings of the loop, checked by [`LightParams::check`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightParams {
    /// Stop when the estimated relative L2 error of the solved `B − E` (against the exact
    /// kernel on the same mesh) is at most this. Valid: (0, 1).
    pub tolerance: f64,
    /// Probes added in the second round (the first probes both ends of every section); each
    /// round after adds twice as many as the last. Valid: ≥ 1.
    pub first_round: usize,
    /// Stop once this many probes (cells) are placed. Valid: ≥ 1.
    pub max_cells: usize,
    /// Stop after this many seconds (checked between rounds). Valid: > 0.
    pub max_seconds: f64,
}

impl Default for LightParams {
    fn default() -> Self {
        LightParams {
            tolerance: 0.01,
            first_round: 256,
            max_cells: usize::MAX,
            max_seconds: f64::INFINITY,
        }
    }
}

impl LightParams {
    /// Checks every field; the error names it and its valid range.
    pub fn check(&self) -> Result<(), LightError> {
        let bad = |name: &'static str, value: String, valid: &'static str| {
            Err(LightError::InvalidParameter { name, value, valid })
        };
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("tolerance", self.tolerance.to_string(), "in (0, 1)");
        }
        if self.first_round == 0 {
            return bad("first_round", "0".into(), "at least 1");
        }
        if self.max_cells == 0 {
            return bad("max_cells", "0".into(), "at least 1");
        }
        if self.max_seconds.is_nan() || self.max_seconds <= 0.0 {
            return bad("max_seconds", self.max_seconds.to_string(), "more than 0");
        }
        Ok(())
    }
}

/// Why the loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightStop {
    /// The estimated error is within the tolerance.
    Tolerance,
    /// Every element is probed, or no row has any doubt left: the learned operator is the
    /// exact one on this mesh.
    Exact,
    /// The cell budget ran out.
    Cells,
    /// The time budget ran out.
    Time,
}

impl LightStop {
    /// Its name in reports and JSON: `tolerance`, `exact`, `cells` or `time`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            LightStop::Tolerance => "tolerance",
            LightStop::Exact => "exact",
            LightStop::Cells => "cells",
            LightStop::Time => "time",
        }
    }
}

/// One round as it ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Round {
    /// Probes (cells) placed so far.
    pub cells: usize,
    /// The estimated relative L2 error of `B − E` after this round's solve.
    pub estimated_error: f64,
    /// Seconds since the loop started.
    pub seconds: f64,
}

/// What probing one element gives: its exact row and the stretches its point sees.
type Probed = (Vec<(u32, f64)>, Vec<SeenSpan>);

/// Probes `elements` (new, distinct) in parallel, records them and sets their exact rows.
fn probe(
    sweep: &Sweep,
    mesh: &Mesh,
    elements: &[usize],
    probes: &mut Probes,
    rows: &mut Rows,
    stop: &Stop,
) -> Result<(), LightError> {
    let seen: Vec<Probed> = elements
        .par_iter()
        .map_init(ProbeBuffers::default, |buffers, &i| {
            if stop() {
                return Err(LightError::Interrupted);
            }
            let (mut row, mut spans) = (Vec::new(), Vec::new());
            sweep.probe(mesh, i, buffers, &mut row, &mut spans);
            Ok((row, spans))
        })
        .collect::<Result<_, _>>()?;
    let mut exact = Vec::with_capacity(elements.len());
    for (&i, (row, spans)) in elements.iter().zip(seen) {
        probes.add(i, &spans);
        exact.push((i, Rows::exact(&row)));
    }
    rows.replace(exact);
    Ok(())
}

/// Rebuilds the rows of `elements` from their brackets, in parallel (a probed one keeps the
/// exact row its probe set).
fn borrow(
    sweep: &Sweep,
    mesh: &Mesh,
    elements: &[usize],
    probes: &Probes,
    rows: &mut Rows,
    stop: &Stop,
) -> Result<(), LightError> {
    let built: Vec<Option<Vec<Entry>>> = elements
        .par_iter()
        .with_min_len(16)
        .map_init(
            || (Vec::new(), Vec::new()),
            |(left, right), &i| {
                if stop() {
                    return Err(LightError::Interrupted);
                }
                Ok(match probes.bracket(mesh, i) {
                    // Its own probe set its exact row.
                    Bracket::Probed(_) => None,
                    Bracket::Between {
                        left: l,
                        right: r,
                        f,
                    } => {
                        sweep.row_through(mesh, i, probes.spans(l), left);
                        sweep.row_through(mesh, i, probes.spans(r), right);
                        Some(Rows::blend(mesh.edge_of(i).reflectance, f, left, right))
                    }
                })
            },
        )
        .collect::<Result<_, _>>()?;
    rows.replace(
        elements
            .iter()
            .zip(built)
            .filter_map(|(&i, row)| row.map(|row| (i, row)))
            .collect(),
    );
    Ok(())
}

#[cfg(test)]
mod tests;
