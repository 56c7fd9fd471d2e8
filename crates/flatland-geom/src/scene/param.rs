//! The arc-length parameterization `s ↦ point` over the parent edges, and its inverse.

use glam::DVec2;

use super::{Group, Scene};
use crate::{EdgeId, SurfaceRank};

/// A point of the parameterization: which edge, where, and that edge's front normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The edge (of a subdivided edge, the piece).
    pub edge: EdgeId,
    /// The point.
    pub position: DVec2,
    /// Front normal of the edge (of its parent edge for a piece made by [`Scene::subdivide`]).
    pub normal: DVec2,
}

impl Scene {
    /// The edges cut from the same parent edge as `edge` by [`Scene::subdivide`], as a range of
    /// consecutive edges (`edge..edge + 1` for an edge that was never subdivided); `None` for
    /// an edge not in the scene. The parent runs from the `a` of the range's start to the `b`
    /// of its last edge and has the material of every piece: a solver that meshes or occludes
    /// with whole edges uses this, so a subdivided scene costs what the original does.
    #[must_use]
    pub fn parent_pieces(&self, edge: EdgeId) -> Option<std::ops::Range<EdgeId>> {
        let g = &self.groups[*self.group_of.get(edge.index())?];
        Some(EdgeId::new(g.first)..EdgeId::new(g.first + g.count))
    }

    /// The rank of `edge`'s parent among the parent surface edges, `None` for a blocker or an
    /// edge not in the scene.
    #[must_use]
    pub fn surface_rank(&self, edge: EdgeId) -> Option<SurfaceRank> {
        self.groups[*self.group_of.get(edge.index())?].rank
    }

    /// The parameter interval `[s0, s1)` of a surface edge, `None` for a blocker or an edge not
    /// in the scene.
    #[must_use]
    pub fn edge_param_range(&self, edge: EdgeId) -> Option<(f64, f64)> {
        let edge = edge.index();
        let g = &self.groups[*self.group_of.get(edge)?];
        let rank = g.rank?.index();
        let k = (edge - g.first) as f64;
        let n = g.count as f64;
        let l = self.total_length;
        let s0 = (self.cum[rank] + g.length * (k / n)) / l;
        let last = rank + 1 == self.surface_groups.len() && edge + 1 == g.first + g.count;
        let s1 = if last {
            1.0
        } else {
            (self.cum[rank] + g.length * ((k + 1.0) / n)) / l
        };
        Some((s0, s1))
    }

    /// The point at arc length `s·L` along the surface chain.
    ///
    /// `s` is taken modulo 1 (the chain is a loop of parameter: `point(-0.25) == point(0.75)`);
    /// a non-finite `s` gives `point(0)`. Never panics. For a scene made by
    /// [`Scene::subdivide`] the result is bit for bit the original scene's, except `edge`, which
    /// names the piece.
    #[must_use]
    pub fn point(&self, s: f64) -> SurfacePoint {
        let (g, u) = self.locate(s);
        let group = &self.groups[g];
        SurfacePoint {
            edge: piece_of(group, u),
            position: lerp(group.a, group.b, u),
            normal: group.normal,
        }
    }

    /// The parameter `s` of the point of surface edge `edge` nearest to `p` (orthogonal
    /// projection, clamped to the edge): the inverse of [`Scene::point`]. `None` for a blocker,
    /// an edge not in the scene or a non-finite `p`.
    #[must_use]
    pub fn param_of(&self, edge: EdgeId, p: DVec2) -> Option<f64> {
        let edge = edge.index();
        let g = &self.groups[*self.group_of.get(edge)?];
        let rank = g.rank?.index();
        if !p.is_finite() {
            return None;
        }
        let d = g.b - g.a;
        let k = (edge - g.first) as f64;
        let n = g.count as f64;
        let u = ((p - g.a).dot(d) / d.length_squared()).clamp(k / n, (k + 1.0) / n);
        Some(below_one(
            (self.cum[rank] + u * g.length) / self.total_length,
        ))
    }

    /// The parameter interval `[s0, s1)` of the parent surface edge of rank `rank` (the
    /// surface edges laid end to end, pieces of a subdivided edge together); `None` past the
    /// last rank.
    #[must_use]
    pub fn parent_param_range(&self, rank: SurfaceRank) -> Option<(f64, f64)> {
        let rank = rank.index();
        if rank + 1 >= self.cum.len() {
            return None;
        }
        let l = self.total_length;
        let s1 = if rank + 2 == self.cum.len() {
            1.0
        } else {
            self.cum[rank + 1] / l
        };
        Some((self.cum[rank] / l, s1))
    }

    /// The parent groups (a single edge is a group of one).
    pub(crate) fn groups(&self) -> &[Group] {
        &self.groups
    }

    /// The group of edge `edge`.
    pub(crate) fn group_of(&self, edge: usize) -> usize {
        self.group_of[edge]
    }

    /// Group index and parameter `u ∈ [0, 1]` along it of the point `s` (see [`Scene::point`]).
    /// The hot path of every kernel evaluation.
    #[inline(always)]
    pub(crate) fn locate(&self, s: f64) -> (usize, f64) {
        let s = wrap(s);
        let arc = s * self.total_length;
        let n = self.surface_groups.len();
        let r = if n <= SMALL_SCENE {
            // Branch-free count of the group starts at or before `arc`: no data-dependent
            // branch or load chain, which is what a binary search costs on a few edges.
            self.cum[1..n].iter().map(|&c| usize::from(c <= arc)).sum()
        } else {
            // Start from the bucket's rank; the scans fix any rounding at bucket borders.
            let nb = self.buckets.len();
            let mut r = self.buckets[((s * nb as f64) as usize).min(nb - 1)] as usize;
            while r > 0 && self.cum[r] > arc {
                r -= 1;
            }
            while r + 1 < n && self.cum[r + 1] <= arc {
                r += 1;
            }
            r
        };
        let g = self.surface_groups[r];
        let u = ((arc - self.cum[r]) * self.inv_length[r]).clamp(0.0, 1.0);
        (g, u)
    }

    /// The position at parameter `u` along group `g` (what [`Scene::point`] returns).
    #[inline]
    pub(crate) fn group_point(&self, g: usize, u: f64) -> DVec2 {
        let group = &self.groups[g];
        lerp(group.a, group.b, u)
    }

    /// The piece of group `g` containing parameter `u`.
    #[inline]
    pub(crate) fn piece(&self, g: usize, u: f64) -> EdgeId {
        piece_of(&self.groups[g], u)
    }
}

/// Up to this many surface groups [`Scene::locate`] counts instead of searching.
const SMALL_SCENE: usize = 16;

#[inline]
pub(super) fn lerp(a: DVec2, b: DVec2, u: f64) -> DVec2 {
    a + (b - a) * u
}

#[inline]
fn piece_of(g: &Group, u: f64) -> EdgeId {
    EdgeId::new(g.first + ((u * g.count as f64) as usize).min(g.count - 1))
}

/// `s` modulo 1 in `[0, 1)`; non-finite gives 0.
#[inline]
fn wrap(s: f64) -> f64 {
    if (0.0..1.0).contains(&s) {
        s
    } else if s.is_finite() {
        below_one(s.rem_euclid(1.0))
    } else {
        0.0
    }
}

/// Maps a value that rounded up to 1 to the largest `f64` below 1.
#[inline]
fn below_one(s: f64) -> f64 {
    if s >= 1.0 {
        1.0 - f64::EPSILON / 2.0
    } else {
        s.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assert_close;
    use crate::test_support::{bundled, rng, room, unit_box};
    use crate::{Edge, Role};
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn point_walks_arc_length_in_file_order_skipping_blockers() {
        let mut edges = room(&[v(0.0, 0.0), v(2.0, 0.0), v(2.0, 1.0), v(0.0, 1.0)], 0.5);
        edges.insert(1, Edge::blocker(v(0.5, 0.5), v(1.5, 0.5)));
        let scene = Scene::new(edges).unwrap();
        assert_eq!(scene.total_length(), 6.0);
        let id = EdgeId::new;
        assert_eq!(scene.surface_edges(), &[id(0), id(2), id(3), id(4)]);
        let p = scene.point(1.0 / 6.0);
        assert_eq!(
            (p.edge, p.position, p.normal),
            (id(0), v(1.0, 0.0), v(0.0, 1.0))
        );
        let p = scene.point(2.5 / 6.0);
        assert_eq!((p.edge, p.position), (id(2), v(2.0, 0.5)));
        assert_eq!(scene.edge_param_range(id(1)), None);
        assert_eq!(scene.edge_param_range(id(0)), Some((0.0, 2.0 / 6.0)));
        assert_eq!(scene.edge_param_range(id(4)), Some((5.0 / 6.0, 1.0)));
        assert_eq!(scene.param_of(id(1), v(1.0, 0.5)), None);
        assert_eq!(scene.param_of(id(99), v(1.0, 0.5)), None);
        let rank = |i| Some(SurfaceRank::new(i));
        assert_eq!(scene.surface_rank(id(0)), rank(0));
        assert_eq!(scene.surface_rank(id(1)), None, "a blocker");
        assert_eq!(scene.surface_rank(id(4)), rank(3));
        assert_eq!(scene.surface_rank(id(99)), None);
    }

    #[test]
    fn point_wraps_outside_the_unit_interval_and_never_panics() {
        let scene = unit_box();
        assert_eq!(scene.point(-0.25), scene.point(0.75));
        assert_eq!(scene.point(1.25), scene.point(0.25));
        assert_eq!(scene.point(f64::NAN), scene.point(0.0));
        assert_eq!(scene.point(f64::INFINITY), scene.point(0.0));
        let end = scene.point(-1e-300);
        assert_eq!(end.edge, EdgeId::new(3));
        assert!(end.position.distance(v(0.0, 0.0)) < 1e-12);
    }

    #[test]
    fn param_of_inverts_point() {
        let scene = bundled("fig3");
        let mut r = rng(1);
        for _ in 0..1000 {
            let s: f64 = r.random_range(0.0..1.0);
            let p = scene.point(s);
            let back = scene.param_of(p.edge, p.position).unwrap();
            assert_close!(back, s, 1e-14);
            let (s0, s1) = scene.edge_param_range(p.edge).unwrap();
            assert!(
                s0 <= s && s < s1,
                "{s} not in [{s0}, {s1}) of edge {}",
                p.edge
            );
        }
    }

    #[test]
    fn locate_agrees_with_a_binary_search_on_large_and_small_scenes() {
        let mut r = rng(9);
        for n in [3, 16, 17, 300] {
            // A polygon with uneven edge lengths (above 16 surfaces, locate uses its buckets).
            let mut angles: Vec<f64> = (0..n)
                .map(|_| r.random_range(0.0..std::f64::consts::TAU))
                .collect();
            angles.sort_by(f64::total_cmp);
            angles.dedup();
            let pts: Vec<DVec2> = angles.iter().map(|a| v(a.cos(), a.sin())).collect();
            let scene = Scene::new(room(&pts, 0.5)).unwrap();
            let mut samples: Vec<f64> = (0..2000).map(|_| r.random_range(0.0..1.0)).collect();
            samples.extend(scene.cum.iter().map(|c| c / scene.total_length));
            for s in samples {
                let arc = wrap(s) * scene.total_length;
                let n = scene.surface_groups.len();
                let expected = scene.cum[1..n].partition_point(|&c| c <= arc);
                let (g, u) = scene.locate(s);
                assert_eq!(
                    scene.groups[g].rank,
                    Some(SurfaceRank::new(expected)),
                    "s = {s}"
                );
                assert!((0.0..=1.0).contains(&u));
            }
        }
    }

    proptest! {
        #[test]
        fn point_stays_on_its_edge(s in -2.0f64..2.0, m in 1usize..50) {
            let scene = bundled("corners").subdivide(m).unwrap();
            let p = scene.point(s);
            let e = *scene.edge(p.edge);
            prop_assert_eq!(e.role, Role::Surface);
            let slack = 1e-12 * (1.0 + e.length());
            prop_assert!(e.a.distance(p.position) + p.position.distance(e.b) <= e.length() + slack);
        }
    }
}
