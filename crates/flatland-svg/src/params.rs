//! [`ImportParams`]: how a drawing becomes edges, checked before any work.

use crate::SvgError;

/// How a drawing is read. Build with [`ImportParams::default`] and change fields; [`import`]
/// checks them ([`ImportParams::check`]) before reading.
///
/// [`import`]: crate::import
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImportParams {
    /// Largest distance between a curve (arc, Bézier, circle) and the segments that replace it,
    /// in drawing units (the root's user units, after its viewBox). `None`: a thousandth of the
    /// drawing's diagonal (its viewBox, or its size without one). Valid: finite and > 0.
    pub flatten: Option<f64>,
    /// Plan units per drawing unit: a drawing in millimetres read with `unit = 0.001` gives a
    /// plan in metres. Valid: finite and > 0.
    pub unit: f64,
    /// Reflectance ρ of every element without `data-flatland-reflectance`. Valid: `[0, 1]`.
    pub reflectance: f64,
}

impl Default for ImportParams {
    fn default() -> Self {
        ImportParams {
            flatten: None,
            unit: 1.0,
            reflectance: 0.5,
        }
    }
}

impl ImportParams {
    /// Checks every field; the error names the field and its valid range.
    pub fn check(&self) -> Result<(), SvgError> {
        let positive = |name, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(SvgError::Param {
                    name,
                    range: "(0, inf), finite",
                    value,
                })
            }
        };
        if let Some(flatten) = self.flatten {
            positive("flatten", flatten)?;
        }
        positive("unit", self.unit)?;
        if !(0.0..=1.0).contains(&self.reflectance) {
            return Err(SvgError::Param {
                name: "reflectance",
                range: "[0, 1]",
                value: self.reflectance,
            });
        }
        // The plan's coordinates must stay finite: a unit so large that f32 drawing
        // coordinates overflow f64 is refused by the edges' own check.
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_pass_and_each_bad_field_is_named_with_its_range() {
        assert!(ImportParams::default().check().is_ok());
        let cases = [
            (
                ImportParams {
                    flatten: Some(0.0),
                    ..ImportParams::default()
                },
                "flatten must be in (0, inf)",
            ),
            (
                ImportParams {
                    unit: f64::NAN,
                    ..ImportParams::default()
                },
                "unit must be in (0, inf)",
            ),
            (
                ImportParams {
                    reflectance: 1.5,
                    ..ImportParams::default()
                },
                "reflectance must be in [0, 1]",
            ),
        ];
        for (params, message) in cases {
            let err = params.check().unwrap_err().to_string();
            assert!(err.starts_with(message), "{err}");
        }
    }
}
