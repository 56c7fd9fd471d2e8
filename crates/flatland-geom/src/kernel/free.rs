//! Free space between the edges: whether a straight path meets an edge, and how far a point is
//! from the nearest one (what a walk through the rooms asks at every step).

use glam::DVec2;

use super::Kernel;
use crate::visibility::on_closed_segment;

impl Kernel {
    /// Whether the closed segment from `a` to `b` meets no edge of the scene (blockers and
    /// both sides of every surface count): a point moving along it crosses nothing.
    #[must_use]
    pub fn path_is_clear(&self, a: DVec2, b: DVec2) -> bool {
        // The BVH tests the open segment; its end points are tested exactly on their own.
        let on_an_edge = |p: DVec2| {
            self.bvh.overlapping(p, p).into_iter().any(|g| {
                let s = self.segments[g as usize];
                on_closed_segment(p, s.a, s.b)
            })
        };
        !on_an_edge(a) && !on_an_edge(b) && (a == b || !self.bvh.any_hit(a, b, None, None))
    }

    /// The distance from `p` to the nearest edge when it is at most `limit`, `None` when every
    /// edge is farther. Through the BVH: only the edges whose boxes come within `limit` of `p`
    /// are measured.
    #[must_use]
    pub fn nearest_edge_within(&self, p: DVec2, limit: f64) -> Option<f64> {
        let reach = DVec2::splat(limit.max(0.0));
        self.bvh
            .overlapping(p - reach, p + reach)
            .into_iter()
            .map(|g| {
                let s = self.segments[g as usize];
                point_segment_distance(p, s.a, s.b)
            })
            .filter(|&d| d <= limit)
            .min_by(f64::total_cmp)
    }

    /// The median length of the scene's whole (parent) edges.
    pub(crate) fn median_edge_length(&self) -> f64 {
        let mut lengths: Vec<f64> = self.segments.iter().map(|s| s.a.distance(s.b)).collect();
        lengths.sort_by(f64::total_cmp);
        lengths[lengths.len() / 2]
    }
}

/// The distance from `p` to the closed segment `[a, b]`.
pub(crate) fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let u = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * u)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Edge, Scene};
    use flatland_testkit::assert_close;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// A unit square room with a blocker across its middle's left half.
    fn room() -> Kernel {
        let mut edges = Edge::polygon(&[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)], 0.5);
        edges.push(Edge::blocker(v(0.0, 0.5), v(0.5, 0.5)));
        Kernel::new(Scene::new(edges).unwrap())
    }

    #[test]
    fn nearest_edges_and_clear_paths_agree_with_every_edge_tested() {
        let kernel = room();
        let edges = kernel.scene().edges().to_vec();
        let mut rng = flatland_testkit::rng(3);
        for _ in 0..500 {
            let p = v(rng.random_range(-0.2..1.2), rng.random_range(-0.2..1.2));
            let q = v(rng.random_range(-0.2..1.2), rng.random_range(-0.2..1.2));
            let nearest = edges
                .iter()
                .map(|e| point_segment_distance(p, e.a, e.b))
                .fold(f64::INFINITY, f64::min);
            for limit in [0.05, 0.2, 2.0] {
                match kernel.nearest_edge_within(p, limit) {
                    Some(d) => assert_close!(d, nearest, 1e-12),
                    None => assert!(nearest > limit, "{p} {limit}: {nearest}"),
                }
            }
            // A segment that crosses or touches an edge, tested against each with the exact
            // predicate, or an end point on one.
            let blocked = edges.iter().any(|e| {
                crate::visibility::open_segment_hits(p, q, e.a, e.b)
                    || on_closed_segment(p, e.a, e.b)
                    || on_closed_segment(q, e.a, e.b)
            });
            assert_eq!(kernel.path_is_clear(p, q), !blocked, "{p} → {q}");
        }
        // Along the blocker's line, through its end: blocked; just under it: clear.
        assert!(!kernel.path_is_clear(v(0.2, 0.5), v(0.8, 0.5)));
        assert!(kernel.path_is_clear(v(0.2, 0.4), v(0.8, 0.4)));
    }
}
