//! What every solve is told: its checked settings ([`SolveParams`]) and the stop flag polled by
//! its long loops ([`Stop`]). A leaf, so the operators and the solve both use it.

use serde::{Deserialize, Serialize};

use crate::SolveError;

/// The stop flag of every long loop here: polled between rows and iterations; when it returns
/// `true` the work ends with [`SolveError::Interrupted`].
pub type Stop = dyn Fn() -> bool + Sync;

/// A [`Stop`] that never stops.
#[must_use]
pub fn never() -> bool {
    false
}

/// Settings of a solve, checked by [`SolveParams::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SolveParams {
    /// Relative residual `‖E − (I − K) B‖ / ‖E‖` the linear solve must reach. Valid: (0, 0.1].
    pub tolerance: f64,
    /// Most products with K before giving up. Valid: ≥ 1.
    pub max_iterations: usize,
    /// Gauss–Legendre points per element for the default (quadrature) operator. Valid: [1, 16].
    pub quadrature_points: usize,
}

impl Default for SolveParams {
    fn default() -> Self {
        SolveParams {
            tolerance: 1e-10,
            max_iterations: 2000,
            quadrature_points: 2,
        }
    }
}

impl SolveParams {
    /// Checks every field; the error names it and its valid range.
    pub fn validate(&self) -> Result<(), SolveError> {
        let bad =
            |name, value: String, valid| Err(SolveError::InvalidParameter { name, value, valid });
        if !(self.tolerance > 0.0 && self.tolerance <= 0.1) {
            return bad("tolerance", self.tolerance.to_string(), "in (0, 0.1]");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "0".into(), "at least 1");
        }
        if !(1..=16).contains(&self.quadrature_points) {
            return bad(
                "quadrature_points",
                self.quadrature_points.to_string(),
                "in [1, 16]",
            );
        }
        Ok(())
    }
}
