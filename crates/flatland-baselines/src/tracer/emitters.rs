//! The emitters of a lighting: each edge's emission and each point light, the power it sends,
//! stratified start points.

use std::f64::consts::TAU;

use flatland_geom::{DVec2, EdgeId, PointLight};
use flatland_solve::Mesh;

use super::Lighting;
use crate::BaselineError;

/// One emitting edge (a whole edge of the mesh) or point light.
#[derive(Clone, Copy, Debug)]
struct Emitter {
    source: Source,
    /// Where its share of the total power starts, and its power.
    start: f64,
    power: f64,
}

/// What emits.
#[derive(Clone, Copy, Debug)]
enum Source {
    /// An edge from `a` to `b` facing `normal`; `edge` is its first piece, which a photon
    /// leaving it skips.
    Edge {
        a: DVec2,
        b: DVec2,
        normal: DVec2,
        edge: EdgeId,
    },
    /// A point light.
    Light { at: DVec2 },
}

/// Where a photon starts and how it leaves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Start {
    pub point: DVec2,
    pub leaving: Leaving,
    /// The edge it leaves from (none for a light).
    pub skip: Option<EdgeId>,
}

/// How a photon leaves its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Leaving {
    /// Cosine-distributed about this normal (a surface).
    About(DVec2),
    /// Along this unit direction (a light: uniform in angle, stratified with the starts).
    Along(DVec2),
}

/// The emission of every mesh edge under a lighting, and the emitters laid end to end by power.
#[derive(Clone, Debug)]
pub(super) struct Emitters {
    /// E per mesh edge.
    emission: Vec<f64>,
    list: Vec<Emitter>,
    total: f64,
}

impl Emitters {
    /// The mesh's emissions with `lighting`'s overrides (`surface_of`: the mesh edge of each
    /// scene edge), then the point `lights`; an override of a blocker, of an edge not in the
    /// scene or of a value that is not finite and ≥ 0 is refused.
    pub(super) fn new(
        mesh: &Mesh,
        surface_of: &[Option<u32>],
        lighting: &Lighting,
        lights: &[PointLight],
    ) -> Result<Emitters, BaselineError> {
        let mut emission: Vec<f64> = mesh.edges().iter().map(|e| e.emission).collect();
        for &(edge, value) in lighting.overrides() {
            let bad = |valid| BaselineError::InvalidParameter {
                name: "emission",
                value: format!("{value} on edge {edge}"),
                valid,
            };
            let Some(&slot) = surface_of.get(edge.index()) else {
                return Err(bad("on an edge of the scene"));
            };
            let Some(m) = slot else {
                return Err(bad("on a surface edge (blockers do not emit)"));
            };
            if !(value.is_finite() && value >= 0.0) {
                return Err(bad("finite and at least 0"));
            }
            emission[m as usize] = value;
        }
        let mut list = Vec::new();
        let mut total = 0.0;
        for (edge, &e) in mesh.edges().iter().zip(&emission) {
            if e > 0.0 {
                let power = e * (edge.b - edge.a).length();
                list.push(Emitter {
                    source: Source::Edge {
                        a: edge.a,
                        b: edge.b,
                        normal: edge.normal,
                        edge: EdgeId::new(edge.pieces.start),
                    },
                    start: total,
                    power,
                });
                total += power;
            }
        }
        for light in lights.iter().filter(|l| l.power > 0.0) {
            list.push(Emitter {
                source: Source::Light { at: light.at },
                start: total,
                power: light.power,
            });
            total += light.power;
        }
        Ok(Emitters {
            emission,
            list,
            total,
        })
    }

    /// The power all emitters send.
    pub(super) fn power(&self) -> f64 {
        self.total
    }

    /// E of mesh edge `m`.
    pub(super) fn emission(&self, m: usize) -> f64 {
        self.emission[m]
    }

    /// The start at `u ∈ [0, 1)` of the emitters laid end to end by power: uniform `u` gives
    /// an emitter in proportion to its power and a point uniform along it, or for a light a
    /// direction uniform in angle (`Φ / (2π)` per radian).
    pub(super) fn start(&self, u: f64) -> Start {
        let at = u * self.total;
        let k = self.list.partition_point(|e| e.start <= at).max(1) - 1;
        let e = &self.list[k];
        let v = ((at - e.start) / e.power).clamp(0.0, 1.0);
        match e.source {
            Source::Edge { a, b, normal, edge } => Start {
                point: a + (b - a) * v,
                leaving: Leaving::About(normal),
                skip: Some(edge),
            },
            Source::Light { at } => {
                let (sin, cos) = (TAU * v).sin_cos();
                Start {
                    point: at,
                    leaving: Leaving::Along(DVec2::new(cos, sin)),
                    skip: None,
                }
            }
        }
    }

    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        self.list.len() * size_of::<Emitter>() + self.emission.len() * size_of::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{kernel, surface};

    #[test]
    fn stratified_starts_give_each_emitter_its_share_uniformly_along_it() {
        // A floor of E = 1 and length 1 (power 1), a wall of E = 2 and length 3 (power 6), a
        // thin shelf of E = 1 and length 1 (two faces back to back, power 1 each).
        let kernel = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([1.0, 0.0], [1.0, 3.0], 0.5, 2.0),
            surface([1.0, 3.0], [0.0, 0.0], 0.5, 0.0),
            surface([0.2, 1.0], [0.2, 2.0], 0.5, 1.0),
            surface([0.2, 2.0], [0.2, 1.0], 0.5, 1.0),
        ]);
        let mesh = Mesh::new(&kernel, 16).unwrap();
        let surface_of: Vec<Option<u32>> = (0..5).map(Some).collect();
        let emitters = Emitters::new(&mesh, &surface_of, &Lighting::default(), &[]).unwrap();
        assert_eq!(emitters.power(), 9.0);
        let n = 900;
        let mut counts = [0usize; 5];
        let mut along_wall = 0.0;
        for k in 0..n {
            let start = emitters.start((k as f64 + 0.5) / n as f64);
            let edge = start.skip.unwrap();
            counts[edge.index()] += 1;
            if edge == EdgeId::new(1) {
                along_wall += start.point.y / 3.0;
            }
        }
        assert_eq!(counts, [100, 600, 0, 100, 100]);
        assert!(
            (along_wall / 600.0 - 0.5).abs() < 1e-12,
            "uniform along the wall"
        );
        let normal = |u: f64| match emitters.start(u).leaving {
            Leaving::About(n) => n,
            Leaving::Along(_) => panic!("no light here"),
        };
        let (left, right) = (normal(0.85), normal(0.95));
        assert!(
            left.x < 0.0 && right.x > 0.0,
            "each face leaves from its own side"
        );
    }

    #[test]
    fn overrides_relight_and_bad_ones_are_refused() {
        let edges = vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([1.0, 0.0], [0.0, 1.0], 0.5, 0.0),
            surface([0.0, 1.0], [0.0, 0.0], 0.5, 0.0),
        ];
        let mut with_blocker = edges.clone();
        with_blocker.push(flatland_geom::Edge::blocker(
            flatland_geom::DVec2::new(0.1, 0.1),
            flatland_geom::DVec2::new(0.2, 0.2),
        ));
        let kernel = kernel(with_blocker);
        let mesh = Mesh::new(&kernel, 8).unwrap();
        let surface_of = vec![Some(0), Some(1), Some(2), None];
        let relit = Lighting::default()
            .with_emission(EdgeId::new(0), 0.0)
            .with_emission(EdgeId::new(2), 3.0)
            .with_emission(EdgeId::new(2), 2.0);
        let emitters = Emitters::new(&mesh, &surface_of, &relit, &[]).unwrap();
        assert_eq!((emitters.emission(0), emitters.emission(2)), (0.0, 2.0));
        assert_eq!(emitters.power(), 2.0);
        assert_eq!(emitters.start(0.3).skip, Some(EdgeId::new(2)));
        for (edge, value, says) in [
            (3, 1.0, "blockers do not emit"),
            (4, 1.0, "an edge of the scene"),
            (1, -1.0, "at least 0"),
            (1, f64::NAN, "finite"),
        ] {
            let lighting = Lighting::default().with_emission(EdgeId::new(edge), value);
            let err = Emitters::new(&mesh, &surface_of, &lighting, &[])
                .unwrap_err()
                .to_string();
            assert!(err.contains(says) && err.contains("emission"), "{err}");
        }
    }

    #[test]
    fn a_light_takes_its_power_share_and_sends_it_uniformly_in_angle() {
        let kernel = kernel(vec![
            surface([0.0, 0.0], [2.0, 0.0], 0.5, 1.0),
            surface([2.0, 0.0], [0.0, 2.0], 0.5, 0.0),
            surface([0.0, 2.0], [0.0, 0.0], 0.5, 0.0),
        ]);
        let mesh = Mesh::new(&kernel, 12).unwrap();
        let surface_of: Vec<Option<u32>> = (0..3).map(Some).collect();
        let lights = [
            PointLight::new(DVec2::new(0.5, 0.5), 6.0),
            PointLight::new(DVec2::new(0.4, 0.4), 0.0),
        ];
        let emitters = Emitters::new(&mesh, &surface_of, &Lighting::default(), &lights).unwrap();
        assert_eq!(emitters.power(), 8.0, "the floor's 2 and the light's 6");
        let n = 8000;
        let (mut from_light, mut mean) = (0, DVec2::ZERO);
        for k in 0..n {
            let start = emitters.start((k as f64 + 0.5) / n as f64);
            if let Leaving::Along(d) = start.leaving {
                assert_eq!((start.point, start.skip), (lights[0].at, None));
                assert!((d.length() - 1.0).abs() < 1e-15);
                from_light += 1;
                mean += d;
            }
        }
        assert_eq!(from_light, 6000);
        assert!(
            mean.length() / 6000.0 < 1e-12,
            "directions balance all around"
        );
    }
}
