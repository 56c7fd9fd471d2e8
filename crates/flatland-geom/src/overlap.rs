//! Surface edges that lie on top of each other.
//!
//! A scene may legally hold two surface edges on the same line that share a stretch of it
//! (a duplicated line in a file, a wall drawn twice). Each is parameterized and emits on its
//! own, so the light of that stretch is counted twice. Back-to-back one-sided edges (a thin
//! wall's two faces) face opposite ways and are not an overlap; touching end to end (the pieces
//! of a subdivided edge) is not one either.

use std::collections::HashMap;

use glam::DVec2;

use crate::EdgeId;
use crate::scene::Scene;

/// Relative tolerance: distances below this times the scene's diagonal count as zero.
const REL_TOL: f64 = 1e-9;

impl Scene {
    /// Pairs `(i, j)`, `i < j`, of surface edges that share a stretch of positive length (up to
    /// a relative 1e-9 of the scene's size) and face the same way.
    /// Sorted. `O(n log n)` for scenes without overlaps, e.g. every subdivided scene.
    #[must_use]
    pub fn overlapping_surface_edges(&self) -> Vec<(EdgeId, EdgeId)> {
        let (lo, hi) = self.bounds();
        let tol = REL_TOL * (hi - lo).length();
        let edges = self.edges();
        // Group by the line each edge lies on: direction angle in [0, π) and signed offset,
        // quantized; a pair straddling a quantum is found through the neighbouring key.
        let angle_quantum = REL_TOL * 16.0;
        let offset_quantum = (tol * 16.0).max(f64::MIN_POSITIVE);
        let mut lines: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for i in self.surface_edges().iter().map(|e| e.index()) {
            let (theta, offset) = line_of(edges[i].a, edges[i].b);
            let key = (
                (theta / angle_quantum).floor() as i64,
                (offset / offset_quantum).floor() as i64,
            );
            lines.entry(key).or_default().push(i);
        }
        let mut pairs = Vec::new();
        for (&(qa, qo), members) in &lines {
            let mut candidates = members.clone();
            for (da, d_o) in [(0, 1), (1, -1), (1, 0), (1, 1)] {
                if let Some(more) = lines.get(&(qa + da, qo + d_o)) {
                    candidates.extend_from_slice(more);
                }
            }
            sweep(self, &candidates, members, tol, &mut pairs);
        }
        pairs.sort_unstable();
        pairs.dedup();
        pairs
            .into_iter()
            .map(|(i, j)| (EdgeId::new(i), EdgeId::new(j)))
            .collect()
    }
}

/// The line through `a` and `b`: direction angle in `[0, π)` and the signed distance of the line
/// from the origin along the normal of that direction.
fn line_of(a: DVec2, b: DVec2) -> (f64, f64) {
    let mut d = (b - a).normalize();
    if d.y < 0.0 || (d.y == 0.0 && d.x < 0.0) {
        d = -d;
    }
    let theta = d.y.atan2(d.x).clamp(0.0, std::f64::consts::PI);
    (theta, d.perp_dot(a))
}

/// Checks the pairs among `candidates` (at least one of them in `own`) whose extents along the
/// line overlap: sorted by where they start, each is compared with the ones still open.
fn sweep(
    scene: &Scene,
    candidates: &[usize],
    own: &[usize],
    tol: f64,
    out: &mut Vec<(usize, usize)>,
) {
    if candidates.len() < 2 {
        return;
    }
    let edges = scene.edges();
    let first = edges[candidates[0]];
    let axis = (first.b - first.a).normalize();
    let mut spans: Vec<(f64, f64, usize)> = candidates
        .iter()
        .map(|&i| {
            let (p, q) = (axis.dot(edges[i].a), axis.dot(edges[i].b));
            (p.min(q), p.max(q), i)
        })
        .collect();
    spans.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.2.cmp(&y.2)));
    let mut open: Vec<(f64, usize)> = Vec::new();
    for &(start, end, i) in &spans {
        open.retain(|&(open_end, _)| open_end > start + tol);
        for &(_, j) in &open {
            if i != j
                && (own.contains(&i) || own.contains(&j))
                && overlap(edges[i].a, edges[i].b, edges[j].a, edges[j].b, tol)
                && same_facing(scene, i, j)
            {
                out.push((i.min(j), i.max(j)));
            }
        }
        open.push((end, i));
    }
}

/// Whether segment `c–d` lies on the line of `a–b` (within `tol`) and shares more than `tol` of
/// its length with `a–b`.
fn overlap(a: DVec2, b: DVec2, c: DVec2, d: DVec2, tol: f64) -> bool {
    let len = (b - a).length();
    let u = (b - a) / len;
    let off = |p: DVec2| u.perp_dot(p - a).abs();
    if off(c) > tol || off(d) > tol {
        return false;
    }
    let (p, q) = (u.dot(c - a), u.dot(d - a));
    let shared = p.max(q).min(len) - p.min(q).max(0.0);
    shared > tol
}

fn same_facing(scene: &Scene, i: usize, j: usize) -> bool {
    let (e, f) = (scene.edges()[i], scene.edges()[j]);
    e.normal().dot(f.normal()) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Edge;

    fn wall(a: [f64; 2], b: [f64; 2]) -> Edge {
        Edge::surface(DVec2::from(a), DVec2::from(b), 0.5)
    }

    fn room(extra: Vec<Edge>) -> Scene {
        let mut edges = vec![
            wall([0., 0.], [4., 0.]),
            wall([4., 0.], [4., 4.]),
            wall([4., 4.], [0., 4.]),
            wall([0., 4.], [0., 0.]),
        ];
        edges.extend(extra);
        Scene::new(edges).unwrap()
    }

    #[test]
    fn a_duplicated_edge_and_a_collinear_overlap_are_found() {
        let dup = room(vec![wall([0., 0.], [4., 0.])]);
        assert_eq!(
            dup.overlapping_surface_edges(),
            vec![(EdgeId::new(0), EdgeId::new(4))]
        );
        // Same line, partly shared, given in the other order: still facing the same way? No:
        // reversed, it faces out of the room, a back-to-back face, not an overlap.
        let back = room(vec![wall([3., 0.], [1., 0.])]);
        assert!(back.overlapping_surface_edges().is_empty());
        let part = room(vec![wall([1., 0.], [6., 0.])]);
        assert_eq!(
            part.overlapping_surface_edges(),
            vec![(EdgeId::new(0), EdgeId::new(4))]
        );
        // An oblique, off-origin line, slightly perturbed by rounding.
        let (a, b) = ([0.1, 0.3], [3.7, 2.9]);
        let c = [0.1 + 3.6 * 0.3, 0.3 + 2.6 * 0.3];
        let oblique = room(vec![wall(a, b), wall(c, b)]);
        assert_eq!(
            oblique.overlapping_surface_edges(),
            vec![(EdgeId::new(4), EdgeId::new(5))]
        );
    }

    #[test]
    fn touching_parallel_and_subdivided_edges_are_not_overlaps() {
        let touching = room(vec![wall([4., 0.], [6., 0.])]);
        assert!(touching.overlapping_surface_edges().is_empty());
        let parallel = room(vec![wall([0., 1e-3], [4., 1e-3])]);
        assert!(parallel.overlapping_surface_edges().is_empty());
        let fine = room(Vec::new()).subdivide(1000).unwrap();
        assert!(fine.overlapping_surface_edges().is_empty());
        // A blocker on a wall is not a surface.
        let mut edges = room(Vec::new()).edges().to_vec();
        edges.push(Edge::blocker(DVec2::new(0., 0.), DVec2::new(4., 0.)));
        assert!(
            Scene::new(edges)
                .unwrap()
                .overlapping_surface_edges()
                .is_empty()
        );
    }
}
