//! Which learner runs: the three the viewer can watch learn, named as everywhere else
//! ([`flatland_methods::Method`]: `light`, `visibility`, `paper`), the one choice the controls,
//! `--learner`, the saved settings and the learner's thread share.

use flatland_methods::{Method, MethodError};
use kernel_fit::Preset;
use serde::{Deserialize, Serialize};

/// A learner the viewer runs. Its name and label are its [`Method`]'s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Learner {
    /// The light-driven learner ([`flatland_light::LightFit`], docs/ALGORITHM.md §4a): rounds of
    /// solving and probing where the uncertain light flows. What `flatland solve` runs.
    #[default]
    Light,
    /// The visibility network ([`Preset::Visibility`]): cells learn V in faces, trained step by
    /// step.
    // Settings saved when the viewer offered "light or network" and a preset read back as the
    // network; `Settings::upgraded` then takes the saved preset's network.
    #[serde(alias = "Network")]
    Visibility,
    /// The paper's network ([`Preset::Paper`]): cells learn ζ, trained step by step, refit at
    /// the end.
    Paper,
}

impl Learner {
    /// Every learner, in the order the controls offer them.
    pub const ALL: [Learner; 3] = [Learner::Light, Learner::Visibility, Learner::Paper];

    /// The method it is.
    #[must_use]
    pub fn method(self) -> Method {
        match self {
            Learner::Light => Method::Light,
            Learner::Visibility => Method::Visibility,
            Learner::Paper => Method::Paper,
        }
    }

    /// Its one name (`light`, `visibility`, `paper`): `--learner`, file names.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.method().name()
    }

    /// What it is, in a few words (the controls' label).
    #[must_use]
    pub fn title(self) -> &'static str {
        self.method().title()
    }

    /// The network's parameter preset; `None` for the light-driven learner, which has no
    /// network.
    #[must_use]
    pub fn preset(self) -> Option<Preset> {
        match self {
            Learner::Light => None,
            Learner::Visibility | Learner::Paper => self.method().preset(),
        }
    }

    /// The network that learns with `preset`'s parameters.
    #[must_use]
    pub fn of_preset(preset: Preset) -> Learner {
        match preset {
            Preset::Visibility => Learner::Visibility,
            Preset::Paper => Learner::Paper,
        }
    }

    /// The learner `method` is; any other method is refused naming the three.
    pub fn of_method(method: Method) -> Result<Learner, MethodError> {
        Learner::ALL
            .into_iter()
            .find(|l| l.method() == method)
            .ok_or(MethodError::NotOneOf {
                method: method.name(),
                what: "a learner the viewer runs",
                valid: "light, visibility or paper",
            })
    }

    /// Parses a learner's name through [`Method::parse`]: a retired name (`theta`) is refused
    /// with the one to write now, a method that is not one of the three with the three.
    pub fn parse(text: &str) -> Result<Learner, MethodError> {
        Learner::of_method(Method::parse(text)?)
    }
}

impl std::fmt::Display for Learner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_learner_parses_back_by_its_methods_name() {
        for learner in Learner::ALL {
            assert_eq!(Learner::parse(learner.name()).unwrap(), learner);
            assert_eq!(learner.title(), learner.method().title());
            assert_eq!(learner.to_string(), learner.name());
        }
        assert_eq!(
            Learner::ALL.map(Learner::name),
            ["light", "visibility", "paper"]
        );
        for preset in Preset::ALL {
            assert_eq!(Learner::of_preset(preset).preset(), Some(preset));
        }
        assert_eq!(Learner::Light.preset(), None);
    }

    #[test]
    fn retired_names_and_other_methods_are_refused_saying_what_is_valid() {
        let theta = Learner::parse("theta").unwrap_err().to_string();
        assert!(
            theta.contains("`theta`") && theta.contains("`visibility`"),
            "{theta}"
        );
        let hr = Learner::parse("hr").unwrap_err().to_string();
        assert!(
            hr.contains("`hr`") && hr.contains("light, visibility or paper"),
            "{hr}"
        );
        let norefit = Learner::parse("paper-norefit").unwrap_err().to_string();
        assert!(norefit.contains("light, visibility or paper"), "{norefit}");
        let unknown = Learner::parse("network").unwrap_err().to_string();
        assert!(
            unknown.contains("`network`") && unknown.contains("visibility"),
            "{unknown}"
        );
    }
}
