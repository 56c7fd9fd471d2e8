//! [`KernelParams`]: the settings of a kernel and their one check.

use crate::GeomError;

/// Settings of a [`Kernel`](crate::Kernel), checked by
/// [`Kernel::with_params`](crate::Kernel::with_params).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct KernelParams {
    /// Source weight `E'` of a non-emitting surface, as a fraction of the largest emission
    /// (docs/ALGORITHM.md §2: a small floor, default 1 %). Valid range `[0, 1]`.
    pub emission_floor: f64,
}

impl Default for KernelParams {
    fn default() -> Self {
        KernelParams {
            emission_floor: 0.01,
        }
    }
}

impl KernelParams {
    /// Checks every field; the error names the valid range.
    pub fn validate(&self) -> Result<(), GeomError> {
        if !(0.0..=1.0).contains(&self.emission_floor) {
            return Err(GeomError::Param {
                name: "emission_floor",
                range: "[0, 1]",
                value: self.emission_floor,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Kernel;
    use crate::test_support::unit_box;

    #[test]
    fn emission_floor_is_validated_and_used() {
        let err = Kernel::with_params(
            unit_box(),
            KernelParams {
                emission_floor: 1.5,
            },
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "emission_floor must be in [0, 1], but is 1.5"
        );
        assert!(
            Kernel::with_params(
                unit_box(),
                KernelParams {
                    emission_floor: f64::NAN
                }
            )
            .is_err()
        );
        let kernel = Kernel::with_params(
            unit_box(),
            KernelParams {
                emission_floor: 0.5,
            },
        )
        .unwrap();
        assert_eq!(kernel.params().emission_floor, 0.5);
        assert_eq!(kernel.source_weight(crate::EdgeId::new(3)), 0.5);
    }
}
