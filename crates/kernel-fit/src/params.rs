//! The fit's parameters as files and the command line spell them, with the paper's values and
//! the visibility network's; [`FitParams::check`] (in `valid`) turns them into the learner's
//! variant and the parameters by lifetime.

use serde::{Deserialize, Serialize};

mod preset;
mod schema;
mod valid;

pub use preset::Preset;
pub use schema::parameter_table;
pub use valid::{
    FixedParams, Head, LiveParams, Measurement, NetworkRates, NetworkRules, Refit, ValidParams,
    VisibilityParams,
};

/// Everything that configures a [`Fit`](crate::Fit), flat, as model and checkpoint files and
/// `--set` spell it. `Default` is the visibility network ([`Preset::Visibility`]);
/// [`FitParams::paper`] the paper's values (§3.2). Not every combination means something:
/// [`FitParams::check`] refuses those that do not and says which learner the rest describe.
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
    /// Refit all output weights by ridge least squares over the training samples at the end
    /// (a learner of ζ or k; the visibility learner's local rule has nothing to refit).
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
    /// [`Target::Visibility`] only (else `off`): which known discontinuities no cell may
    /// straddle.
    pub gating: Gating,
    /// [`Target::Visibility`] only (else 0): the share of samples (and θ candidates) drawn in proportion
    /// to the clipped square of the unoccluded ζ, the rest uniformly over the pairs where
    /// visibility varies. Valid: [0, 1).
    pub importance: f64,
    /// [`Target::Visibility`] only (else `false`): count each sample's error with its importance weight in
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

impl Gating {
    /// The name files and messages use.
    pub fn name(self) -> &'static str {
        match self {
            Gating::Off => "off",
            Gating::Pairs => "pairs",
            Gating::Faces => "faces",
        }
    }
}

impl Target {
    /// The name files and messages use.
    pub fn name(self) -> &'static str {
        match self {
            Target::Zeta => "zeta",
            Target::FactoredEmission => "factored_emission",
            Target::Visibility => "visibility",
        }
    }
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

impl Default for FitParams {
    /// The visibility network ([`Preset::Visibility`]). Where it departs from the paper:
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

impl FitParams {
    /// These parameters learning `target`, with what only some learners have brought along so
    /// that the combination means something (see [`FitParams::check`]): switching to
    /// [`Target::Visibility`] takes the visibility network's gating, importance and weights and
    /// drops the refit; switching away from it turns those off and takes the paper's refit.
    /// The same target returns the parameters unchanged.
    #[must_use]
    pub fn learning(self, target: Target) -> FitParams {
        let was_visibility = self.target == Target::Visibility;
        match (was_visibility, target == Target::Visibility) {
            (false, false) | (true, true) => FitParams { target, ..self },
            (false, true) => {
                let d = FitParams::default();
                FitParams {
                    target,
                    gating: d.gating,
                    importance: d.importance,
                    weighted: d.weighted,
                    refit: false,
                    ..self
                }
            }
            (true, false) => FitParams {
                target,
                gating: Gating::Off,
                importance: 0.0,
                weighted: false,
                refit: FitParams::paper().refit,
                ..self
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changing_the_target_keeps_the_parameters_meaningful() {
        for from in [FitParams::default(), FitParams::paper()] {
            for target in [Target::Zeta, Target::FactoredEmission, Target::Visibility] {
                let changed = from.learning(target);
                assert_eq!(changed.target, target);
                changed.check().unwrap();
                changed.learning(from.target).check().unwrap();
                assert_eq!(
                    (changed.network, changed.target_cells, changed.seed),
                    (from.network, from.target_cells, from.seed),
                    "only what the learners do not share changes"
                );
            }
            assert_eq!(from.learning(from.target), from);
        }
        assert_eq!(
            FitParams::paper().learning(Target::Visibility).gating,
            Gating::Faces
        );
        assert!(FitParams::default().learning(Target::Zeta).refit);
    }
}
