//! The emitters of a lighting: each edge's emission, the power it sends, stratified start points.

use flatland_geom::{DVec2, EdgeId};
use flatland_solve::Mesh;

use super::Lighting;
use crate::BaselineError;

/// One emitting edge (a whole edge of the mesh).
#[derive(Clone, Copy, Debug)]
struct Emitter {
    a: DVec2,
    b: DVec2,
    normal: DVec2,
    /// Its first piece: the edge a photon leaving it skips.
    edge: EdgeId,
    /// Where its share of the total power starts, and its power.
    start: f64,
    power: f64,
}

/// Where a photon starts: a point on an emitter, the normal it leaves about, and the edge it
/// leaves from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Start {
    pub point: DVec2,
    pub normal: DVec2,
    pub edge: EdgeId,
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
    /// scene edge); an override of a blocker, of an edge not in the scene or of a value that
    /// is not finite and ≥ 0 is refused.
    pub(super) fn new(
        mesh: &Mesh,
        surface_of: &[Option<u32>],
        lighting: &Lighting,
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
                    a: edge.a,
                    b: edge.b,
                    normal: edge.normal,
                    edge: EdgeId::new(edge.pieces.start),
                    start: total,
                    power,
                });
                total += power;
            }
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
    /// an emitter in proportion to its power and a point uniform along it.
    pub(super) fn start(&self, u: f64) -> Start {
        let at = u * self.total;
        let k = self.list.partition_point(|e| e.start <= at).max(1) - 1;
        let e = &self.list[k];
        let v = ((at - e.start) / e.power).clamp(0.0, 1.0);
        Start {
            point: e.a + (e.b - e.a) * v,
            normal: e.normal,
            edge: e.edge,
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
        let emitters = Emitters::new(&mesh, &surface_of, &Lighting::default()).unwrap();
        assert_eq!(emitters.power(), 9.0);
        let n = 900;
        let mut counts = [0usize; 5];
        let mut along_wall = 0.0;
        for k in 0..n {
            let start = emitters.start((k as f64 + 0.5) / n as f64);
            counts[start.edge.index()] += 1;
            if start.edge == EdgeId::new(1) {
                along_wall += start.point.y / 3.0;
            }
        }
        assert_eq!(counts, [100, 600, 0, 100, 100]);
        assert!(
            (along_wall / 600.0 - 0.5).abs() < 1e-12,
            "uniform along the wall"
        );
        let (left, right) = (emitters.start(0.85).normal, emitters.start(0.95).normal);
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
        let emitters = Emitters::new(&mesh, &surface_of, &relit).unwrap();
        assert_eq!((emitters.emission(0), emitters.emission(2)), (0.0, 2.0));
        assert_eq!(emitters.power(), 2.0);
        assert_eq!(emitters.start(0.3).edge, EdgeId::new(2));
        for (edge, value, says) in [
            (3, 1.0, "blockers do not emit"),
            (4, 1.0, "an edge of the scene"),
            (1, -1.0, "at least 0"),
            (1, f64::NAN, "finite"),
        ] {
            let lighting = Lighting::default().with_emission(EdgeId::new(edge), value);
            let err = Emitters::new(&mesh, &surface_of, &lighting)
                .unwrap_err()
                .to_string();
            assert!(err.contains(says) && err.contains("emission"), "{err}");
        }
    }
}
