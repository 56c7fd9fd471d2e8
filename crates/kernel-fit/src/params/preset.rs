//! The two networks' parameter sets: the visibility network and the paper's network.

use serde::{Deserialize, Serialize};

use crate::{FitError, FitParams};

/// A named set of [`FitParams`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// The visibility network ([`FitParams::default`]): the network learns only
    /// the visibility, on the pairs of surface edges where geometry cannot decide it; the
    /// exact unoccluded kernel does the rest. Its cells never straddle a visibility
    /// discontinuity, so it improves on the paper's network at a faster rate.
    #[default]
    // Settings the viewer saved before the network had its name read back as it.
    #[serde(alias = "default")]
    Visibility,
    /// The paper's network ([`FitParams::paper`]): SGCS learns ζ itself from `γ(s, t)`, with
    /// the paper's parameters, plus this project's stability fixes and least-squares refit.
    Paper,
}

impl Preset {
    /// Every preset, in the order tables list them.
    pub const ALL: [Preset; 2] = [Preset::Visibility, Preset::Paper];

    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Visibility => "visibility",
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
                valid: "visibility or paper",
            })
    }

    /// The preset's parameters.
    pub fn params(self) -> FitParams {
        match self {
            Preset::Visibility => FitParams::default(),
            Preset::Paper => FitParams::paper(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Target;

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
}
