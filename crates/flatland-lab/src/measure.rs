//! What errors are measured on and when they mean something: the one reference rule of every
//! command and experiment, and "undefined" where a relative error is 0/0.

use flatland_geom::Kernel;
use flatland_solve::{Errors, Reference};
use kernel_fit::{FitParams, REFERENCE_SEED};

/// The reference every error of a fit is measured against: `res × res` grid and
/// `params.heldout` points drawn with the one [`REFERENCE_SEED`] every command uses, so fits of
/// any seed are measured on the same points and `flatland results` reports what `flatland fit`
/// prints.
pub fn reference(kernel: &Kernel, res: usize, params: &FitParams) -> Reference {
    Reference::new(kernel, res, params.heldout, REFERENCE_SEED)
}

/// Which relative errors mean something: against a ζ that is 0 everywhere it was measured (a
/// scene where nothing emits), a relative error is 0/0 and is printed as "undefined", not as a
/// perfect 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Defined {
    /// The error on the reference grid.
    pub grid: bool,
    /// The error at the held-out points.
    pub heldout: bool,
}

impl Defined {
    /// Whether the reference has a non-zero value on its grid and at its held-out points.
    pub fn of(reference: &Reference) -> Defined {
        Defined {
            grid: reference.grid().iter().any(|v| *v != 0.0),
            heldout: reference.heldout().1.iter().any(|v| *v != 0.0),
        }
    }

    /// `grid 0.1234   held out 0.5678`, with "undefined" where it is.
    pub fn format(&self, e: &Errors) -> String {
        format!(
            "grid {}   held out {}",
            error_text(e.grid, self.grid, 4),
            error_text(e.heldout, self.heldout, 4)
        )
    }

    /// Why an error is undefined, when one is.
    pub fn note(&self) -> Option<&'static str> {
        (!(self.grid && self.heldout)).then_some(
            "undefined: the exact ζ is 0 everywhere it was measured (does anything emit?)",
        )
    }
}

/// A relative error with `digits` decimals, or "undefined".
pub fn error_text(value: f64, defined: bool, digits: usize) -> String {
    if defined {
        format!("{value:.digits$}")
    } else {
        "undefined".to_owned()
    }
}
