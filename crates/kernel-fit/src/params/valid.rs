//! [`FitParams::check`], the one place a fit's parameters are validated: values out of range
//! and combinations that mean nothing are refused, and the rest become the learner's variant
//! ([`Head`]) and the parameters by lifetime — fixed when a fit starts, live while it runs,
//! and how it is measured.

use sgcs::schema::Schema;

use crate::{FitError, FitParams, Gating, Resampling, Target};

/// The learner's variant: what the network learns, and what only that learner has. Chosen
/// once, by [`FitParams::check`]; where learners behave differently, code matches on this
/// (or on what a fit built from it), never on a flag.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Head {
    /// The paper's: the network learns ζ itself from `γ(s, t)`.
    Zeta {
        /// The least-squares refit that ends the fit, if any.
        refit: Option<Refit>,
    },
    /// The network learns k, and `ζ̃ = E' · k̃` with the emission `E'` exact.
    FactoredEmission {
        /// The least-squares refit that ends the fit, if any.
        refit: Option<Refit>,
    },
    /// The visibility network's: the network learns the visibility `V` on the pairs of surface
    /// edges where geometry cannot decide it, and `ζ̃ = ζ_unoccluded · Ṽ`.
    Visibility(VisibilityParams),
}

impl Head {
    /// The [`Target`] files name this learner by.
    pub fn target(&self) -> Target {
        match self {
            Head::Zeta { .. } => Target::Zeta,
            Head::FactoredEmission { .. } => Target::FactoredEmission,
            Head::Visibility(_) => Target::Visibility,
        }
    }

    /// The refit that ends a fit with this head; `None` when it has none (the visibility
    /// learner's local rule leaves nothing to refit).
    pub fn refit(&self) -> Option<Refit> {
        match self {
            Head::Zeta { refit } | Head::FactoredEmission { refit } => *refit,
            Head::Visibility(_) => None,
        }
    }
}

/// The least-squares refit of every output weight that ends a fit of ζ or k.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refit {
    /// The smallest ridge weight it tries ([`FitParams::ridge`]).
    pub ridge: f64,
}

/// What only the visibility learner has.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityParams {
    /// Which known discontinuities no cell may straddle ([`FitParams::gating`]).
    pub gating: Gating,
    /// The share of samples drawn by importance ([`FitParams::importance`]).
    pub importance: f64,
    /// Whether a sample's error counts with its importance weight ([`FitParams::weighted`]).
    pub weighted: bool,
}

/// The network's rules: how its outputs combine and learn, where and with what it grows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NetworkRules {
    /// [`sgcs::Params::output_rule`].
    pub output_rule: sgcs::OutputRule,
    /// [`sgcs::Params::insert_rule`].
    pub insert_rule: sgcs::InsertRule,
    /// [`sgcs::Params::output_mode`].
    pub output_mode: sgcs::OutputMode,
    /// [`sgcs::Params::insertion`].
    pub insertion: sgcs::Insertion,
    /// [`sgcs::Params::resource`].
    pub resource: sgcs::Resource,
}

/// The network's rates, which it takes while it runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NetworkRates {
    /// ε_b ([`sgcs::Params::eps_b`]).
    pub eps_b: f64,
    /// ε_n ([`sgcs::Params::eps_n`]).
    pub eps_n: f64,
    /// η ([`sgcs::Params::eta`]).
    pub eta: f64,
    /// α ([`sgcs::Params::alpha`]).
    pub alpha: f64,
    /// λ ([`sgcs::Params::lambda`]).
    pub lambda: u32,
    /// [`sgcs::Params::activation_cutoff`].
    pub activation_cutoff: f64,
}

/// Fixed when a fit starts: a change means a new fit (the network would learn another thing,
/// or S₀ and the seed streams would be other ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedParams {
    /// The learner's variant.
    pub head: Head,
    /// The network's rules.
    pub rules: NetworkRules,
    /// |S₀| ([`FitParams::initial_samples`]; also the smallest new S₀ of a changed scene).
    pub initial_samples: usize,
    /// The seed of every random choice.
    pub seed: u64,
}

/// What may change while a fit runs ([`Fit::set_params`](crate::Fit::set_params)): when it
/// stops, how fast the network learns and grows, and how new sample sets are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveParams {
    /// [`FitParams::target_cells`] (also the network's `max_cells`).
    pub target_cells: usize,
    /// [`FitParams::max_steps`].
    pub max_steps: u64,
    /// [`FitParams::ray_budget`].
    pub ray_budget: u64,
    /// [`FitParams::target_error`].
    pub target_error: f64,
    /// The network's rates.
    pub rates: NetworkRates,
    /// ω ([`FitParams::omega`]).
    pub omega: f64,
    /// φ ([`FitParams::phi`]).
    pub phi: f64,
    /// ψ ([`FitParams::psi`]).
    pub psi: f64,
    /// [`FitParams::min_set_size`].
    pub min_set_size: usize,
    /// [`FitParams::scan_factor`].
    pub scan_factor: usize,
    /// [`FitParams::resampling`].
    pub resampling: Resampling,
}

/// How a fit is measured: the held-out points of the reference it is given (whoever builds
/// the reference uses this count) and the steps between two points of its learning curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// [`FitParams::heldout`].
    pub heldout: usize,
    /// [`FitParams::eval_every`].
    pub eval_every: u64,
}

/// [`FitParams`] checked: the learner's variant and every parameter by lifetime.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValidParams {
    /// Fixed when the fit starts.
    pub fixed: FixedParams,
    /// Live while it runs.
    pub live: LiveParams,
    /// How it is measured.
    pub measurement: Measurement,
}

impl ValidParams {
    /// The network's parameters: its rules, its rates, and the target cells as `max_cells`.
    pub fn network(&self) -> sgcs::Params {
        let (rules, rates) = (self.fixed.rules, self.live.rates);
        sgcs::Params {
            eps_b: rates.eps_b,
            eps_n: rates.eps_n,
            eta: rates.eta,
            alpha: rates.alpha,
            lambda: rates.lambda,
            max_cells: self.live.target_cells,
            activation_cutoff: rates.activation_cutoff,
            output_rule: rules.output_rule,
            insert_rule: rules.insert_rule,
            output_mode: rules.output_mode,
            insertion: rules.insertion,
            resource: rules.resource,
        }
    }
}

impl FitParams {
    /// Checks every value against [`FitParams::specs`] (the error names the first parameter
    /// out of range and the range), then refuses a combination that means nothing (the error
    /// names both parameters and what would be valid), and splits the rest by lifetime.
    pub fn check(&self) -> Result<ValidParams, FitError> {
        if let Some((spec, value)) = self.invalid() {
            return Err(FitError::OutOfRange {
                name: spec.name,
                value: value.to_string(),
                range: spec.range.to_string(),
            });
        }
        if self.target_error > 0.0 && self.eval_every == 0 {
            return Err(FitError::Meaningless {
                name: "target_error",
                value: self.target_error.to_string(),
                other: "eval_every",
                other_value: "0".to_owned(),
                valid: "the target error is checked when the held-out error is measured, every \
                        eval_every steps; with eval_every = 0 target_error must be 0",
            });
        }
        Ok(ValidParams {
            fixed: FixedParams {
                head: self.head()?,
                rules: NetworkRules {
                    output_rule: self.network.output_rule,
                    insert_rule: self.network.insert_rule,
                    output_mode: self.network.output_mode,
                    insertion: self.network.insertion,
                    resource: self.network.resource,
                },
                initial_samples: self.initial_samples,
                seed: self.seed,
            },
            live: self.live(),
            measurement: Measurement {
                heldout: self.heldout,
                eval_every: self.eval_every,
            },
        })
    }

    /// [`check`](FitParams::check), keeping only the verdict.
    pub fn validate(&self) -> Result<(), FitError> {
        self.check().map(|_| ())
    }

    /// The learner's variant, refusing what only another learner has.
    fn head(&self) -> Result<Head, FitError> {
        let refit = self.refit.then_some(Refit { ridge: self.ridge });
        let head = match self.target {
            Target::Zeta => Head::Zeta { refit },
            Target::FactoredEmission => Head::FactoredEmission { refit },
            Target::Visibility if self.refit => {
                return Err(self.meaningless(
                    "refit",
                    "true",
                    "the visibility learner's local rule leaves nothing to refit (each cell \
                     holds the mean V of its face); with target = visibility refit must be false",
                ));
            }
            Target::Visibility => {
                return Ok(Head::Visibility(VisibilityParams {
                    gating: self.gating,
                    importance: self.importance,
                    weighted: self.weighted,
                }));
            }
        };
        if self.gating != Gating::Off {
            return Err(self.meaningless(
                "gating",
                self.gating.name(),
                "only the visibility learner (target = visibility) has faces or pairs to gate \
                 its cells by; with another target gating must be off",
            ));
        }
        if self.importance != 0.0 {
            return Err(self.meaningless(
                "importance",
                &self.importance.to_string(),
                "only the visibility learner (target = visibility) draws samples by importance; \
                 with another target importance must be 0",
            ));
        }
        if self.weighted {
            return Err(self.meaningless(
                "weighted",
                "true",
                "only the visibility learner (target = visibility) weights its samples' errors; \
                 with another target weighted must be false",
            ));
        }
        Ok(head)
    }

    /// `name = value` means nothing with this target.
    fn meaningless(&self, name: &'static str, value: &str, valid: &'static str) -> FitError {
        FitError::Meaningless {
            name,
            value: value.to_owned(),
            other: "target",
            other_value: self.target.name().to_owned(),
            valid,
        }
    }

    /// The part that may change while a fit runs (not checked; see [`FitParams::check`]).
    pub fn live(&self) -> LiveParams {
        let n = &self.network;
        LiveParams {
            target_cells: self.target_cells,
            max_steps: self.max_steps,
            ray_budget: self.ray_budget,
            target_error: self.target_error,
            rates: NetworkRates {
                eps_b: n.eps_b,
                eps_n: n.eps_n,
                eta: n.eta,
                alpha: n.alpha,
                lambda: n.lambda,
                activation_cutoff: n.activation_cutoff,
            },
            omega: self.omega,
            phi: self.phi,
            psi: self.psi,
            min_set_size: self.min_set_size,
            scan_factor: self.scan_factor,
            resampling: self.resampling,
        }
    }

    /// These parameters with the live part replaced by `live`. Parameters that differ from
    /// `self.with_live(other.live())` differ in what only a new fit can change.
    #[must_use]
    pub fn with_live(self, live: LiveParams) -> FitParams {
        let rates = live.rates;
        FitParams {
            network: sgcs::Params {
                eps_b: rates.eps_b,
                eps_n: rates.eps_n,
                eta: rates.eta,
                alpha: rates.alpha,
                lambda: rates.lambda,
                activation_cutoff: rates.activation_cutoff,
                ..self.network
            },
            target_cells: live.target_cells,
            max_steps: live.max_steps,
            ray_budget: live.ray_budget,
            target_error: live.target_error,
            omega: live.omega,
            phi: live.phi,
            psi: live.psi,
            min_set_size: live.min_set_size,
            scan_factor: live.scan_factor,
            resampling: live.resampling,
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// Each combination that some learner would silently ignore is refused, naming both
    /// parameters and the value that would be valid.
    #[test]
    fn meaningless_combinations_are_refused_naming_both_parameters() {
        let (paper, default) = (FitParams::paper(), FitParams::default());
        let factored = FitParams {
            target: Target::FactoredEmission,
            ..paper
        };
        let cases: [(FitParams, [&str; 3]); 8] = [
            (
                FitParams {
                    gating: Gating::Faces,
                    ..paper
                },
                ["`gating` is faces", "`target` = zeta", "gating must be off"],
            ),
            (
                FitParams {
                    gating: Gating::Pairs,
                    ..factored
                },
                ["`gating`", "`target` = factored_emission", "must be off"],
            ),
            (
                FitParams {
                    importance: 0.7,
                    ..paper
                },
                [
                    "`importance` is 0.7",
                    "`target` = zeta",
                    "importance must be 0",
                ],
            ),
            (
                FitParams {
                    weighted: true,
                    ..factored
                },
                ["`weighted` is true", "`target`", "weighted must be false"],
            ),
            (
                FitParams {
                    refit: true,
                    ..default
                },
                [
                    "`refit` is true",
                    "`target` = visibility",
                    "refit must be false",
                ],
            ),
            (
                FitParams {
                    target: Target::Zeta,
                    ..default
                },
                ["`gating` is faces", "`target` = zeta", "must be off"],
            ),
            (
                FitParams {
                    target_error: 0.1,
                    eval_every: 0,
                    ..default
                },
                [
                    "`target_error` is 0.1",
                    "`eval_every` = 0",
                    "target_error must be 0",
                ],
            ),
            (
                FitParams {
                    target_error: 0.1,
                    eval_every: 0,
                    ..paper
                },
                ["`target_error`", "`eval_every`", "must be 0"],
            ),
        ];
        for (params, needles) in cases {
            let msg = params.check().unwrap_err().to_string();
            assert!(!msg.contains('\n'), "{msg}");
            for needle in needles {
                assert!(msg.contains(needle), "`{needle}` missing from: {msg}");
            }
        }
        // What the presets combine means something, and each head keeps its own fields.
        let head = default.check().unwrap().fixed.head;
        assert_eq!(
            head,
            Head::Visibility(VisibilityParams {
                gating: Gating::Faces,
                importance: 0.7,
                weighted: true,
            })
        );
        assert_eq!(head.refit(), None);
        let head = paper.check().unwrap().fixed.head;
        assert_eq!(head.refit(), Some(Refit { ridge: 1e-6 }));
        assert_eq!(head.target(), Target::Zeta);
        let no_refit = FitParams {
            refit: false,
            ..factored
        };
        assert_eq!(
            no_refit.check().unwrap().fixed.head,
            Head::FactoredEmission { refit: None }
        );
    }

    /// Every parameter belongs to one lifetime: changing it changes exactly that part, and
    /// the live part goes back into the parameters it came from.
    #[test]
    fn every_parameter_has_one_lifetime() {
        use sgcs::schema::Schema as _;
        let base = FitParams::paper();
        let valid = base.check().unwrap();
        assert_eq!(base.with_live(base.live()), base);
        assert_eq!(valid.network(), {
            let mut n = base.network;
            n.max_cells = base.target_cells;
            n
        });
        let live = [
            "target_cells",
            "max_steps",
            "ray_budget",
            "target_error",
            "omega",
            "phi",
        ];
        let live = live
            .into_iter()
            .chain([
                "psi",
                "min_set_size",
                "scan_factor",
                "eps_b",
                "eps_n",
                "eta",
            ])
            .chain(["alpha", "lambda", "activation_cutoff"]);
        let groups: Vec<(&str, Vec<&str>)> = vec![
            ("live", live.collect()),
            ("fixed", vec!["initial_samples", "ridge", "importance"]),
            ("measurement", vec!["heldout", "eval_every"]),
        ];
        let listed: usize = groups.iter().map(|g| g.1.len()).sum();
        assert_eq!(listed, FitParams::specs().len(), "every numeric parameter");
        for (group, names) in &groups {
            for &name in names {
                // The importance means something to the visibility learner only.
                let base = match name {
                    "importance" => FitParams::default(),
                    _ => base,
                };
                let valid = base.check().unwrap();
                let spec = FitParams::spec(name).unwrap();
                let value = base.get(name).unwrap();
                let other = [value / 2.0, value * 2.0, value + 1.0, value - 1.0, 0.5]
                    .into_iter()
                    .find(|&v| {
                        v != value
                            && spec.range.contains(v)
                            && (!spec.range.integer || v.fract() == 0.0)
                    })
                    .unwrap();
                let mut changed = base;
                assert!(changed.set(name, other));
                let now = changed.check().unwrap();
                let differs = [
                    ("live", now.live != valid.live),
                    ("fixed", now.fixed != valid.fixed),
                    ("measurement", now.measurement != valid.measurement),
                ];
                let which: Vec<&str> = differs.iter().filter(|d| d.1).map(|d| d.0).collect();
                assert_eq!(which, [*group], "{name}");
                assert_eq!(
                    base.with_live(changed.live()) == changed,
                    *group == "live",
                    "{name}"
                );
            }
        }
        // The choices: the head, the network's rules and the seed are fixed; resampling is live.
        let fixed_choices = [
            FitParams { seed: 9, ..base },
            FitParams {
                refit: false,
                ..base
            },
            base.learning(Target::Visibility),
            FitParams {
                network: sgcs::Params {
                    insertion: sgcs::Insertion::WorstSample,
                    ..base.network
                },
                ..base
            },
        ];
        for changed in fixed_choices {
            let now = changed.check().unwrap();
            assert!(
                now.fixed != valid.fixed && now.live == valid.live,
                "{changed:?}"
            );
        }
        let uniform = FitParams {
            resampling: Resampling::Uniform,
            ..base
        };
        assert_eq!(base.with_live(uniform.live()), uniform);
    }
}
