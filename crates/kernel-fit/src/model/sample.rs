//! A training sample: what the network learns from, wherever it was drawn (the fit's source
//! draws it; the head files it under its face; checkpoints keep it).

use serde::{Deserialize, Serialize};

/// One training sample: where it is, what the network sees, the target, and its weight.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub(crate) struct Sample {
    pub(crate) st: [f64; 2],
    pub(crate) xi: [f64; 4],
    /// What the network learns for this sample (ζ, k when the emission is factored out, or V).
    pub(crate) target: f64,
    /// Importance weight of the sample's error (1 unless [`FitParams::weighted`](crate::FitParams::weighted)).
    #[serde(default = "unit_scale")]
    pub(crate) weight: f64,
}

/// 1: the serde default of a weight or scale older files do not hold.
pub(crate) fn unit_scale() -> f64 {
    1.0
}
