//! The transport's settings and their one check.

use serde::{Deserialize, Serialize};

use crate::TransportError;

/// How the later bounces are represented and how closely, checked by [`TransportParams::check`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TransportParams {
    /// The relative (Frobenius) error allowed each cluster's block of `M₂`: rows and singular
    /// values whose share is below it are left out. In (0, 1); default 0.05.
    pub tolerance: f64,
    /// Most bytes the model may hold (`None`: what the tolerance needs). When the tolerance
    /// needs more, the singular triplets carrying the least per byte are dropped. At least
    /// 1024 when given.
    pub budget: Option<usize>,
    /// Most elements of a cluster (the sources of one block). In [1, 4096]; default 64.
    pub cluster_elements: usize,
    /// A local solve shoots light until none above this fraction of a column's largest value
    /// is left unshot. In (0, 0.1]; default 1e-3.
    pub solve_tolerance: f64,
    /// Lights the set-up draws to estimate its own error (never a query's position).
    /// In [1, 4096]; default 32.
    pub validation_lights: usize,
    /// The seed of the set-up's random draws (the validation lights).
    pub seed: u64,
}

impl Default for TransportParams {
    fn default() -> Self {
        TransportParams {
            tolerance: 0.05,
            budget: None,
            cluster_elements: 64,
            solve_tolerance: 1e-3,
            validation_lights: 32,
            seed: 0,
        }
    }
}

impl TransportParams {
    /// Refuses a value outside its range, naming the parameter and the range.
    pub fn check(&self) -> Result<(), TransportError> {
        let invalid = |name, value: String, valid| {
            Err(TransportError::InvalidParameter { name, value, valid })
        };
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return invalid("tolerance", self.tolerance.to_string(), "in (0, 1)");
        }
        if let Some(budget) = self.budget
            && budget < 1024
        {
            return invalid("budget", budget.to_string(), "at least 1024 bytes");
        }
        if !(1..=4096).contains(&self.cluster_elements) {
            return invalid(
                "cluster_elements",
                self.cluster_elements.to_string(),
                "in [1, 4096]",
            );
        }
        if !(self.solve_tolerance > 0.0 && self.solve_tolerance <= 0.1) {
            return invalid(
                "solve_tolerance",
                self.solve_tolerance.to_string(),
                "in (0, 0.1]",
            );
        }
        if !(1..=4096).contains(&self.validation_lights) {
            return invalid(
                "validation_lights",
                self.validation_lights.to_string(),
                "in [1, 4096]",
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_out_of_range_value_is_named_with_its_range() {
        assert!(TransportParams::default().check().is_ok());
        let cases = [
            (
                TransportParams {
                    tolerance: 0.0,
                    ..Default::default()
                },
                "tolerance",
            ),
            (
                TransportParams {
                    tolerance: f64::NAN,
                    ..Default::default()
                },
                "tolerance",
            ),
            (
                TransportParams {
                    budget: Some(10),
                    ..Default::default()
                },
                "budget",
            ),
            (
                TransportParams {
                    cluster_elements: 0,
                    ..Default::default()
                },
                "cluster_elements",
            ),
            (
                TransportParams {
                    solve_tolerance: 0.5,
                    ..Default::default()
                },
                "solve_tolerance",
            ),
            (
                TransportParams {
                    validation_lights: 0,
                    ..Default::default()
                },
                "validation_lights",
            ),
        ];
        for (params, name) in cases {
            let message = params.check().unwrap_err().to_string();
            assert!(
                message.contains(&format!("`{name}`")) && message.contains("must be"),
                "{message}"
            );
        }
    }
}
