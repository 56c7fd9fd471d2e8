//! Closest-hit rays: the first edge a ray meets, through the BVH or by scanning every edge.

use std::cmp::Ordering;

use glam::DVec2;

use super::{Hit, Kernel};
use crate::EdgeId;
use crate::visibility::{Contact, Ray, orient, wins_tie};

impl Kernel {
    /// The first edge the ray `origin + λ·direction`, `λ > 0`, meets, or `None` if it leaves
    /// the scene. `skip` (the edge the ray leaves from) and the other pieces of its parent edge
    /// are never met; an edge not in the scene skips nothing. Also `None` for a zero or
    /// non-finite `direction` or `origin`.
    ///
    /// The rule is visibility's ([crate docs](crate#visibility)): edges are closed, so a ray
    /// that touches an end point or runs along an edge meets it (at the first point of the
    /// overlap), and the origin itself never counts. Which edge comes first is decided exactly,
    /// and of several met at one point (a corner, a junction, a thin wall's two faces back to
    /// back) a surface whose front faces `origin` comes first, then the one listed first in
    /// the scene, so the answer is [`Kernel::first_hit_brute_force`]'s. The ray is the open
    /// segment from `origin` to a point beyond the scene along `direction` (as rounded).
    ///
    /// A ray that leaves `skip` (from a point on it, up to rounding) into its front meets
    /// nothing wholly on or behind `skip`'s line: it could only do so at `origin`, which never
    /// counts. So a photon leaving a thin wall's face never stops on the other face behind it,
    /// wherever rounding put `origin`.
    ///
    /// Every edge occludes, blockers too; what a hit means (front or back, reflect or absorb)
    /// is the caller's: `direction · normal < 0` is a hit on the front.
    #[must_use]
    pub fn first_hit(&self, origin: DVec2, direction: DVec2, skip: Option<EdgeId>) -> Option<Hit> {
        let (ray, skip) = self.ray(origin, direction, skip)?;
        let (group, contact) = self.bvh.first_hit(&ray, skip, self.judge(&ray, skip))?;
        Some(self.hit(&ray, group, &contact))
    }

    /// The parent (group) [`Kernel::first_hit`] meets from `origin` along `direction`, skipping
    /// nothing: what a lamp's rays ask (`kernel/lamps.rs`).
    pub(super) fn first_parent_hit(&self, origin: DVec2, direction: DVec2) -> Option<usize> {
        let (ray, _) = self.ray(origin, direction, None)?;
        let (group, _) = self.bvh.first_hit(&ray, None, self.judge(&ray, None))?;
        Some(group)
    }

    /// For a parent the ray meets: `None` if the meeting does not count (wholly on or behind
    /// the line of `skip`, which the ray leaves into its front), else whether it is a surface
    /// whose front faces the origin (which wins a tie at one point).
    fn judge(&self, ray: &Ray, skip: Option<usize>) -> impl Fn(usize) -> Option<bool> + '_ {
        let leaving = skip
            .map(|g| self.segments[g])
            .filter(|s| orient(s.a, s.b, ray.f) > 0.0);
        let o = ray.o;
        move |group: usize| {
            let s = self.segments[group];
            if let Some(own) = leaving
                && orient(own.a, own.b, s.a) <= 0.0
                && orient(own.a, own.b, s.b) <= 0.0
            {
                return None;
            }
            Some(self.parents[group].rank.is_some() && orient(s.a, s.b, o) > 0.0)
        }
    }

    /// The same answer as [`Kernel::first_hit`] by testing every parent edge: the reference
    /// for tests and benches.
    #[must_use]
    pub fn first_hit_brute_force(
        &self,
        origin: DVec2,
        direction: DVec2,
        skip: Option<EdgeId>,
    ) -> Option<Hit> {
        let (ray, skip) = self.ray(origin, direction, skip)?;
        let judge = self.judge(&ray, skip);
        let mut best: Option<(usize, Contact)> = None;
        for (group, s) in self.segments.iter().enumerate() {
            if Some(group) == skip {
                continue;
            }
            let Some(contact) = ray.contact(s.a, s.b) else {
                continue;
            };
            let Some(facing) = judge(group) else {
                continue;
            };
            let first = best.is_none_or(|(b, first)| match ray.order(&contact, &first) {
                Ordering::Less => true,
                Ordering::Equal => wins_tie(facing, group, judge(b) == Some(true), b),
                Ordering::Greater => false,
            });
            if first {
                best = Some((group, contact));
            }
        }
        best.map(|(group, contact)| self.hit(&ray, group, &contact))
    }

    /// The ray as a segment to beyond the scene, and the parent group it skips, if any.
    fn ray(
        &self,
        origin: DVec2,
        direction: DVec2,
        skip: Option<EdgeId>,
    ) -> Option<(Ray, Option<usize>)> {
        if !origin.is_finite() {
            return None;
        }
        let far = self.bvh.far_point(origin, direction)?;
        let skip = skip.and_then(|edge| self.group(edge));
        Some((Ray { o: origin, f: far }, skip))
    }

    /// The hit of `contact` on parent `group`: the piece it falls in and the fraction along it.
    fn hit(&self, ray: &Ray, group: usize, contact: &Contact) -> Hit {
        let s = self.segments[group];
        let (point, u) = ray.locate(contact, s.a, s.b);
        let parent = &self.scene.groups()[group];
        let pieces = parent.count as f64;
        let k = ((u * pieces) as usize).min(parent.count - 1);
        Hit {
            edge: EdgeId::new(parent.first + k),
            distance: (point - ray.o).length(),
            point,
            u: (u * pieces - k as f64).clamp(0.0, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{random_scene, rng, unit_box};
    use crate::{Edge, Scene};
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn id(i: usize) -> EdgeId {
        EdgeId::new(i)
    }

    /// The first hit leaving edge `skip` (an index), checked against brute force.
    fn hit(kernel: &Kernel, o: DVec2, d: DVec2, skip: Option<usize>) -> Option<Hit> {
        let skip = skip.map(id);
        let h = kernel.first_hit(o, d, skip);
        assert_eq!(h, kernel.first_hit_brute_force(o, d, skip), "brute force");
        h
    }

    #[test]
    fn rays_hit_the_first_edge_by_the_documented_rule() {
        let boxk = Kernel::new(unit_box());
        // Straight up from the floor: the ceiling (1,1)→(0,1), halfway along.
        let up = hit(&boxk, v(0.5, 0.0), v(0.0, 1.0), Some(0)).unwrap();
        assert_eq!(
            (up.edge, up.point, up.u, up.distance),
            (id(2), v(0.5, 1.0), 0.5, 1.0)
        );
        // Exactly into the corner (1, 1) of the right wall (edge 1) and the ceiling (edge 2):
        // the first listed.
        let corner = hit(&boxk, v(0.5, 0.5), v(1.0, 1.0), None).unwrap();
        assert_eq!(
            (corner.edge, corner.point, corner.u),
            (id(1), v(1.0, 1.0), 1.0)
        );
        // From the corner (0, 0) the left wall touching it does not count.
        assert_eq!(
            hit(&boxk, v(0.0, 0.0), v(1.0, 1.0), Some(0)).unwrap().edge,
            id(1)
        );
        // Leaving a corner along the floor runs along it: met at once.
        let along = hit(&boxk, v(0.0, 0.0), v(1.0, 0.0), Some(3)).unwrap();
        assert_eq!((along.edge, along.distance, along.u), (id(0), 0.0, 0.0));
        assert_eq!(boxk.first_hit(v(0.5, 0.5), DVec2::ZERO, None), None);
        assert_eq!(boxk.first_hit(v(f64::NAN, 0.5), v(1.0, 0.0), None), None);

        let floor = Edge::surface(v(0.0, 0.0), v(2.0, 0.0), 0.5);
        let blocker = Edge::blocker(v(1.0, 1.0), v(1.5, 1.0));
        let kernel = Kernel::new(Scene::new(vec![floor, blocker]).unwrap());
        // Through the blocker's end point: met there. Along it: met at its first point.
        let tip = hit(&kernel, v(1.0, 0.0), v(0.0, 1.0), Some(0)).unwrap();
        assert_eq!(
            (tip.edge, tip.point, tip.distance),
            (id(1), v(1.0, 1.0), 1.0)
        );
        let run = hit(&kernel, v(3.0, 1.0), v(-1.0, 0.0), None).unwrap();
        assert_eq!((run.edge, run.point, run.u), (id(1), v(1.5, 1.0), 1.0));
        // Upwards past the blocker: nothing, the scene is open.
        assert_eq!(hit(&kernel, v(0.5, 0.0), v(0.0, 1.0), Some(0)), None);
    }

    #[test]
    fn a_subdivided_edge_is_met_in_the_right_piece_and_skipped_whole() {
        let fine = Kernel::new(unit_box().subdivide(4).unwrap());
        // The ceiling is edges 8..12, each a quarter from (1, 1) to (0, 1): x = 0.3 is 0.7 of
        // the way, in the third piece, 0.8 along it.
        let h = hit(&fine, v(0.3, 0.0), v(0.0, 1.0), Some(1)).unwrap();
        assert_eq!(h.edge, id(10));
        assert!((h.u - 0.8).abs() < 1e-12 && (h.point - v(0.3, 1.0)).length() < 1e-15);
        let p = fine.scene().edge(h.edge).point_at(h.u);
        assert!((p - h.point).length() < 1e-15);
        // From the floor's first piece along the floor: its other pieces are skipped too.
        let along = hit(&fine, v(0.1, 0.0), v(1.0, 0.0), Some(0)).unwrap();
        assert_eq!(
            (along.edge, along.point),
            (id(4), v(1.0, 0.0)),
            "the right wall's corner"
        );
    }

    /// A thin oblique wall, its faces back to back in both listing orders: a ray from either
    /// face into its front never stops on the other face (wherever rounding put its origin),
    /// and a ray from the room meets the face towards it.
    #[test]
    fn a_thin_walls_faces_are_met_from_their_own_side() {
        for swap in [false, true] {
            let mut edges =
                crate::Edge::polygon(&[v(0.0, 0.0), v(4.0, 0.0), v(4.0, 2.0), v(0.0, 2.0)], 0.5);
            let (p, q) = (v(1.7, 0.3), v(2.3, 1.7));
            let (left, right) = (Edge::surface(p, q, 0.5), Edge::surface(q, p, 0.5));
            edges.extend(if swap { [right, left] } else { [left, right] });
            let (l, r) = if swap { (5, 4) } else { (4, 5) };
            let kernel = Kernel::new(Scene::new(edges.clone()).unwrap());
            let mut rng = rng(5);
            for _ in 0..500 {
                let u: f64 = rng.random_range(0.01..0.99);
                let angle: f64 = rng.random_range(-1.5..1.5);
                for face in [l, r] {
                    let n = edges[face].normal();
                    let d = n * angle.cos() + n.perp() * angle.sin();
                    let h = hit(&kernel, edges[face].point_at(u), d, Some(face)).unwrap();
                    assert!(
                        h.edge < id(4),
                        "from face {face}: stopped on edge {}",
                        h.edge
                    );
                    // Back along the same line from the wall it reached: the face it left.
                    let back = hit(&kernel, h.point, -d, Some(h.edge.index())).unwrap();
                    assert_eq!(back.edge, id(face), "from {:?} towards the wall", h.point);
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

        /// Rays from points on edges (as a tracer casts them) and from anywhere, in random
        /// directions and along the axes and diagonals (which, on a snapped scene, run through
        /// end points and along edges): the BVH's answer is the scan's, and the hit lies on
        /// its edge.
        #[test]
        fn closest_hits_match_the_scan(seed in any::<u64>(), snap in any::<bool>()) {
            let scene = random_scene(seed, snap);
            let kernel = Kernel::new(scene.clone());
            let mut r = rng(seed ^ 0x4a7);
            let edges = scene.edges();
            for _ in 0..300 {
                let from = r.random_range(0..edges.len() + 1);
                let (o, skip) = if from < edges.len() {
                    let u = if snap {
                        f64::from(r.random_range(0..=4)) / 4.0
                    } else {
                        r.random_range(0.0..=1.0)
                    };
                    (edges[from].point_at(u), Some(id(from)))
                } else {
                    (v(r.random_range(-1.5..1.5), r.random_range(-1.5..1.5)), None)
                };
                let d = if r.random_bool(0.5) {
                    let angle: f64 = r.random_range(0.0..std::f64::consts::TAU);
                    v(angle.cos(), angle.sin())
                } else {
                    v(f64::from(r.random_range(-1..=1)), f64::from(r.random_range(-1..=1)))
                };
                let fast = kernel.first_hit(o, d, skip);
                let slow = kernel.first_hit_brute_force(o, d, skip);
                prop_assert_eq!(fast, slow, "o {:?} d {:?} skip {:?}", o, d, skip);
                if let Some(h) = fast {
                    let e = scene.edge(h.edge);
                    prop_assert!((e.point_at(h.u) - h.point).length() <= 1e-9 * (1.0 + e.length()));
                    prop_assert!(((h.point - o).length() - h.distance).abs() <= 1e-12);
                }
            }
        }
    }
}
