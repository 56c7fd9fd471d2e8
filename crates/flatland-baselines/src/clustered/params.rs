//! Clustered HR's settings: the minimum element length, rays per link and the link cap,
//! checked in one place.

use crate::BaselineError;

/// Links per surface edge a caller asks of clustered HR when it has no budget of its own: its
/// resources in proportion to the scene (it has no initial linking to set a floor; at 10⁵ links
/// a 300-edge floor plan is lit to about 7 %, while a few hundred links on a scene of a
/// thousand edges light it at the coarsest clusters only).
pub const DEFAULT_LINKS_PER_EDGE: usize = 100;

/// Settings of hierarchical radiosity with clustering. F_ε is not among them: the budget of
/// links decides it (see the `clustered` module docs).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClusteredParams {
    /// Minimum element length, as a fraction of the mean surface-edge length `L / n`, in
    /// (0, 1]. An element shorter than twice this is not halved. Relative to the mean edge
    /// rather than to `L` (HR's rule) so a scene of 10⁴ edges still refines its walls.
    pub min_length: f64,
    /// Rays per link (default 20, as HR and the paper's comparison).
    pub rays_per_link: usize,
    /// Rounds of Hanrahan's BF refinement: after the first shot (links weighted by E', as HR),
    /// this many times the links so far are solved and the senders re-weighed by their
    /// radiosity, each round at four times the last one's links, the last at the budget.
    /// 0 keeps HR's weights throughout.
    pub bf_rounds: usize,
    /// Refuse a budget above this many links (each keeps 16 bytes, and was paid for with
    /// `rays_per_link` rays, with as many again for the links refined away).
    pub max_links: usize,
}

impl Default for ClusteredParams {
    fn default() -> Self {
        ClusteredParams {
            min_length: 1.0 / 256.0,
            rays_per_link: 20,
            bf_rounds: 2,
            max_links: 20_000_000,
        }
    }
}

impl ClusteredParams {
    /// The one place these values are checked.
    pub fn check(&self) -> Result<(), BaselineError> {
        if !(self.min_length > 0.0 && self.min_length <= 1.0) {
            return Err(BaselineError::InvalidParameter {
                name: "min_length",
                value: self.min_length.to_string(),
                valid: "a fraction of the mean surface-edge length in (0, 1]",
            });
        }
        if !(1..=1024).contains(&self.rays_per_link) {
            return Err(BaselineError::InvalidParameter {
                name: "rays_per_link",
                value: self.rays_per_link.to_string(),
                valid: "in [1, 1024]",
            });
        }
        if self.bf_rounds > 8 {
            return Err(BaselineError::InvalidParameter {
                name: "bf_rounds",
                value: self.bf_rounds.to_string(),
                valid: "in [0, 8]",
            });
        }
        if !(1..=u32::MAX as usize / 4).contains(&self.max_links) {
            return Err(BaselineError::InvalidParameter {
                name: "max_links",
                value: self.max_links.to_string(),
                valid: "in [1, 1 073 741 823]",
            });
        }
        Ok(())
    }

    /// A budget clustered HR can be asked for: at least one link, at most `max_links`.
    pub(super) fn check_budget(&self, budget: usize) -> Result<(), BaselineError> {
        if budget == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "budget",
                value: budget.to_string(),
                valid: "at least 1 link",
            });
        }
        if budget > self.max_links {
            return Err(BaselineError::BudgetAboveMaxLinks {
                budget,
                max_links: self.max_links,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_values_are_named_with_their_range() {
        let base = ClusteredParams::default();
        assert!(base.check().is_ok());
        for (params, name, range) in [
            (
                ClusteredParams {
                    min_length: 0.0,
                    ..base
                },
                "min_length",
                "(0, 1]",
            ),
            (
                ClusteredParams {
                    min_length: f64::NAN,
                    ..base
                },
                "min_length",
                "(0, 1]",
            ),
            (
                ClusteredParams {
                    rays_per_link: 0,
                    ..base
                },
                "rays_per_link",
                "[1, 1024]",
            ),
            (
                ClusteredParams {
                    bf_rounds: 9,
                    ..base
                },
                "bf_rounds",
                "[0, 8]",
            ),
            (
                ClusteredParams {
                    max_links: 0,
                    ..base
                },
                "max_links",
                "[1, 1 073 741 823]",
            ),
        ] {
            let msg = params.check().unwrap_err().to_string();
            assert!(msg.contains(name) && msg.contains(range), "{msg}");
        }
        assert!(
            base.check_budget(0)
                .unwrap_err()
                .to_string()
                .contains("at least 1")
        );
        let msg = base
            .check_budget(base.max_links + 1)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("max_links"), "{msg}");
    }
}
