//! [`Edge`] and [`Role`]: a segment with its material, its constructors and its validation.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::GeomError;

/// What an edge does: a `Surface` is parameterized, reflects, emits and occludes; a `Blocker`
/// only occludes (the paper's Fig. 3 blocker is "not included into the parametrization").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// Part of the parameterization; reflects, emits and occludes.
    #[default]
    Surface,
    /// Occludes only.
    Blocker,
}

/// A line segment from `a` to `b` with its material. A plain value: build scenes from it with
/// [`Scene::new`](crate::Scene::new), which validates every field.
///
/// The front side is the left of `a → b`; see [`Edge::normal`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Diffuse reflectance ρ in `[0, 1]`.
    pub reflectance: f64,
    /// Emitted radiosity E ≥ 0.
    pub emission: f64,
    /// Surface (parameterized) or blocker (occludes only).
    pub role: Role,
    /// Whether both sides face the scene. Only a blocker may be two-sided (where it changes
    /// nothing: a blocker occludes from both sides anyway); a two-sided surface is refused,
    /// since its one radiosity cannot stand for both sides (docs/ALGORITHM.md §1).
    pub two_sided: bool,
}

impl Edge {
    /// A one-sided, non-emitting surface edge.
    #[must_use]
    pub const fn surface(a: DVec2, b: DVec2, reflectance: f64) -> Edge {
        Edge {
            a,
            b,
            reflectance,
            emission: 0.0,
            role: Role::Surface,
            two_sided: false,
        }
    }

    /// The walls of a closed polygon room through `points`, each with `reflectance`: listed
    /// counter-clockwise, they face inwards.
    #[must_use]
    pub fn polygon(points: &[DVec2], reflectance: f64) -> Vec<Edge> {
        (0..points.len())
            .map(|i| Edge::surface(points[i], points[(i + 1) % points.len()], reflectance))
            .collect()
    }

    /// A blocker edge (occludes only; reflectance and emission are 0).
    #[must_use]
    pub const fn blocker(a: DVec2, b: DVec2) -> Edge {
        Edge {
            a,
            b,
            reflectance: 0.0,
            emission: 0.0,
            role: Role::Blocker,
            two_sided: false,
        }
    }

    /// The same edge with emission `emission`.
    #[must_use]
    pub const fn with_emission(self, emission: f64) -> Edge {
        Edge { emission, ..self }
    }

    /// The same edge, two-sided or not (a two-sided surface is refused by
    /// [`Scene::new`](crate::Scene::new); only a blocker may be two-sided).
    #[must_use]
    pub const fn with_two_sided(self, two_sided: bool) -> Edge {
        Edge { two_sided, ..self }
    }

    /// Euclidean length `|b − a|`.
    #[must_use]
    pub fn length(&self) -> f64 {
        (self.b - self.a).length()
    }

    /// Front normal `perp(b − a) / |b − a|` with `perp(x, y) = (−y, x)`: the left of `a → b`.
    /// A room listed counter-clockwise faces inwards.
    #[must_use]
    pub fn normal(&self) -> DVec2 {
        let d = self.b - self.a;
        DVec2::new(-d.y, d.x) / d.length()
    }

    /// The point `a + u (b − a)`; `u = 0` is `a`, `u = 1` is `b`.
    #[must_use]
    pub fn point_at(&self, u: f64) -> DVec2 {
        self.a + (self.b - self.a) * u
    }

    /// Checks every rule of docs/ALGORITHM.md §1 for this edge; `index` names it in the error.
    pub(super) fn validate(&self, index: usize) -> Result<(), GeomError> {
        let coords = [
            ("a.x", self.a.x),
            ("a.y", self.a.y),
            ("b.x", self.b.x),
            ("b.y", self.b.y),
        ];
        for (field, value) in coords {
            if !value.is_finite() {
                return Err(GeomError::NonFinite {
                    edge: index,
                    field,
                    value,
                });
            }
        }
        let d = self.b - self.a;
        if !d.x.is_finite() || !d.y.is_finite() || !d.length().is_finite() {
            return Err(GeomError::NonFinite {
                edge: index,
                field: "length |b - a|",
                value: d.length(),
            });
        }
        // An edge so short that |b − a|² underflows has no usable normal: same rule as a == b.
        if d.length_squared() <= 0.0 || !self.normal().is_finite() {
            return Err(GeomError::ZeroLength {
                edge: index,
                ax: self.a.x,
                ay: self.a.y,
                bx: self.b.x,
                by: self.b.y,
            });
        }
        if !(0.0..=1.0).contains(&self.reflectance) {
            return Err(GeomError::Reflectance {
                edge: index,
                value: self.reflectance,
            });
        }
        if !self.emission.is_finite() || self.emission < 0.0 {
            return Err(GeomError::Emission {
                edge: index,
                value: self.emission,
            });
        }
        // One radiosity for both sides would let the surface gather from both half-planes
        // (row sums up to 2ρ) and send that into both: the exact solve then gains energy and
        // can return negative radiosity. A thin wall is two one-sided faces.
        if self.two_sided && self.role == Role::Surface {
            return Err(GeomError::TwoSidedSurface { edge: index });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;
    use crate::test_support::room;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn triangle() -> Vec<Edge> {
        room(&[v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)], 0.5)
    }

    /// Builds a scene whose edge 1 is `bad` and checks the message names edge 1 and `rule`.
    fn assert_rejected(bad: Edge, rule: &str) {
        let mut edges = triangle();
        edges[1] = bad;
        let err = Scene::new(edges).unwrap_err().to_string();
        assert!(
            err.starts_with("edge 1: "),
            "message does not name the edge: {err}"
        );
        assert!(
            err.contains(rule),
            "message does not state the rule `{rule}`: {err}"
        );
    }

    #[test]
    fn non_finite_coordinates_are_rejected_naming_the_edge() {
        assert_rejected(
            Edge::surface(v(f64::NAN, 0.0), v(1.0, 0.0), 0.5),
            "a.x must be finite",
        );
        assert_rejected(
            Edge::surface(v(0.0, 0.0), v(1.0, f64::INFINITY), 0.5),
            "b.y must be finite",
        );
        let overflow = Edge::surface(v(-1e308, 0.0), v(1e308, 0.0), 0.5);
        assert_rejected(overflow, "length |b - a| must be finite");
    }

    #[test]
    fn zero_length_is_rejected_naming_the_edge() {
        assert_rejected(Edge::surface(v(1.0, 1.0), v(1.0, 1.0), 0.5), "zero length");
        // |b − a|² underflows: no usable normal, same rule.
        assert_rejected(
            Edge::surface(v(0.0, 0.0), v(1e-170, 0.0), 0.5),
            "zero length",
        );
    }

    #[test]
    fn reflectance_outside_unit_interval_is_rejected_naming_the_edge() {
        for bad in [-0.1, 1.5, f64::NAN] {
            assert_rejected(
                Edge::surface(v(0.0, 0.0), v(1.0, 0.0), bad),
                "reflectance must be in [0, 1]",
            );
        }
    }

    #[test]
    fn bad_emission_is_rejected_naming_the_edge() {
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let e = Edge::surface(v(0.0, 0.0), v(1.0, 0.0), 0.5).with_emission(bad);
            assert_rejected(e, "emission must be finite and >= 0");
        }
    }

    #[test]
    fn a_two_sided_surface_is_refused_saying_how_to_model_a_thin_wall() {
        let wall = Edge::surface(v(0.0, 0.0), v(1.0, 0.0), 0.5).with_two_sided(true);
        assert_rejected(wall, "a surface cannot be two-sided");
        let mut edges = triangle();
        edges[1] = wall;
        let err = Scene::new(edges).unwrap_err().to_string();
        assert!(
            err.contains("box") && err.contains("two one-sided edges back to back"),
            "{err}"
        );
        assert!(!err.contains('\n'), "one line: {err}");
        // A two-sided blocker stays, and so does the thin wall as two one-sided faces.
        let mut edges = triangle();
        edges.push(Edge::blocker(v(0.2, 0.2), v(0.3, 0.3)).with_two_sided(true));
        edges.push(Edge::surface(v(0.1, 0.1), v(0.2, 0.1), 0.5));
        edges.push(Edge::surface(v(0.2, 0.1), v(0.1, 0.1), 0.5));
        assert!(Scene::new(edges).is_ok());
    }

    #[test]
    fn normal_is_the_left_of_a_to_b() {
        let e = Edge::surface(v(0.0, 0.0), v(2.0, 0.0), 0.5);
        assert_eq!(e.normal(), v(0.0, 1.0));
        assert_eq!(e.length(), 2.0);
        assert_eq!(e.point_at(0.25), v(0.5, 0.0));
    }
}
