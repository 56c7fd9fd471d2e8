//! The fit's parameters, with the paper's defaults and one validation step.

use serde::{Deserialize, Serialize};

use sgcs::schema::{Bound, Range, Schema, Spec};

use crate::{FitError, limits};

/// Everything that configures a [`Fit`](crate::Fit). `Default` gives the paper's values (§3.2)
/// where the paper has one, and measured choices where it is silent (each documented).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FitParams {
    /// The network's own parameters (ε_b, ε_n, η, α, λ, …).
    pub network: sgcs::Params,
    /// ω: a cell is critical when `τ_c > ω · mean τ`. Paper: 0.6. Valid: finite, ≥ 0.
    pub omega: f64,
    /// φ: ξ is inside a (sub-)network when its summed activation exceeds φ. Paper: 1. Valid: > 0.
    pub phi: f64,
    /// ψ: a new sample set is made when `|A| / |S| > ψ`. Paper: 0.05 (≈ 20 samples per cell).
    /// Valid: (0, 1].
    pub psi: f64,
    /// |S₀|: uniform random samples before training starts. Valid: ≥ 3.
    pub initial_samples: usize,
    /// Smallest size of a resampled set `S_j`; a set is also large enough to bring
    /// `|A| / |S|` back to ψ. Valid: ≥ 1.
    pub min_set_size: usize,
    /// The θ scan looks at most `scan_factor × set size` candidates, so it always ends even when
    /// θ rejects nearly everything. Valid: ≥ 1.
    pub scan_factor: usize,
    /// Stop when the network has this many cells (and has trained one λ period with it). Valid: ≥ 3.
    pub target_cells: usize,
    /// Stop after this many training steps. Valid: ≥ 1.
    pub max_steps: u64,
    /// Stop when this many rays (exact kernel evaluations for training) have been cast. Valid: ≥ 1.
    pub ray_budget: u64,
    /// Stop when the held-out relative L2 error falls to this value (0 disables). Valid: [0, ∞).
    pub target_error: f64,
    /// Refit all output weights by ridge least squares over the training samples at the end.
    pub refit: bool,
    /// Smallest ridge (Tikhonov) weight the refit tries, relative to the mean diagonal of the
    /// normal equations; it tries this × 10⁰ … 10⁶ and keeps what validates best. Valid: > 0.
    pub ridge: f64,
    /// Held-out random points for the error measured during and after the fit. Valid: ≥ 16.
    pub heldout: usize,
    /// Steps between two held-out error measurements recorded in the history (0: never).
    pub eval_every: u64,
    /// Seed of every random choice: same seed, same fit.
    pub seed: u64,
    /// How new sample sets are chosen: θ (the paper) or uniformly (the control experiment).
    pub resampling: Resampling,
    /// What the network learns: ζ itself (the paper), k with the emission factored out, or
    /// only the visibility where it varies.
    pub target: Target,
    /// [`Target::Visibility`] only: which known discontinuities no cell may straddle.
    pub gating: Gating,
    /// [`Target::Visibility`] only: the share of samples (and θ candidates) drawn in proportion
    /// to the clipped square of the unoccluded ζ, the rest uniformly over the pairs where
    /// visibility varies. Valid: [0, 1).
    pub importance: f64,
    /// [`Target::Visibility`] only: count each sample's error with its importance weight in
    /// the resource (so growth follows the error of ζ, not of V). With `importance > 0` the
    /// weight also undoes the sampling density.
    pub weighted: bool,
}

/// Which known discontinuities of the target the cells may not straddle ([`Target::Visibility`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gating {
    /// Every cell responds to every input (the paper's network).
    #[default]
    Off,
    /// A cell responds only to rays between the same two surface edges as its centre ray.
    Pairs,
    /// And only to rays on the same side of every visibility event point within its reach:
    /// the cells of one face of the visibility structure, where `V` is constant.
    Faces,
}

/// What the network's output approximates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// ζ = E'(sender) · k (paper §3.3).
    #[default]
    Zeta,
    /// k, and ζ̃ = E'(sender) · κ. E' is piecewise constant per edge and known exactly, so the
    /// network need not spend cells on its jumps (a light set into a ceiling is a 100× step
    /// along one straight line, invisible to γ).
    FactoredEmission,
    /// The visibility `V ∈ [0, 1]`, and only on the pairs of surface edges where the geometry
    /// cannot decide it: `ζ̃ = ζ_unoccluded · Ṽ`, with the unoccluded `ζ = E' ρ G` exact (no ray),
    /// `Ṽ = 1` where a pair is provably unoccluded and 0 where provably blocked. The network
    /// spends its cells and rays only on shadows.
    Visibility,
}

/// How the sets `S₁, S₂, …` are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Resampling {
    /// The paper's θ(ξ) = ρ_ACC(ξ) ∨ ¬ρ_A(ξ): rays only in critical or uncovered zones.
    #[default]
    Theta,
    /// Uniform random (s, t), same set sizes: the control that shows what θ earns.
    Uniform,
}

/// A named set of [`FitParams`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// The project's learner (the default, [`FitParams::default`]): the network learns only
    /// the visibility, on the pairs of surface edges where geometry cannot decide it; the
    /// exact unoccluded kernel does the rest. Its cells never straddle a visibility
    /// discontinuity, so it improves on the paper's network at a faster rate.
    #[default]
    Default,
    /// The paper's network ([`FitParams::paper`]): SGCS learns ζ itself from `γ(s, t)`, with
    /// the paper's parameters, plus this project's stability fixes and least-squares refit.
    Paper,
}

impl Preset {
    /// Every preset, in the order tables list them.
    pub const ALL: [Preset; 2] = [Preset::Default, Preset::Paper];

    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Default => "default",
            Preset::Paper => "paper",
        }
    }

    /// Parses [`Preset::name`].
    pub fn parse(name: &str) -> Result<Preset, FitError> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| FitError::InvalidParameter {
                name: "preset",
                value: name.to_owned(),
                valid: "default or paper",
            })
    }

    /// The preset's parameters.
    pub fn params(self) -> FitParams {
        match self {
            Preset::Default => FitParams::default(),
            Preset::Paper => FitParams::paper(),
        }
    }
}

impl Default for FitParams {
    /// The project's learner ([`Preset::Default`]). Where it departs from the paper:
    /// - `target: Visibility`, `gating: Faces`: learn `V` only where it varies, with cells
    ///   that never straddle a visibility discontinuity (the paper learns ζ everywhere);
    /// - `output_mode: Normalized`, `output_rule: Local`: a partition of unity whose cells
    ///   hold the mean target they win, exact on a face of constant `V`;
    /// - `insertion: WorstSample`, `insert_rule: SampleTarget`, `resource: ErrorSum`: grow
    ///   where the (importance-weighted) error is, not at an edge midpoint;
    /// - `importance: 0.7`, `weighted: true`: draw samples where the unoccluded ζ is large;
    /// - `phi: 0.01`: θ's "outside the network" means the cells of a candidate's face reach it
    ///   with less than 1 % activation; the paper's φ = 1 was set for sums of overlapping
    ///   ungated cells and here spends rays on faces already learned exactly;
    /// - `refit: false`: the local rule converges exactly; there is nothing to refit.
    ///
    /// Everything else keeps the paper's values (ε_b, ε_n, η, α, λ, ω, ψ).
    fn default() -> Self {
        FitParams {
            network: sgcs::Params {
                output_mode: sgcs::OutputMode::Normalized,
                output_rule: sgcs::OutputRule::Local,
                insertion: sgcs::Insertion::WorstSample,
                insert_rule: sgcs::InsertRule::SampleTarget,
                resource: sgcs::Resource::ErrorSum,
                ..sgcs::Params::default()
            },
            phi: 0.01,
            refit: false,
            target: Target::Visibility,
            gating: Gating::Faces,
            importance: 0.7,
            weighted: true,
            ..FitParams::paper()
        }
    }
}

impl FitParams {
    /// The paper's network ([`Preset::Paper`]): its parameters (§3.2), ζ learned from
    /// `γ(s, t)`, θ-resampling, plus the least-squares output refit and NLMS step of this
    /// project (which change nothing where the paper's rule is stable).
    pub fn paper() -> FitParams {
        FitParams {
            network: sgcs::Params::default(),
            omega: 0.6,
            phi: 1.0,
            psi: 0.05,
            initial_samples: 500,
            min_set_size: 50,
            scan_factor: 16,
            target_cells: 400,
            max_steps: 50_000_000,
            ray_budget: u64::MAX,
            target_error: 0.0,
            refit: true,
            ridge: 1e-6,
            heldout: 4096,
            eval_every: 3000,
            seed: 1,
            resampling: Resampling::Theta,
            target: Target::Zeta,
            gating: Gating::Off,
            importance: 0.0,
            weighted: false,
        }
    }
}

/// The fit's own numeric parameters (the network's follow them in [`FitParams::specs`]).
fn own_specs() -> Vec<Spec> {
    use Bound::{Closed, None as Unbounded, Open};
    let real = Range::real;
    let whole = |lo: f64, hi: Option<u64>| Range::integer(lo, hi.map(|h| h as f64));
    let spec = |name, symbol, range, help| Spec {
        name,
        symbol,
        range,
        help,
    };
    vec![
        spec(
            "omega",
            "ω",
            real(Closed(0.0), Unbounded),
            "a cell is critical when τ_c > ω · mean τ",
        ),
        spec(
            "phi",
            "φ",
            real(Open(0.0), Unbounded),
            "ξ is inside a (sub-)network when its summed activation exceeds φ",
        ),
        spec(
            "psi",
            "ψ",
            real(Open(0.0), Closed(1.0)),
            "a new sample set is drawn when cells / samples > ψ",
        ),
        spec(
            "initial_samples",
            "|S₀|",
            whole(3.0, Some(limits::MAX_SET_SIZE as u64)),
            "uniform random samples before training",
        ),
        spec(
            "min_set_size",
            "",
            whole(1.0, Some(limits::MAX_SET_SIZE as u64)),
            "smallest resampled set",
        ),
        spec(
            "scan_factor",
            "",
            whole(1.0, None),
            "the θ scan looks at most this × set size candidates",
        ),
        spec(
            "target_cells",
            "N",
            whole(3.0, Some(limits::MAX_CELLS as u64)),
            "stop at this many cells (the network's max_cells)",
        ),
        spec(
            "max_steps",
            "",
            whole(1.0, Some(limits::MAX_COUNT)),
            "stop after this many training steps",
        ),
        spec(
            "ray_budget",
            "",
            whole(1.0, None),
            "stop after this many training rays",
        ),
        spec(
            "target_error",
            "",
            real(Closed(0.0), Unbounded),
            "stop when the held-out relative L2 reaches this (0: never)",
        ),
        spec(
            "ridge",
            "",
            real(Open(0.0), Closed(1e100)),
            "smallest ridge weight the least-squares refit tries (× 10⁰ … 10⁶)",
        ),
        spec(
            "heldout",
            "",
            whole(
                *limits::HELDOUT.start() as f64,
                Some(*limits::HELDOUT.end() as u64),
            ),
            "held-out points of the error measured during the fit",
        ),
        spec(
            "eval_every",
            "",
            whole(0.0, None),
            "steps between two held-out measurements in the history (0: never)",
        ),
        spec(
            "importance",
            "",
            real(Closed(0.0), Open(1.0)),
            "visibility learner: share of samples drawn by importance",
        ),
    ]
}

impl Schema for FitParams {
    /// The network's parameters (except `max_cells`, which is `target_cells`), then the fit's.
    fn specs() -> Vec<Spec> {
        let mut specs: Vec<Spec> = sgcs::Params::specs()
            .into_iter()
            .filter(|s| s.name != "max_cells")
            .collect();
        specs.extend(own_specs());
        specs
    }

    fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "omega" => self.omega,
            "phi" => self.phi,
            "psi" => self.psi,
            "initial_samples" => self.initial_samples as f64,
            "min_set_size" => self.min_set_size as f64,
            "scan_factor" => self.scan_factor as f64,
            "target_cells" => self.target_cells as f64,
            "max_steps" => self.max_steps as f64,
            "ray_budget" => self.ray_budget as f64,
            "target_error" => self.target_error,
            "ridge" => self.ridge,
            "heldout" => self.heldout as f64,
            "eval_every" => self.eval_every as f64,
            "importance" => self.importance,
            "max_cells" => return None,
            _ => return self.network.get(name),
        })
    }

    fn set(&mut self, name: &str, value: f64) -> bool {
        match name {
            "omega" => self.omega = value,
            "phi" => self.phi = value,
            "psi" => self.psi = value,
            "initial_samples" => self.initial_samples = value as usize,
            "min_set_size" => self.min_set_size = value as usize,
            "scan_factor" => self.scan_factor = value as usize,
            "target_cells" => self.target_cells = value as usize,
            "max_steps" => self.max_steps = value as u64,
            "ray_budget" => self.ray_budget = value as u64,
            "target_error" => self.target_error = value,
            "ridge" => self.ridge = value,
            "heldout" => self.heldout = value as usize,
            "eval_every" => self.eval_every = value as u64,
            "importance" => self.importance = value,
            "max_cells" => return false,
            _ => return self.network.set(name, value),
        }
        true
    }
}

/// The Markdown table of every numeric parameter (name, symbol, range, the paper's and the
/// default learner's value, meaning): the table of docs/ALGORITHM.md §8, which a test keeps
/// equal to this.
pub fn parameter_table() -> String {
    sgcs::schema::markdown_table(&[
        ("paper", &FitParams::paper()),
        ("default learner", &FitParams::default()),
    ])
}

impl FitParams {
    /// Checks every value against [`FitParams::specs`]; the error names the first parameter
    /// out of range and the range.
    pub fn validate(&self) -> Result<(), FitError> {
        match self.invalid() {
            None => Ok(()),
            Some((spec, value)) => Err(FitError::OutOfRange {
                name: spec.name,
                value: value.to_string(),
                range: spec.range.to_string(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BEGIN: &str = "<!-- parameters: kernel_fit::parameter_table() -->\n";
    const END: &str = "<!-- end of parameters -->";

    #[test]
    fn the_documented_parameter_table_is_the_schema() {
        let doc = include_str!("../../../docs/ALGORITHM.md");
        let table = doc
            .split_once(BEGIN)
            .and_then(|(_, rest)| rest.split_once(END))
            .map(|(table, _)| table)
            .expect("docs/ALGORITHM.md §8 holds the generated table between its markers");
        assert_eq!(
            table,
            parameter_table(),
            "docs/ALGORITHM.md §8 is out of date; replace its table with:\n{}",
            parameter_table()
        );
    }

    #[test]
    fn every_value_just_outside_a_range_is_refused_by_name() {
        for spec in FitParams::specs() {
            for bad in spec.range.outside() {
                let mut params = FitParams::default();
                assert!(params.set(spec.name, bad), "{}", spec.name);
                let msg = params.validate().unwrap_err().to_string();
                assert!(
                    msg.contains(spec.name) && msg.contains("must be in"),
                    "{msg}"
                );
            }
        }
        let mut params = FitParams::default();
        assert!(sgcs::schema::set_checked(&mut params, "eta = 0.5").is_ok());
        assert_eq!(params.network.eta, 0.5);
        let err = sgcs::schema::set_checked(&mut params, "eta=2").unwrap_err();
        assert!(err.contains("(0, 2)"), "{err}");
        let err = sgcs::schema::set_checked(&mut params, "max_cells=10").unwrap_err();
        assert!(err.contains("target_cells"), "the list of names: {err}");
    }

    #[test]
    fn presets_are_valid_and_the_paper_keeps_its_values() {
        let paper = FitParams::paper();
        paper.validate().unwrap();
        assert_eq!((paper.omega, paper.phi, paper.psi), (0.6, 1.0, 0.05));
        assert_eq!(paper.network, sgcs::Params::default());
        assert_eq!(paper.target, Target::Zeta);
        let default = FitParams::default();
        default.validate().unwrap();
        assert_eq!((default.omega, default.phi, default.psi), (0.6, 0.01, 0.05));
        assert_eq!(default.target, Target::Visibility);
        for p in Preset::ALL {
            assert_eq!(Preset::parse(p.name()).unwrap(), p);
        }
        assert!(
            Preset::parse("nope")
                .unwrap_err()
                .to_string()
                .contains("paper")
        );
    }

    #[test]
    fn errors_name_the_parameter_and_range() {
        let cases: [(FitParams, &str); 4] = [
            (
                FitParams {
                    psi: 0.0,
                    ..Default::default()
                },
                "psi",
            ),
            (
                FitParams {
                    phi: f64::NAN,
                    ..Default::default()
                },
                "phi",
            ),
            (
                FitParams {
                    target_cells: 2,
                    ..Default::default()
                },
                "target_cells",
            ),
            (
                FitParams {
                    ridge: -1.0,
                    ..Default::default()
                },
                "ridge",
            ),
        ];
        for (p, name) in cases {
            let msg = p.validate().unwrap_err().to_string();
            assert!(msg.contains(name) && msg.contains("must be"), "{msg}");
        }
    }
}
