//! Visibility of a point pair: through the pair's cached shaft, the BVH, or by brute force.

use glam::DVec2;

use super::Kernel;
use crate::EdgeId;
use crate::visibility::{Segment, Shaft, open_segment_hits, orient};

impl Kernel {
    /// `V(x, y)` for `x` on edge `ex` and `y` on edge `ey` (see [`crate::visibility`'s rule in
    /// the crate docs](crate#visibility)): the open segment meets no edge other than `ex`, `ey`
    /// and the pieces of their parent edges. Symmetric. An edge not in the scene excludes
    /// nothing.
    ///
    /// `x` should lie on `ex` and `y` on `ey` (as [`Scene::point`](crate::Scene::point) gives
    /// them, up to rounding): the cached shaft of the two edges is used only then; other points
    /// get a plain BVH ray.
    #[must_use]
    pub fn visible(&self, x: DVec2, ex: EdgeId, y: DVec2, ey: EdgeId) -> bool {
        let (gx, gy) = (self.group(ex), self.group(ey));
        if let (Some(gx), Some(gy)) = (gx, gy)
            && self.roughly_on(x, gx)
            && self.roughly_on(y, gy)
        {
            self.visible_parents(x, gx, y, gy)
        } else {
            !self.bvh.any_hit(x, y, gx, gy)
        }
    }

    /// The same answer as [`Kernel::visible`] by testing every edge (every piece, not parents):
    /// the reference for tests and benches. The two agree exactly for points exactly on their
    /// edges. The accelerated path treats `x` and `y` as exactly on their edges, so for rounded
    /// points they can differ where rounding decides: when an occluder lies on the line of `e_x`
    /// (a coincident, overlapping edge), or a ray passes within rounding of a piece's end point in
    /// a subdivided scene (pieces are rounded copies of their parent).
    #[must_use]
    pub fn visible_brute_force(&self, x: DVec2, ex: EdgeId, y: DVec2, ey: EdgeId) -> bool {
        self.visible_brute_force_groups(x, self.group(ex), y, self.group(ey))
    }

    /// [`Kernel::visible_brute_force`] from `x` on parent `gx` to `y` on parent `gy` (`None`:
    /// on no parent, excluding nothing).
    pub(super) fn visible_brute_force_groups(
        &self,
        x: DVec2,
        gx: Option<usize>,
        y: DVec2,
        gy: Option<usize>,
    ) -> bool {
        !self.scene.edges().iter().enumerate().any(|(i, e)| {
            let g = Some(self.scene.group_of(i));
            g != gx && g != gy && open_segment_hits(x, y, e.a, e.b)
        })
    }

    /// Whether `p` is on parent `g` but not one of its end points (a point of the
    /// parameterization at `u` strictly between 0 and 1).
    #[inline]
    fn strictly_inside(&self, p: DVec2, g: usize) -> bool {
        let s = self.segments[g];
        p != s.a && p != s.b
    }

    /// Whether `p` is within rounding of parent `g`: a loose check, only to route points that
    /// are clearly elsewhere away from the shaft cache.
    fn roughly_on(&self, p: DVec2, g: usize) -> bool {
        let parent = &self.parents[g];
        let (d, w) = (parent.d, p - parent.a);
        let len2 = d.length_squared();
        let u = w.dot(d) / len2;
        (-1e-9..=1.0 + 1e-9).contains(&u) && d.perp_dot(w).abs() <= 1e-9 * len2
    }

    /// `V` between `x` on parent `gx` and `y` on parent `gy`.
    #[inline(always)]
    pub(super) fn visible_parents(&self, x: DVec2, gx: usize, y: DVec2, gy: usize) -> bool {
        if let Some(shaft) = self.shaft(gx, gy) {
            // Canonical order keeps V symmetric: the same shaft and the same tests either way.
            let (x, gx, y, gy) = if self.parents[gx].rank < self.parents[gy].rank {
                (x, gx, y, gy)
            } else {
                (y, gy, x, gx)
            };
            if self.faces(gx, y) && self.faces(gy, x) {
                return match shaft {
                    Shaft::Clear => true,
                    Shaft::Blocked(_) => false,
                    Shaft::Candidates(c) => match c.interior {
                        Some(v) if self.strictly_inside(x, gx) && self.strictly_inside(y, gy) => v,
                        _ if c.occluders.len() <= 8 => !c.occluders.iter().any(|&i| {
                            let s = self.segments[i as usize];
                            open_segment_hits(x, y, s.a, s.b)
                        }),
                        _ => !self.any_hit_facing(x, gx, y, gy),
                    },
                    Shaft::NoFacing => !self.bvh.any_hit(x, y, Some(gx), Some(gy)),
                };
            }
        }
        if self.faces(gx, y) && self.faces(gy, x) {
            !self.any_hit_facing(x, gx, y, gy)
        } else {
            !self.bvh.any_hit(x, y, Some(gx), Some(gy))
        }
    }

    /// Whether the open segment from `x` on parent `gx` to `y` on parent `gy`, which face each
    /// other, meets an occluder. One wholly on or behind the line of `gx` or `gy` can meet it
    /// only at its end, which the open segment leaves out: it never blocks, as in the shaft
    /// test. The plain ray would let rounding decide where `x` is a hair behind its own line
    /// and such an occluder lies on it: a thin wall's other face, back to back.
    fn any_hit_facing(&self, x: DVec2, gx: usize, y: DVec2, gy: usize) -> bool {
        let behind = |g: usize, s: Segment| {
            let p = self.segments[g];
            orient(p.a, p.b, s.a) <= 0.0 && orient(p.a, p.b, s.b) <= 0.0
        };
        self.bvh
            .any_hit_unless(x, y, gx, gy, |s| behind(gx, s) || behind(gy, s))
    }

    /// [`Side::faces`], with a floating-point filter first: the signed distance of `p` from the
    /// line has an error of a few ulps of the coordinates, so beyond `1e-12` of them its sign
    /// is certain; only closer points pay for the exact predicate.
    #[inline]
    fn faces(&self, g: usize, p: DVec2) -> bool {
        let parent = &self.parents[g];
        let c = parent.normal.dot(p - parent.a);
        let tol = 1e-12 * (p.abs() + parent.a.abs()).element_sum();
        if c > tol {
            return true;
        } else if c < -tol {
            return false;
        }
        self.side(g).faces(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{random_scene, rng, room, unit_box};
    use crate::{Edge, Scene};
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn id(i: usize) -> EdgeId {
        EdgeId::new(i)
    }

    #[test]
    fn rays_graze_by_the_documented_rule() {
        let floor = Edge::surface(v(0.0, 0.0), v(2.0, 0.0), 0.5);
        let ceiling = Edge::surface(v(2.0, 2.0), v(0.0, 2.0), 0.5);
        let blocker = Edge::blocker(v(1.0, 1.0), v(1.5, 1.0));
        let touching = Edge::blocker(v(1.5, 1.0), v(1.5, 1.5));
        let kernel = Kernel::new(Scene::new(vec![floor, ceiling, blocker, touching]).unwrap());
        let vis = |x: DVec2, y: DVec2| {
            let a = kernel.visible(x, id(0), y, id(1));
            assert_eq!(a, kernel.visible(y, id(1), x, id(0)), "symmetry");
            assert_eq!(
                a,
                kernel.visible_brute_force(x, id(0), y, id(1)),
                "brute force"
            );
            a
        };
        // Exactly through the blocker's end point (1, 1): blocked.
        assert!(!vis(v(0.5, 0.0), v(1.5, 2.0)));
        // Just beside it: visible.
        assert!(vis(v(0.5, 0.0), v(1.5 - 1e-9, 2.0)));
        // Through the shared corner (1.5, 1) of two blockers: blocked (watertight).
        assert!(!vis(v(2.0, 0.0), v(1.0, 2.0)));
        // Along a blocker (collinear overlap): blocked.
        let wall = Edge::surface(v(0.5, 2.0), v(0.5, 0.0), 0.5);
        let kernel2 = Kernel::new(
            Scene::new(vec![
                wall,
                Edge::surface(v(3.0, 0.5), v(3.0, 1.5), 0.5),
                blocker,
            ])
            .unwrap(),
        );
        assert!(!kernel2.visible(v(0.5, 1.0), id(0), v(3.0, 1.0), id(1)));
        assert!(!kernel2.visible_brute_force(v(0.5, 1.0), id(0), v(3.0, 1.0), id(1)));
        // Points off their edges still get the exact answer (plain ray, no shaft).
        assert!(!kernel.visible(v(0.5, 1.0), id(0), v(3.0, 1.0), id(1)));
        // End points never block: a ray from the floor ending at the blocker's end point sees it.
        let kernel3 = Kernel::new(Scene::new(vec![floor, blocker]).unwrap());
        assert!(kernel3.visible(v(1.0, 0.0), id(0), v(1.0, 1.0), id(1)));
        // Adjacent walls touching the sender at a corner do not block it.
        let boxk = Kernel::new(unit_box());
        assert!(boxk.visible(v(0.5, 0.0), id(0), v(0.0, 0.5), id(3)));
        assert!(
            boxk.visible(v(0.0, 0.0), id(0), v(1.0, 1.0), id(2)),
            "diagonal corner to corner"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

        #[test]
        fn accelerated_visibility_matches_brute_force_and_is_symmetric(seed in any::<u64>(), snap in any::<bool>()) {
            let scene = random_scene(seed, snap);
            let kernel = Kernel::new(scene.clone());
            let mut r = rng(seed ^ 0xb00);
            let edges = scene.edges();
            for _ in 0..300 {
                let (ex, ey) = (r.random_range(0..edges.len()), r.random_range(0..edges.len()));
                // On a snapped scene (coordinates in multiples of ½) points at u = k/16 are exact,
                // so every grazing case (end points, collinear, touching) is decided exactly.
                let mut on = |e: usize| -> DVec2 {
                    let u = if snap { f64::from(r.random_range(0..=16)) / 16.0 } else { r.random_range(0.0..=1.0) };
                    edges[e].point_at(u)
                };
                let (x, y) = (on(ex), on(ey));
                let (ex, ey) = (id(ex), id(ey));
                let fast = kernel.visible(x, ex, y, ey);
                prop_assert_eq!(fast, kernel.visible(y, ey, x, ex), "symmetry");
                prop_assert_eq!(fast, kernel.visible_brute_force(x, ex, y, ey), "x {:?} e{} y {:?} e{}", x, ex, y, ey);
                if !snap {
                    // Rounded points from the parameterization: exact agreement away from
                    // coincident edges, which a non-snapped random scene has with probability 0.
                    let (s, t) = (r.random_range(0.0..1.0), r.random_range(0.0..1.0));
                    prop_assert_eq!(kernel.k(s, t), kernel.k_naive(s, t));
                }
            }
        }
    }

    /// A thin wall as two faces back to back, oblique so that its points round off its line:
    /// each face exchanges light with the wall it faces at every sample, with the shaft cache
    /// and beyond it (hundreds of boxes outside the room), where the plain ray let rounding put
    /// the sample behind the other face half the time.
    #[test]
    fn a_thin_walls_faces_see_their_side_with_and_without_the_shaft_cache() {
        for pad in [0usize, 200] {
            let mut edges = room(&[v(0.0, 0.0), v(4.0, 0.0), v(4.0, 2.0), v(0.0, 2.0)], 0.5);
            edges.push(Edge::surface(v(1.7, 0.3), v(2.3, 1.7), 0.5)); // faces left
            edges.push(Edge::surface(v(2.3, 1.7), v(1.7, 0.3), 0.5)); // faces right
            for k in 0..pad {
                let c = v(10.0 + (k % 20) as f64, (k / 20) as f64);
                let corners = [c, c + v(0.0, 0.3), c + v(0.3, 0.3), c + v(0.3, 0.0)];
                edges.extend(Edge::polygon(&corners, 0.5)); // clockwise: a solid box
            }
            let scene = Scene::new(edges).unwrap();
            let kernel = Kernel::new(scene.clone());
            let range = |e: usize| scene.edge_param_range(id(e)).unwrap();
            let at = |(s0, s1): (f64, f64), u: f64| s0 + (s1 - s0) * u;
            let (left, right) = (range(4), range(5));
            let (left_wall, right_wall) = (range(3), range(1));
            let n = 400;
            let mut dark = 0;
            for i in 0..n {
                let u = (i as f64 + 0.5) / n as f64;
                let w = 0.3 + 0.4 * ((i * 7) % n) as f64 / n as f64;
                for (face, wall) in [(left, left_wall), (right, right_wall)] {
                    dark += usize::from(kernel.k(at(face, u), at(wall, w)) == 0.0);
                    dark += usize::from(kernel.k(at(wall, w), at(face, u)) == 0.0);
                    // And never through the wall to the other side.
                    let other = if wall == left_wall {
                        right_wall
                    } else {
                        left_wall
                    };
                    assert_eq!(kernel.k(at(face, u), at(other, w)), 0.0);
                }
            }
            assert_eq!(dark, 0, "{pad} boxes: {dark} of {} samples dark", 4 * n);
        }
    }
}
