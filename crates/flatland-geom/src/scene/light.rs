//! [`PointLight`]: a lamp at a point, its validation against the scene's edges.

use glam::DVec2;

use super::Edge;
use crate::GeomError;
use crate::visibility::on_closed_segment;

/// A point light: a lamp, a torch, a lantern. It sends its power `Φ` equally in every
/// direction of the plane, `Φ / (2π)` per radian, so a surface point it sees at distance `r`
/// and angle `θ` from its normal receives the irradiance `Φ cos θ / (2π r)` (docs/ALGORITHM.md
/// §1a). A plain value: a scene validates it ([`Scene::with_lights`](crate::Scene::with_lights)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Where it is.
    pub at: DVec2,
    /// Its power `Φ ≥ 0`, in the units of an edge's `E × length`.
    pub power: f64,
}

impl PointLight {
    /// A light of power `power` at `at`.
    #[must_use]
    pub const fn new(at: DVec2, power: f64) -> PointLight {
        PointLight { at, power }
    }

    /// Checks the light's own fields; `index` names it in the error.
    fn validate(&self, index: usize) -> Result<(), GeomError> {
        for (field, value) in [("at.x", self.at.x), ("at.y", self.at.y)] {
            if !value.is_finite() {
                return Err(GeomError::LightNonFinite {
                    light: index,
                    field,
                    value,
                });
            }
        }
        if !self.power.is_finite() || self.power < 0.0 {
            return Err(GeomError::LightPower {
                light: index,
                value: self.power,
            });
        }
        Ok(())
    }
}

/// Checks every light: finite, power ≥ 0, and not on any edge (its light would leave from
/// inside a wall: half of it would light the wall's back). Errors name the first offending
/// light by its index, and the edge it lies on.
///
/// Lights are looked up in a grid of the edges' boxes, so this is linear in edges plus lights
/// (as long as edges are not piled into one cell), never their product.
pub(super) fn check_lights(edges: &[Edge], lights: &[PointLight]) -> Result<(), GeomError> {
    for (i, light) in lights.iter().enumerate() {
        light.validate(i)?;
    }
    if lights.is_empty() {
        return Ok(());
    }
    LightCheck::of_edges(edges.to_vec()).check(lights)
}

/// A scene's edges filed to check lights against: built once (linear in the edges), each
/// check a look-up per light — what a light moved many times is checked with
/// ([`Scene::with_lights`](crate::Scene::with_lights) files the edges anew each call).
#[derive(Clone, Debug)]
pub struct LightCheck {
    edges: Vec<Edge>,
    grid: EdgeGrid,
}

impl LightCheck {
    /// The edges of `scene`, filed.
    #[must_use]
    pub fn new(scene: &crate::Scene) -> LightCheck {
        LightCheck::of_edges(scene.edges().to_vec())
    }

    fn of_edges(edges: Vec<Edge>) -> LightCheck {
        LightCheck {
            grid: EdgeGrid::new(&edges),
            edges,
        }
    }

    /// The rule of [`Scene::with_lights`](crate::Scene::with_lights): every light finite, of
    /// power ≥ 0 and off every edge; the error names the first light that is not (by its
    /// index in `lights`) and the edge it lies on.
    pub fn check(&self, lights: &[PointLight]) -> Result<(), GeomError> {
        for (i, light) in lights.iter().enumerate() {
            light.validate(i)?;
            if let Some(edge) = self
                .grid
                .near(light.at)
                .find(|&e| on_closed_segment(light.at, self.edges[e].a, self.edges[e].b))
            {
                return Err(GeomError::LightOnEdge {
                    light: i,
                    x: light.at.x,
                    y: light.at.y,
                    edge,
                });
            }
        }
        Ok(())
    }
}

/// The edges filed by the square cells their bounding boxes touch: about one edge per cell.
#[derive(Clone, Debug)]
struct EdgeGrid {
    lo: DVec2,
    cell: f64,
    cols: usize,
    rows: usize,
    /// `starts[c]..starts[c + 1]` indexes `items` for cell `c`.
    starts: Vec<usize>,
    items: Vec<usize>,
}

/// Most cells a grid has per side.
const MAX_SIDE: usize = 4096;

impl EdgeGrid {
    fn new(edges: &[Edge]) -> EdgeGrid {
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for e in edges {
            lo = lo.min(e.a).min(e.b);
            hi = hi.max(e.a).max(e.b);
        }
        let extent = (hi - lo).max(DVec2::splat(f64::MIN_POSITIVE));
        // About one cell per edge, square.
        let cell = (extent.x * extent.y / edges.len().max(1) as f64)
            .sqrt()
            .max(extent.max_element() / MAX_SIDE as f64);
        let side = |len: f64| ((len / cell).floor() as usize + 1).clamp(1, MAX_SIDE + 1);
        let (cols, rows) = (side(extent.x), side(extent.y));
        let mut grid = EdgeGrid {
            lo,
            cell,
            cols,
            rows,
            starts: vec![0; cols * rows + 1],
            items: Vec::new(),
        };
        // Counting sort: count per cell, then fill.
        for e in edges {
            for c in grid.cells(e.a.min(e.b), e.a.max(e.b)) {
                grid.starts[c + 1] += 1;
            }
        }
        for c in 0..cols * rows {
            grid.starts[c + 1] += grid.starts[c];
        }
        let mut next = grid.starts.clone();
        grid.items = vec![0; grid.starts[cols * rows]];
        for (k, e) in edges.iter().enumerate() {
            for c in grid.cells(e.a.min(e.b), e.a.max(e.b)) {
                grid.items[next[c]] = k;
                next[c] += 1;
            }
        }
        grid
    }

    /// The cells the box `[lo, hi]` touches (closed: a point on a cell border is in both).
    fn cells(&self, lo: DVec2, hi: DVec2) -> impl Iterator<Item = usize> + use<> {
        let index = |u: f64, n: usize| (((u / self.cell).floor()).max(0.0) as usize).min(n - 1);
        let (l, h) = (lo - self.lo, hi - self.lo);
        let (c0, c1) = (index(l.x, self.cols), index(h.x, self.cols));
        let (r0, r1) = (index(l.y, self.rows), index(h.y, self.rows));
        let cols = self.cols;
        (r0..=r1).flat_map(move |r| (c0..=c1).map(move |c| r * cols + c))
    }

    /// The edges whose boxes may hold `p` (every edge through `p` is among them).
    fn near(&self, p: DVec2) -> impl Iterator<Item = usize> + '_ {
        self.cells(p, p).flat_map(|c| {
            self.items[self.starts[c]..self.starts[c + 1]]
                .iter()
                .copied()
        })
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

    fn lit(lights: Vec<PointLight>) -> Result<Scene, GeomError> {
        Scene::new(room(
            &[v(0.0, 0.0), v(2.0, 0.0), v(2.0, 1.0), v(0.0, 1.0)],
            0.5,
        ))
        .unwrap()
        .with_lights(lights)
    }

    fn refused(lights: Vec<PointLight>) -> String {
        let err = lit(lights).unwrap_err().to_string();
        assert!(!err.contains('\n'), "one line: {err}");
        err
    }

    #[test]
    fn a_light_inside_is_kept_and_bad_lights_are_refused_by_index() {
        let inside = PointLight::new(v(0.7, 0.4), 2.0);
        assert_eq!(lit(vec![inside]).unwrap().lights(), &[inside]);
        let nan = PointLight::new(v(f64::NAN, 0.4), 1.0);
        let err = refused(vec![inside, nan]);
        assert!(err.starts_with("light 1: at.x must be finite"), "{err}");
        for bad in [-1.0, f64::INFINITY, f64::NAN] {
            let err = refused(vec![PointLight::new(v(1.0, 0.5), bad)]);
            assert!(
                err.starts_with("light 0: power must be finite and >= 0"),
                "{err}"
            );
        }
        // Zero power is a light switched off: kept.
        assert!(lit(vec![PointLight::new(v(1.0, 0.5), 0.0)]).is_ok());
    }

    #[test]
    fn a_light_on_an_edge_or_a_corner_is_refused_naming_the_edge() {
        let err = refused(vec![
            PointLight::new(v(1.0, 0.5), 1.0),
            PointLight::new(v(1.5, 1.0), 1.0),
        ]);
        assert!(
            err.starts_with("light 1: at (1.5, 1) lies on edge 2"),
            "{err}"
        );
        // A corner lies on two edges: the first is named.
        let err = refused(vec![PointLight::new(v(2.0, 0.0), 1.0)]);
        assert!(err.contains("lies on edge 0"), "{err}");
        // Just off the wall is fine.
        assert!(lit(vec![PointLight::new(v(1.5, 1.0 - 1e-12), 1.0)]).is_ok());
    }

    /// The grid finds an edge through any point of it, however the edges are spread: the same
    /// answers as testing every edge.
    #[test]
    fn the_grid_finds_every_edge_a_point_lies_on() {
        let mut rng = crate::test_support::rng(5);
        use rand::RngExt;
        let edges: Vec<Edge> = (0..300)
            .map(|k| {
                let a = v(rng.random_range(0.0..50.0), rng.random_range(0.0..3.0));
                let len = if k % 10 == 0 { 40.0 } else { 0.5 };
                let turn: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                Edge::surface(a, a + v(turn.cos(), turn.sin()) * len, 0.5)
            })
            .collect();
        let grid = EdgeGrid::new(&edges);
        for (k, e) in edges.iter().enumerate() {
            for p in [e.a, e.b, e.a.midpoint(e.b)] {
                let by_scan: Vec<usize> = (0..edges.len())
                    .filter(|&j| on_closed_segment(p, edges[j].a, edges[j].b))
                    .collect();
                let found: Vec<usize> = grid
                    .near(p)
                    .filter(|&j| on_closed_segment(p, edges[j].a, edges[j].b))
                    .collect();
                assert!(found.contains(&k) || !by_scan.contains(&k), "edge {k}");
                for j in by_scan {
                    assert!(found.contains(&j), "edge {j} at {p}");
                }
            }
        }
    }

    #[test]
    fn a_check_built_once_gives_what_with_lights_gives() {
        let scene = lit(Vec::new()).unwrap();
        let check = LightCheck::new(&scene);
        for lights in [
            vec![PointLight::new(v(0.7, 0.4), 2.0)],
            vec![
                PointLight::new(v(0.7, 0.4), 2.0),
                PointLight::new(v(2.0, 0.5), 1.0),
            ],
            vec![PointLight::new(v(1.0, 0.0), 1.0)],
            vec![PointLight::new(v(1.0, 0.5), -1.0)],
            vec![PointLight::new(v(f64::NAN, 0.5), 1.0)],
        ] {
            let once = check.check(&lights).map_err(|e| e.to_string());
            let anew = scene
                .clone()
                .with_lights(lights.clone())
                .map(|_| ())
                .map_err(|e| e.to_string());
            assert_eq!(once, anew, "{lights:?}");
        }
    }
}
