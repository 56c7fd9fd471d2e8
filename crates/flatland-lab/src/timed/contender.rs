//! The methods `flatland bench` times against each other, and their names.

use crate::LabError;

/// A method of the timed bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Contender {
    /// The light-driven learner ([`flatland_light::LightFit`]), swept by tolerance.
    Default,
    /// The θ-driven learner `flatland fit` trains, swept by cells.
    FirstShot,
    /// The paper's network with the least-squares output refit.
    Paper,
    /// The paper's network with its delta-rule output weights only (the same fit as `paper`).
    PaperNoRefit,
    /// Hierarchical radiosity, from its initial linking upwards.
    Hr,
    /// Hierarchical radiosity with clustering: refined from one link, no initial linking.
    Clustered,
    /// Piecewise constant on a g × g grid.
    Uniform,
    /// The exact kernel solved on growing element counts.
    Exact,
    /// The Monte Carlo light tracer at growing photon counts.
    Tracer,
}

/// Names the methods had before, still accepted.
const ALIASES: [(&str, Contender); 4] = [
    ("sgcs", Contender::Default),
    ("sgcs-paper", Contender::Paper),
    ("sgcs-paper-norefit", Contender::PaperNoRefit),
    ("sgcs-paper-no-refit", Contender::PaperNoRefit),
];

/// What an unknown name is told.
const VALID: &str = "a comma-separated list of default, first-shot, paper, paper-norefit, hr, clustered, uniform, exact, tracer";

impl Contender {
    /// Every method, in the order the bench runs and lists them.
    pub const ALL: [Contender; 9] = [
        Contender::Default,
        Contender::FirstShot,
        Contender::Paper,
        Contender::PaperNoRefit,
        Contender::Hr,
        Contender::Clustered,
        Contender::Uniform,
        Contender::Exact,
        Contender::Tracer,
    ];

    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Contender::Default => "default",
            Contender::FirstShot => "first-shot",
            Contender::Paper => "paper",
            Contender::PaperNoRefit => "paper-norefit",
            Contender::Hr => "hr",
            Contender::Clustered => "clustered",
            Contender::Uniform => "uniform",
            Contender::Exact => "exact",
            Contender::Tracer => "tracer",
        }
    }

    /// Parses [`Contender::name`] or an old name (`sgcs` is `default`).
    pub fn parse(name: &str) -> Result<Contender, LabError> {
        Contender::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .or_else(|| ALIASES.iter().find(|a| a.0 == name).map(|a| a.1))
            .ok_or_else(|| LabError::InvalidParameter {
                name: "methods",
                value: name.to_owned(),
                valid: VALID,
            })
    }

    /// Whether its result depends on a seed (run once per seed); the others run once.
    pub fn seeded(self) -> bool {
        !matches!(self, Contender::Default | Contender::Exact)
    }

    /// Whether it is swept over budgets of basis functions.
    pub fn budgeted(self) -> bool {
        matches!(
            self,
            Contender::FirstShot
                | Contender::Paper
                | Contender::PaperNoRefit
                | Contender::Hr
                | Contender::Clustered
                | Contender::Uniform
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_old_names_parse() {
        for m in Contender::ALL {
            assert_eq!(Contender::parse(m.name()).unwrap(), m);
        }
        for (old, m) in ALIASES {
            assert_eq!(Contender::parse(old).unwrap(), m);
        }
        let msg = Contender::parse("nope").unwrap_err().to_string();
        assert!(
            msg.contains("first-shot") && msg.contains("clustered") && msg.contains("tracer"),
            "{msg}"
        );
    }
}
