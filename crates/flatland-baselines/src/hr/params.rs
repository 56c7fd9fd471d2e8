//! HR's settings: the oracle, the link estimate, F_ε, the minimum length and the link cap,
//! checked in one place.

use crate::BaselineError;

/// How a link's mean ζ is estimated from its rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum LinkEstimate {
    /// Exact unoccluded mean times a G-weighted visible fraction from the rays (Hanrahan's
    /// form factor × visibility). Exact for unoccluded links.
    FormFactorVisibility,
    /// Plain mean of ζ over the rays.
    SampleMean,
}

/// What the refinement oracle compares with F_ε.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Oracle {
    /// The unoccluded form factors `F_pq`, `F_qp` (Hanrahan's F refinement).
    FormFactor,
    /// The form factors times `E'(i) ρ(j) / max E'`: the transfer the link carries into ζ,
    /// the analogue of Hanrahan's brightness-weighted ("BF") refinement for the target ζ, whose
    /// emitter rows are 100× the others'.
    Weighted,
}

/// Settings of hierarchical radiosity.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HrParams {
    /// Form-factor threshold F_ε of the oracle, > 0. Smaller refines more.
    pub f_eps: f64,
    /// Minimum element length as a fraction of the total surface length L, in (0, 1).
    pub min_length: f64,
    /// Rays per final link (default 20, the paper's comparison).
    pub rays_per_link: usize,
    /// What the oracle compares with F_ε.
    pub oracle: Oracle,
    /// How a link's value is estimated from its rays.
    pub estimate: LinkEstimate,
    /// Refuse to build more links than this: a budget above it, or an initial linking or a
    /// refinement past it, is an error naming it (the ×1000 scene needs ~10⁷ initial links; a
    /// link keeps about 32 bytes, and `rays_per_link` rays are cast for it).
    pub max_links: usize,
}

impl Default for HrParams {
    fn default() -> Self {
        HrParams {
            f_eps: 0.05,
            min_length: 1.0 / 1024.0,
            rays_per_link: 20,
            oracle: Oracle::Weighted,
            estimate: LinkEstimate::FormFactorVisibility,
            max_links: 2_000_000,
        }
    }
}

impl HrParams {
    /// The one place these values are checked.
    pub fn check(&self) -> Result<(), BaselineError> {
        if !(self.f_eps.is_finite() && self.f_eps > 0.0) {
            return Err(BaselineError::InvalidParameter {
                name: "f_eps",
                value: self.f_eps.to_string(),
                valid: "positive and finite",
            });
        }
        if !(self.min_length > 0.0 && self.min_length < 1.0) {
            return Err(BaselineError::InvalidParameter {
                name: "min_length",
                value: self.min_length.to_string(),
                valid: "a fraction of the total surface length in (0, 1)",
            });
        }
        if self.rays_per_link == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "rays_per_link",
                value: self.rays_per_link.to_string(),
                valid: "at least 1",
            });
        }
        if self.max_links == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "max_links",
                value: self.max_links.to_string(),
                valid: "at least 1",
            });
        }
        Ok(())
    }
}
