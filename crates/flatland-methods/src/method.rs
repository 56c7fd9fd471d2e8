//! The one name of every method: the enum, its words, and the names it no longer answers to.

use std::fmt;

use clap::ValueEnum;
use kernel_fit::Preset;
use serde::{Deserialize, Serialize};

/// A way to light a scene: a representation of the kernel (exact, learned, or a baseline's) or
/// the Monte Carlo tracer. The one name each has on the command line (`solve --kernel`, `bench
/// --methods`, `view --learner`), in CSV files, in the docs and in the viewer.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, ValueEnum, Serialize, Deserialize,
)]
#[serde(rename_all = "kebab-case")]
#[value(rename_all = "kebab-case")]
pub enum Method {
    /// The exact kernel: closed-form transfer of each visible piece, no rays.
    Exact,
    /// The light-driven learner: exact views (probes) of points along the surfaces, grown where
    /// the uncertain light flows, until its own error estimate meets a tolerance.
    Light,
    /// The visibility network: growing cells learn V where geometry cannot decide it, in faces
    /// cut by the blockers' shadow lines; the unoccluded kernel stays exact.
    Visibility,
    /// The paper's network: growing Gaussian cells learn ζ itself from γ(s, t), θ-resampled,
    /// ended by a least-squares refit of the output weights.
    Paper,
    /// The paper's network as its delta rule left it, before the refit (the same fit).
    PaperNorefit,
    /// Hierarchical radiosity, refined from its initial linking.
    Hr,
    /// Hierarchical radiosity with clustering: refined from one link of the root cluster.
    Clustered,
    /// A g × g grid over (s, t), each block the mean of 20 rays.
    Uniform,
    /// The same grid, each block the exact mean of k.
    UniformExact,
    /// The Monte Carlo light tracer: photons from the emitters, no kernel at all.
    Tracer,
    /// The learned transport of the later bounces, for one scene lit again and again
    /// (`flatland relight`): the exact direct light and first bounce, a learned operator for
    /// the light that bounces twice or more. Not built yet: named so that commands refuse it
    /// with that reason.
    Transport,
    /// A uniform grid of precomputed light positions (what game light-probe grids do), given
    /// the learned transport's bytes: the later bounces of a unit light stored at each, blended
    /// at a move from the probes nearest the light. Relights only, like the transport.
    Probes,
}

/// What a method is, for the tables that sort and sweep them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// The exact kernel.
    Exact,
    /// A learner of this project or the paper.
    Learner,
    /// A baseline it is measured against.
    Baseline,
}

/// The knob a method is swept over when it is timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knob {
    /// The tolerance on its own error estimate (the light-driven learner).
    Tolerance,
    /// Basis functions: cells, links or blocks.
    Budget,
    /// Elements of the mesh (the exact kernel).
    Elements,
    /// Photons (the tracer).
    Photons,
}

impl Method {
    /// Every method, in the order tables list them.
    pub const ALL: [Method; 12] = [
        Method::Light,
        Method::Visibility,
        Method::Paper,
        Method::PaperNorefit,
        Method::Hr,
        Method::Clustered,
        Method::Uniform,
        Method::UniformExact,
        Method::Exact,
        Method::Tracer,
        Method::Transport,
        Method::Probes,
    ];

    /// Its one name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::Light => "light",
            Method::Visibility => "visibility",
            Method::Paper => "paper",
            Method::PaperNorefit => "paper-norefit",
            Method::Hr => "hr",
            Method::Clustered => "clustered",
            Method::Uniform => "uniform",
            Method::UniformExact => "uniform-exact",
            Method::Tracer => "tracer",
            Method::Transport => "transport",
            Method::Probes => "probes",
        }
    }

    /// What it is, in a few words (the viewer's label, a table's legend).
    #[must_use]
    pub fn title(self) -> &'static str {
        match self {
            Method::Exact => "exact kernel",
            Method::Light => "light-driven learner",
            Method::Visibility => "visibility network",
            Method::Paper => "paper's network",
            Method::PaperNorefit => "paper's network before its refit",
            Method::Hr => "hierarchical radiosity",
            Method::Clustered => "clustered HR",
            Method::Uniform => "uniform grid",
            Method::UniformExact => "uniform grid of exact means",
            Method::Tracer => "Monte Carlo tracer",
            Method::Transport => "learned transport of the later bounces",
            Method::Probes => "uniform grid of light-position probes",
        }
    }

    /// The error refusing this method where one lighting is asked for: it relights only.
    #[must_use]
    pub fn relight_only(self) -> crate::MethodError {
        let command = match self {
            Method::Probes => "flatland bench --relight",
            _ => "flatland relight --kernel transport",
        };
        crate::MethodError::RelightOnly(self.name(), self.title(), command)
    }

    /// Parses [`Method::name`] (clap's `ValueEnum` parser); a name the project used before
    /// gets an error naming the new one, any other an error listing the valid names.
    pub fn parse(text: &str) -> Result<Method, crate::MethodError> {
        if let Some(retired) = Retired::of(text) {
            return Err(crate::MethodError::Retired {
                name: text.to_owned(),
                now: retired.now,
            });
        }
        Method::from_str(text, false).map_err(|_| crate::MethodError::Unknown {
            name: text.to_owned(),
            valid: Method::ALL.map(Method::name).join(", "),
        })
    }

    /// Exact, learner or baseline.
    #[must_use]
    pub fn family(self) -> Family {
        match self {
            Method::Exact => Family::Exact,
            Method::Light
            | Method::Visibility
            | Method::Paper
            | Method::PaperNorefit
            | Method::Transport => Family::Learner,
            Method::Hr
            | Method::Clustered
            | Method::Uniform
            | Method::UniformExact
            | Method::Tracer
            | Method::Probes => Family::Baseline,
        }
    }

    /// What it is swept over when timed.
    #[must_use]
    pub fn knob(self) -> Knob {
        match self {
            Method::Exact => Knob::Elements,
            Method::Light => Knob::Tolerance,
            Method::Tracer => Knob::Photons,
            _ => Knob::Budget,
        }
    }

    /// Whether it lights a scene once (`solve`, `bench`): every method but the learned
    /// transport and the probe grid, which relight one scene for a moving light (`flatland
    /// relight`, `bench --relight`).
    #[must_use]
    pub fn lights_once(self) -> bool {
        !matches!(self, Method::Transport | Method::Probes)
    }

    /// Whether it is swept over budgets of basis functions.
    #[must_use]
    pub fn budgeted(self) -> bool {
        self.knob() == Knob::Budget
    }

    /// Whether its result depends on a seed (run once per seed); the others run once.
    #[must_use]
    pub fn seeded(self) -> bool {
        !matches!(self, Method::Light | Method::Exact | Method::UniformExact)
    }

    /// The network's parameter preset, for the two networks `flatland fit` trains.
    #[must_use]
    pub fn preset(self) -> Option<Preset> {
        match self {
            Method::Visibility => Some(Preset::Visibility),
            Method::Paper | Method::PaperNorefit => Some(Preset::Paper),
            _ => None,
        }
    }

    /// Parses the name of a network `flatland fit` trains (`visibility` or `paper`) into its
    /// preset; any other method is refused with what is valid.
    pub fn parse_network(text: &str) -> Result<Preset, crate::MethodError> {
        match Method::parse(text)? {
            m @ (Method::Visibility | Method::Paper) => Ok(m.preset().expect("a network")),
            method => Err(crate::MethodError::NotOneOf {
                method: method.name(),
                what: "a network `flatland fit` trains",
                valid: "visibility or paper (the paper's network without its refit: paper with \
                        --no-refit)",
            }),
        }
    }

    /// The method a network preset trains.
    #[must_use]
    pub fn of_preset(preset: Preset) -> Method {
        match preset {
            Preset::Visibility => Method::Visibility,
            Preset::Paper => Method::Paper,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name a method had before it got its one name, and what to say to a script that still
/// uses it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Retired {
    /// The old spelling.
    pub name: &'static str,
    /// What to write instead.
    pub now: &'static str,
}

impl Retired {
    /// Every retired spelling. `default` and `sgcs` named the light-driven learner in `solve`
    /// and `bench` but the visibility network in `fit`: their message names both.
    pub const ALL: [Retired; 8] = [
        Retired {
            name: "default",
            now: "`light` (the light-driven learner `solve` and `bench` ran) or `visibility` (the \
                  network `fit` trained)",
        },
        Retired {
            name: "sgcs",
            now: "`light` (the light-driven learner `solve` and `bench` ran) or `visibility` (the \
                  network `fit` trained)",
        },
        Retired {
            name: "first-shot",
            now: "`visibility`",
        },
        Retired {
            name: "theta",
            now: "`visibility`",
        },
        Retired {
            name: "sgcs-paper",
            now: "`paper`",
        },
        Retired {
            name: "sgcs-paper-norefit",
            now: "`paper-norefit`",
        },
        Retired {
            name: "sgcs-paper-no-refit",
            now: "`paper-norefit`",
        },
        Retired {
            name: "light-driven",
            now: "`light`",
        },
    ];

    /// The retired spelling `text` is, if it is one.
    #[must_use]
    pub fn of(text: &str) -> Option<Retired> {
        Retired::ALL.into_iter().find(|r| r.name == text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_back_and_clap_agrees() {
        for m in Method::ALL {
            assert_eq!(Method::parse(m.name()).unwrap(), m);
            assert_eq!(Method::from_str(m.name(), false).unwrap(), m, "clap's name");
            let json = serde_json_name(m);
            assert_eq!(json, m.name(), "serde's name");
        }
        assert_eq!(Method::ALL.len(), Method::value_variants().len());
    }

    #[test]
    fn retired_names_are_refused_with_the_new_one() {
        let msg = Method::parse("first-shot").unwrap_err().to_string();
        assert!(
            msg.contains("`first-shot`") && msg.contains("`visibility`"),
            "{msg}"
        );
        let msg = Method::parse("default").unwrap_err().to_string();
        assert!(
            msg.contains("`light`") && msg.contains("`visibility`"),
            "{msg}"
        );
        // No retired name is a name again.
        for r in Retired::ALL {
            assert!(Method::ALL.iter().all(|m| m.name() != r.name), "{}", r.name);
        }
        let msg = Method::parse("hrr").unwrap_err().to_string();
        assert!(msg.contains("exact, ") && msg.contains("tracer"), "{msg}");
    }

    #[test]
    fn only_the_networks_parse_as_networks() {
        assert_eq!(
            Method::parse_network("visibility").unwrap(),
            Preset::Visibility
        );
        assert_eq!(Method::parse_network("paper").unwrap(), Preset::Paper);
        let msg = Method::parse_network("hr").unwrap_err().to_string();
        assert!(
            msg.contains("`hr`") && msg.contains("visibility or paper"),
            "{msg}"
        );
        let msg = Method::parse_network("default").unwrap_err().to_string();
        assert!(msg.contains("`visibility`"), "{msg}");
    }

    #[test]
    fn the_transport_is_named_and_refused_where_one_lighting_is_asked_for() {
        assert_eq!(Method::parse("transport").unwrap(), Method::Transport);
        assert!(
            Method::ALL
                .iter()
                .all(|m| m.lights_once() != matches!(m, Method::Transport | Method::Probes))
        );
        let msg = Method::Transport.relight_only().to_string();
        assert_eq!(
            msg,
            "`transport` (learned transport of the later bounces) is for a moving light: run \
             `flatland relight --kernel transport`"
        );
    }

    #[test]
    fn the_networks_have_presets_and_back() {
        for preset in Preset::ALL {
            assert_eq!(Method::of_preset(preset).preset(), Some(preset));
        }
        assert_eq!(Method::Light.preset(), None);
    }

    fn serde_json_name(m: Method) -> String {
        serde_json::to_string(&m)
            .unwrap()
            .trim_matches('"')
            .to_owned()
    }
}
