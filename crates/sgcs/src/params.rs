//! Learning parameters and their single validation step.

use serde::{Deserialize, Serialize};

use crate::SgcsError;
use crate::schema::{Bound, Range, Schema, Spec};

/// How the output weights `v_c` follow the error (the supervised layer's update rule).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum OutputRule {
    /// Normalised least mean squares (the default):
    /// `Δv_c = η (ζ − κ(ξ)) M_c / max(1, Σ_c M_c²)`.
    ///
    /// Identical to [`OutputRule::Plain`] wherever `Σ M_c² ≤ 1` (a sparse network); where many
    /// cells overlap it shortens the step so the error of the presented sample is multiplied by
    /// `1 − η min(1, Σ M_c²) ∈ (−1, 1)`: it cannot diverge for `η ∈ (0, 2)`.
    Normalized,
    /// The paper's delta rule `Δv_c = η (ζ − κ(ξ)) M_c`. Diverges when `η Σ M_c² > 2`
    /// (many overlapping cells); kept for comparison with the paper.
    Plain,
    /// Only the best matching unit learns, towards the target itself: `Δv_s = η (ζ − v_s)`.
    /// Each cell's weight becomes a decayed mean of the targets it wins, so where the target
    /// is constant over a region whose cells never straddle its edges (see [`crate::Gate`]),
    /// every weight converges to that constant and a normalised output reproduces it exactly;
    /// the least-squares rules instead spread errors over overlapping cells that cancel only
    /// at the samples.
    Local,
}

/// The output weight given to a freshly inserted cell `r`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum InsertRule {
    /// The default: `v_r` is chosen so that the network's output at the new centre `w_r` is the
    /// same before and after the insertion (`v_r = κ_before(w_r) − κ_after,v_r=0(w_r)`, using
    /// `M_r(w_r) = 1`). Insertion then does not disturb what has been learned; the new cell only
    /// adds capacity.
    PreserveOutput,
    /// The mean of the new cell's neighbours' output weights, each weighted by the Voronoi volume
    /// `|F_c|` it loses to the new cell (the rule of docs/ALGORITHM.md §3, consistent with the counters).
    /// Falls back to the plain mean of the split edge's two ends when no neighbour loses volume.
    VolumeWeighted,
    /// The target of the sample the cell is put at ([`Insertion::WorstSample`]); the
    /// [`InsertRule::PreserveOutput`] value when it is put at a midpoint. Right where the target
    /// is piecewise constant and cells never straddle a jump (see [`crate::Gate`]).
    SampleTarget,
}

/// How the cells' outputs combine into the network's output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum OutputMode {
    /// `κ(ξ) = Σ_c v_c M_c(ξ)`, the paper's radial-basis sum (the default).
    #[default]
    Sum,
    /// `κ(ξ) = Σ_c v_c M_c(ξ) / Σ_c M_c(ξ)`: a partition of unity (normalised RBF). A region
    /// whose cells all hold the same `v` reproduces it exactly, however the cells overlap; far
    /// from every cell (no activation above the cutoff) the output is 0.
    Normalized,
}

/// Where a new cell is put.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Insertion {
    /// At the midpoint of the longest edge of the cell `q` with the largest resource (Fritzke,
    /// the paper; the default).
    #[default]
    Midpoint,
    /// At the input of the sample with the largest (weighted) squared error that `q` won,
    /// decayed like the resource counters, so a recent bad sample outranks an old one; `q` is
    /// the cell with the largest resource among those holding such a sample. Where the target
    /// jumps, the midpoint of an edge can land on the wrong side; the worst sample is where the
    /// error is. While no cell holds one (every recent sample was predicted exactly), growth
    /// waits.
    WorstSample,
}

/// What the resource `τ_c` (growth and critical cells) measures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Resource {
    /// `τ_c = τ_err,c / τ_cnt,c · |F_c|`: the mean squared error of the samples `c` won times
    /// its Voronoi volume, an estimate of the error integral over its region when samples are
    /// uniform (the paper; the default).
    #[default]
    MeanTimesVolume,
    /// `τ_c = τ_err,c`: the decayed sum of the (weighted) squared errors of the samples `c` won.
    /// With importance-weighted samples this estimates the error integral itself, whatever the
    /// sampling density, and a cell next to an unlearned region is not diluted by the many
    /// samples it predicts exactly.
    ErrorSum,
}

/// Parameters of a supervised growing cell structures network.
///
/// Defaults are the paper's (§3.2): `ε_b = 0.01`, `ε_n = 0.001`, `η = 0.1`, `α = 0.05`, `λ = 300`.
/// Every value is checked by [`Params::validate`], which [`crate::Network::new`] and
/// [`crate::Network::set_params`] call. Deserialising fills missing fields with the defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Params {
    /// Learning rate of the best matching unit's position, `ε_b ∈ (0, 1]`.
    pub eps_b: f64,
    /// Learning rate of the BMU's topological neighbours' positions, `ε_n ∈ [0, 1]`.
    pub eps_n: f64,
    /// Learning rate of the output weights, `η ∈ (0, 2)`.
    pub eta: f64,
    /// Forgetting factor of the resource counters, `α ∈ [0, 1)`: every step each counter
    /// is multiplied by `1 − α` (lazily, see the crate docs).
    pub alpha: f64,
    /// A cell is inserted every `λ ≥ 1` steps.
    pub lambda: u32,
    /// Growth stops when the network has this many cells (`≥ 3`); learning continues.
    pub max_cells: usize,
    /// Activations `M_c(ξ)` below this value are treated as exactly 0, `∈ [0, 1)`.
    ///
    /// A cell is skipped when `|ξ − w_c|² > ln(1/cutoff) · δ_c²`, i.e. when `M_c(ξ) < cutoff`.
    /// This is what makes a step cost independent of the network's size. `0` disables the cutoff
    /// (every cell is visited). The default `1e-8` changes `κ` by less than
    /// `1e-8 · Σ_{skipped} |v_c|`, in practice far below `f64` noise of the learning itself.
    pub activation_cutoff: f64,
    /// Update rule of the output weights.
    pub output_rule: OutputRule,
    /// Output weight of an inserted cell.
    pub insert_rule: InsertRule,
    /// How cell outputs combine.
    pub output_mode: OutputMode,
    /// Where an inserted cell goes.
    pub insertion: Insertion,
    /// What the resource measures.
    pub resource: Resource,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            eps_b: 0.01,
            eps_n: 0.001,
            eta: 0.1,
            alpha: 0.05,
            lambda: 300,
            max_cells: 1_000_000,
            activation_cutoff: 1e-8,
            output_rule: OutputRule::Normalized,
            insert_rule: InsertRule::PreserveOutput,
            output_mode: OutputMode::Sum,
            insertion: Insertion::Midpoint,
            resource: Resource::MeanTimesVolume,
        }
    }
}

impl Schema for Params {
    fn specs() -> Vec<Spec> {
        use Bound::{Closed, Open};
        let real = Range::real;
        vec![
            Spec {
                name: "eps_b",
                symbol: "ε_b",
                range: real(Open(0.0), Closed(1.0)),
                help: "learning rate of the best matching unit's position",
            },
            Spec {
                name: "eps_n",
                symbol: "ε_n",
                range: real(Closed(0.0), Closed(1.0)),
                help: "learning rate of the best matching unit's neighbours' positions",
            },
            Spec {
                name: "eta",
                symbol: "η",
                range: real(Open(0.0), Open(2.0)),
                help: "learning rate of the output weights",
            },
            Spec {
                name: "alpha",
                symbol: "α",
                range: real(Closed(0.0), Open(1.0)),
                help: "forgetting factor of the resource counters, per step",
            },
            Spec {
                name: "lambda",
                symbol: "λ",
                range: Range::integer(1.0, None),
                help: "steps between two insertions",
            },
            Spec {
                name: "max_cells",
                symbol: "N_max",
                range: Range::integer(3.0, None),
                help: "the network stops growing at this many cells (set from the fit's target_cells)",
            },
            Spec {
                name: "activation_cutoff",
                symbol: "M_min",
                range: real(Closed(0.0), Open(1.0)),
                help: "activations below this count as 0 (0: every cell is visited)",
            },
        ]
    }

    fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "eps_b" => self.eps_b,
            "eps_n" => self.eps_n,
            "eta" => self.eta,
            "alpha" => self.alpha,
            "lambda" => f64::from(self.lambda),
            "max_cells" => self.max_cells as f64,
            "activation_cutoff" => self.activation_cutoff,
            _ => return None,
        })
    }

    fn set(&mut self, name: &str, value: f64) -> bool {
        match name {
            "eps_b" => self.eps_b = value,
            "eps_n" => self.eps_n = value,
            "eta" => self.eta = value,
            "alpha" => self.alpha = value,
            "lambda" => self.lambda = value as u32,
            "max_cells" => self.max_cells = value as usize,
            "activation_cutoff" => self.activation_cutoff = value,
            _ => return false,
        }
        true
    }
}

impl Params {
    /// Checks every parameter against [`Params::specs`]; the error names the first invalid one
    /// and its valid range.
    pub fn validate(&self) -> Result<(), SgcsError> {
        match self.invalid() {
            None => Ok(()),
            Some((spec, value)) => Err(SgcsError::InvalidParam {
                name: spec.name,
                range: spec.range.to_string(),
                value: value.to_string(),
            }),
        }
    }

    /// `ln(1/cutoff)`: a cell is active when `|ξ − w_c|² ≤ this · δ_c²` (infinite without cutoff).
    pub(crate) fn reach_sq(&self) -> f64 {
        if self.activation_cutoff > 0.0 {
            -self.activation_cutoff.ln()
        } else {
            f64::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn defaults_are_the_papers_and_valid() {
        let p = Params::default();
        assert_eq!(
            (p.eps_b, p.eps_n, p.eta, p.alpha, p.lambda),
            (0.01, 0.001, 0.1, 0.05, 300)
        );
        assert_eq!(p.output_rule, OutputRule::Normalized);
        p.validate().unwrap();
    }

    #[test]
    fn errors_name_the_parameter_and_range() {
        let cases: Vec<(Params, &str, &str)> = vec![
            (
                Params {
                    eps_b: 0.0,
                    ..Params::default()
                },
                "eps_b",
                "(0, 1]",
            ),
            (
                Params {
                    eps_n: -1.0,
                    ..Params::default()
                },
                "eps_n",
                "[0, 1]",
            ),
            (
                Params {
                    eta: 2.5,
                    ..Params::default()
                },
                "eta",
                "(0, 2)",
            ),
            (
                Params {
                    eta: f64::NAN,
                    ..Params::default()
                },
                "eta",
                "(0, 2)",
            ),
            (
                Params {
                    alpha: 1.0,
                    ..Params::default()
                },
                "alpha",
                "[0, 1)",
            ),
            (
                Params {
                    lambda: 0,
                    ..Params::default()
                },
                "lambda",
                "[1",
            ),
            (
                Params {
                    max_cells: 2,
                    ..Params::default()
                },
                "max_cells",
                "[3",
            ),
            (
                Params {
                    activation_cutoff: 1.0,
                    ..Params::default()
                },
                "activation_cutoff",
                "[0, 1)",
            ),
        ];
        for (p, name, range) in cases {
            let msg = p.validate().unwrap_err().to_string();
            assert!(msg.contains(name) && msg.contains(range), "{msg}");
        }
    }

    #[test]
    fn partial_params_deserialise_with_defaults() {
        let p: Params = serde_json::from_str(r#"{"lambda": 50, "output_rule": "Plain"}"#).unwrap();
        assert_eq!(p.lambda, 50);
        assert_eq!(p.output_rule, OutputRule::Plain);
        assert_eq!(p.eta, Params::default().eta);
    }

    #[test]
    fn reach_matches_cutoff() {
        let p = Params {
            activation_cutoff: 1e-8,
            ..Params::default()
        };
        let r2 = p.reach_sq();
        assert_close!((-r2).exp(), 1e-8, 1e-20);
        let p = Params {
            activation_cutoff: 0.0,
            ..Params::default()
        };
        assert!(p.reach_sq().is_infinite());
    }
}
