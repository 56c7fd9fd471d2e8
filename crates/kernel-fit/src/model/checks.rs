//! Validation of what model files (and the model part of checkpoints) hold, field by field,
//! before anything is built from them: a file the tools wrote and a user edited loads with a
//! one-line error naming the field and the valid range, never a panic, an allocation abort or
//! garbage numbers.
//!
//! The scene (validated by its deserializer), the network's topology, the head's saved fields
//! (the model's deserializer) and the parameters' ranges and combinations
//! ([`FitParams::check`]) are checked where they are defined; this adds what only the whole
//! model knows.

use super::head::ModelHead;
use crate::{FitParams, FitSummary, INPUT_DIM, LearnedKernel, Target, limits};

/// Largest magnitude of a sample's input or target: what `sgcs` accepts.
pub(crate) const MAX_ABS: f64 = 1e100;

/// A field's name and what is wrong with it.
pub(crate) type Bad = String;

pub(crate) fn bad(field: &str, what: impl std::fmt::Display) -> Bad {
    format!("`{field}` {what}")
}

/// The parameters a file holds, against the parameter schema (whose ranges also bound the
/// counts that size an allocation: a hand-edited 10¹⁵ must not abort the process).
pub(crate) fn params(p: &FitParams) -> Result<(), Bad> {
    match p.validate() {
        Ok(()) => Ok(()),
        Err(crate::FitError::OutOfRange { name, value, range }) => Err(bad(
            &format!("params.{name}"),
            format!("is {value}, but must be in {range}"),
        )),
        Err(crate::FitError::Meaningless {
            name,
            value,
            other,
            other_value,
            valid,
        }) => Err(bad(
            &format!("params.{name}"),
            format!(
                "is {value}, which means nothing with `params.{other}` = {other_value}: {valid}"
            ),
        )),
        Err(other) => Err(other.to_string()),
    }
}

/// A learned kernel: the network's shape, the input frame and the output scale agree with each
/// other, the head learns `target`, and no prediction can overflow.
pub(crate) fn learned_kernel(m: &LearnedKernel, target: Target) -> Result<(), Bad> {
    let net = &m.network;
    if net.steps() > limits::MAX_COUNT {
        return Err(bad(
            "model.network.steps",
            format!("is {}, but must be at most 2^50", net.steps()),
        ));
    }
    if net.input_dim() != INPUT_DIM || net.output_dim() != 1 {
        return Err(bad(
            "model.network",
            format!(
                "maps R^{} to R^{}, but a kernel network maps R^{INPUT_DIM} to R^1",
                net.input_dim(),
                net.output_dim()
            ),
        ));
    }
    frame(m)?;
    let scale = m.output_scale;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(bad(
            "model.output_scale",
            format!("is {scale}, but must be finite and > 0"),
        ));
    }
    if m.target() != target {
        return Err(bad(
            "model.target",
            format!(
                "is {}, but the parameters say {}",
                m.target().name(),
                target.name()
            ),
        ));
    }
    // The emission factors are checked against the scene when the model is read.
    let factor_max = match &m.head {
        ModelHead::FactoredEmission { emission } => emission.iter().copied().fold(0.0, f64::max),
        ModelHead::Zeta | ModelHead::Visibility(_) => 1.0,
    };
    // |ζ̃| ≤ Σ_c |v_c| · scale · max E' (activations are at most 1): keep it finite.
    let weights: f64 = (0..net.len()).map(|c| net.output(c)[0].abs()).sum();
    let bound = weights * scale * factor_max;
    if !bound.is_finite() || weights > MAX_ABS {
        return Err(bad(
            "model.network.outputs",
            format!(
                "sum to {weights:e} in magnitude (× output_scale {scale:e}); predictions could \
                 overflow (valid: a sum at most 1e100 whose product with the scale is finite)"
            ),
        ));
    }
    Ok(())
}

/// A learned kernel's input frame: finite, and mapping the scene into about the unit box.
fn frame(m: &LearnedKernel) -> Result<(), Bad> {
    let frame = m.frame;
    if !(frame.origin.iter().all(|v| v.is_finite())
        && frame.inv_scale.is_finite()
        && frame.inv_scale > 0.0)
    {
        return Err(bad(
            "model.frame",
            format!(
                "is origin {:?}, inv_scale {}; the origin must be finite and inv_scale finite and > 0",
                frame.origin, frame.inv_scale
            ),
        ));
    }
    // The frame maps the scene into the unit box (a dragged end point may leave it a little):
    // anything far from that would make every input the same point, or no point at all.
    let (lo, hi) = m.scene.bounds();
    let (a, b) = (frame.map(lo), frame.map(hi));
    let side = (b[0] - a[0]).max(b[1] - a[1]);
    let far = a
        .iter()
        .chain(&b)
        .any(|v| !v.is_finite() || v.abs() > 100.0);
    if far || !(1e-3..=100.0).contains(&side) {
        return Err(bad(
            "model.frame",
            format!(
                "maps the scene to [{:.3e}, {:.3e}] × [{:.3e}, {:.3e}]; a valid frame maps it \
                 into [-100, 100]² with a side in [0.001, 100] (the file was edited)",
                a[0], b[0], a[1], b[1]
            ),
        ));
    }
    Ok(())
}

/// The figures a model file reports: finite, non-negative, and consistent with the model.
pub(crate) fn summary(s: &FitSummary, cells: usize) -> Result<(), Bad> {
    let numbers = [
        ("summary.errors.grid", s.errors.grid),
        ("summary.errors.heldout", s.errors.heldout),
        ("summary.wall_s", s.wall_s),
        ("summary.train_s", s.train_s),
        ("summary.resample_s", s.resample_s),
        ("summary.refit_s", s.refit_s),
        ("summary.reference_s", s.reference_s),
        ("summary.errors_s", s.errors_s),
    ];
    let before = s.errors_before_refit.map(|e| {
        [
            ("summary.errors_before_refit", e.grid),
            ("summary.errors_before_refit", e.heldout),
        ]
    });
    for (field, v) in numbers.into_iter().chain(before.into_iter().flatten()) {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(field, format!("is {v}, but must be finite and ≥ 0")));
        }
    }
    if s.cells != cells {
        return Err(bad(
            "summary.cells",
            format!("is {}, but the network has {cells} cells", s.cells),
        ));
    }
    Ok(())
}
