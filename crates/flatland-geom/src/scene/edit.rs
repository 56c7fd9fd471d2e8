//! Scenes derived from a scene: every surface edge subdivided, or one edge replaced.

use super::param::lerp;
use super::{Edge, Scene};
use crate::{EdgeId, GeomError};

impl Scene {
    /// Splits every surface edge into `m` equal edges (blockers stay as they are; lights too).
    /// [`Scene::point`] is unchanged for every `s`, and the kernel over `(s, t)` is the same
    /// function: the pieces remember their parent edge. `m = 0` is an error.
    pub fn subdivide(&self, m: usize) -> Result<Scene, GeomError> {
        if m == 0 {
            return Err(GeomError::Param {
                name: "subdivision count m",
                range: "[1, inf)",
                value: 0.0,
            });
        }
        let mut edges = Vec::with_capacity(self.edges.len() * m);
        let mut runs = Vec::with_capacity(self.groups.len());
        for g in &self.groups {
            if g.rank.is_none() {
                edges.extend_from_slice(&self.edges[g.first..g.first + g.count]);
                runs.push(g.count);
                continue;
            }
            let n = g.count.checked_mul(m).ok_or(GeomError::Param {
                name: "subdivision count m",
                range: "[1, usize::MAX / pieces]",
                value: m as f64,
            })?;
            let at = |k: usize| {
                if k == n {
                    g.b
                } else {
                    lerp(g.a, g.b, k as f64 / n as f64)
                }
            };
            for k in 0..n {
                edges.push(Edge {
                    a: at(k),
                    b: at(k + 1),
                    ..g.edge
                });
            }
            runs.push(n);
        }
        Scene::from_runs(edges, &runs)?.with_lights(self.lights.clone())
    }

    /// The scene with edge `index` replaced by `edge` (validated, also against the lights, which
    /// stay). If `index` was a piece of a
    /// subdivided edge, that parent's pieces become independent edges.
    pub fn with_edge(&self, index: EdgeId, edge: Edge) -> Result<Scene, GeomError> {
        let index = index.index();
        if index >= self.edges.len() {
            return Err(GeomError::EdgeIndex {
                index,
                len: self.edges.len(),
            });
        }
        let mut edges = self.edges.clone();
        edges[index] = edge;
        let hit = self.group_of[index];
        let mut runs = Vec::with_capacity(self.groups.len());
        for (i, g) in self.groups.iter().enumerate() {
            if i == hit {
                runs.extend(std::iter::repeat_n(1, g.count));
            } else {
                runs.push(g.count);
            }
        }
        // The new edge may pass through a light: checked again.
        Scene::from_runs(edges, &runs)?.with_lights(self.lights.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assert_close;
    use crate::test_support::{bundled, rng, unit_box};
    use glam::DVec2;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn subdivide_leaves_point_unchanged_bit_for_bit() {
        let scene = bundled("fig3");
        let fine = scene.subdivide(1000).unwrap();
        let surfaces = scene.surface_edges().len();
        assert_eq!(
            fine.edges().len(),
            surfaces * 1000 + (scene.edges().len() - surfaces)
        );
        assert_eq!(fine.total_length(), scene.total_length());
        let mut r = rng(2);
        for _ in 0..10_000 {
            let s: f64 = r.random_range(0.0..1.0);
            let (p, q) = (scene.point(s), fine.point(s));
            assert_eq!((p.position, p.normal), (q.position, q.normal), "s = {s}");
            let piece = fine.edge(q.edge);
            assert!(
                piece.a.distance(q.position) + q.position.distance(piece.b)
                    <= piece.length() + 1e-12
            );
            let back = fine.param_of(q.edge, q.position).unwrap();
            assert_close!(back, s, 1e-14);
        }
        // Every piece knows its parent's run; an edge never subdivided is its own run.
        let id = EdgeId::new;
        let first = fine.surface_edges()[0].index();
        let run = Some(id(first)..id(first + 1000));
        assert_eq!(fine.parent_pieces(id(first)), run);
        assert_eq!(fine.parent_pieces(id(first + 999)), run);
        let blocker = fine.edges().len() - 1;
        assert_eq!(
            fine.parent_pieces(id(blocker)),
            Some(id(blocker)..id(blocker + 1))
        );
        assert_eq!(fine.parent_pieces(id(fine.edges().len())), None);
        // Subdividing twice is the same as once with the product.
        let twice = scene.subdivide(10).unwrap().subdivide(100).unwrap();
        assert_eq!(twice.edges().len(), fine.edges().len());
        assert!(
            scene
                .subdivide(0)
                .unwrap_err()
                .to_string()
                .contains("[1, inf)")
        );
    }

    #[test]
    fn with_edge_replaces_and_validates() {
        let scene = unit_box();
        let moved = scene
            .with_edge(EdgeId::new(1), Edge::surface(v(1.0, 0.0), v(1.2, 1.0), 0.5))
            .unwrap();
        assert_eq!(moved.edges()[1].b, v(1.2, 1.0));
        assert_ne!(moved.fingerprint(), scene.fingerprint());
        let err = scene
            .with_edge(EdgeId::new(2), Edge::surface(v(1.0, 1.0), v(1.0, 1.0), 0.5))
            .unwrap_err();
        assert!(err.to_string().starts_with("edge 2: zero length"), "{err}");
        assert!(
            scene
                .with_edge(EdgeId::new(9), scene.edges()[0])
                .unwrap_err()
                .to_string()
                .contains("index 9")
        );
        // Moving one piece of a subdivided edge frees its siblings.
        let fine = scene.subdivide(4).unwrap();
        let e = fine.edges()[5];
        let moved = fine
            .with_edge(
                EdgeId::new(5),
                Edge {
                    b: e.b + v(0.1, 0.0),
                    ..e
                },
            )
            .unwrap();
        assert_eq!(moved.edges().len(), 16);
        assert_eq!(moved.groups().len(), 3 + 4);
    }
}
