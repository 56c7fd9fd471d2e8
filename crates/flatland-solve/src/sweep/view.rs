//! One side of a receiving point as the sweep sees it: directions named by the sine of their
//! angle from the normal, depths along them, and the directions a segment or a box covers.

use glam::DVec2;

use crate::bvh::Aabb;

/// A segment of the scene in the mesh's unit frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Whether the left of `a → b` is a surface's front (false for a blocker, which has none).
    pub front: bool,
}

/// Boxes nearer than this to the receiving point (unit frame) are taken to cover every
/// direction: their corners' directions would be rounding there.
const TOUCHING: f64 = 1e-9;

/// A segment end this close to the horizon (in radians, seen from the receiving point) lies
/// on it up to rounding.
const ON_HORIZON: f64 = 1e-12;

/// How much a box's range of directions is widened, so rounding never lets culling skip a
/// segment whose end lies on the box's outline.
const WIDEN: f64 = 1e-12;

/// A receiving point `y` looking into the open half-plane its normal `n` points into.
///
/// A direction is named by `σ = sin φ ∈ [−1, 1]`, φ its angle from `n`, counter-clockwise
/// positive: σ grows counter-clockwise, ±1 are the horizon (the receiver's own line), and the
/// closed-form transfer of everything seen between σ₁ and σ₂ is `(σ₂ − σ₁) / 2`, so the sweep
/// never computes an angle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    /// The receiving point.
    pub y: DVec2,
    /// The side it looks to (unit).
    pub n: DVec2,
    /// `n` turned a quarter counter-clockwise: σ's axis.
    t: DVec2,
}

impl View {
    /// The view from `y` into the half-plane of the unit normal `n`.
    pub fn new(y: DVec2, n: DVec2) -> View {
        View { y, n, t: n.perp() }
    }

    /// Whether `s` is a surface whose front faces `y` (strictly).
    #[inline]
    pub fn faced_by(&self, s: &Segment) -> bool {
        s.front && (s.b - s.a).perp_dot(self.y - s.a) > 0.0
    }

    /// Height of `p` above the horizon: positive in front.
    #[inline]
    pub fn height(&self, p: DVec2) -> f64 {
        self.n.dot(p - self.y)
    }

    /// σ of the direction to `p`, a point in front.
    #[inline]
    pub fn sine(&self, p: DVec2) -> f64 {
        let d = p - self.y;
        (self.t.dot(d) / d.length()).clamp(-1.0, 1.0)
    }

    /// σ of the horizon on the side of `p`: where a segment leaving the front half-plane
    /// through `p` is last seen.
    #[inline]
    pub fn horizon(&self, p: DVec2) -> f64 {
        if self.t.dot(p - self.y) >= 0.0 {
            1.0
        } else {
            -1.0
        }
    }

    /// The unit direction σ names.
    #[inline]
    pub fn direction(&self, sigma: f64) -> DVec2 {
        let cos = (1.0 - sigma * sigma).max(0.0).sqrt();
        self.n * cos + self.t * sigma
    }

    /// Distance from `y` along the direction σ to the line of `s` (∞ when parallel).
    #[inline]
    pub fn depth(&self, s: &Segment, sigma: f64) -> f64 {
        let e = s.b - s.a;
        let den = self.direction(sigma).perp_dot(e);
        if den == 0.0 {
            return f64::INFINITY;
        }
        (s.a - self.y).perp_dot(e) / den
    }

    /// The directions `[σ_lo, σ_hi]` in which the part of `s` in front of the horizon is seen;
    /// `None` when it lies behind or is seen edge-on (it subtends nothing). A segment leaving
    /// the front half-plane is clipped where it crosses the horizon, at σ = ±1.
    ///
    /// Edge-on includes a segment on the horizon up to rounding (both ends within
    /// [`ON_HORIZON`] radians of it): the receiver's twin back to back, which holds `y`, would
    /// otherwise cover every direction at depth zero whenever rounding lifts both its ends.
    pub fn span(&self, s: &Segment) -> Option<[f64; 2]> {
        let (ha, hb) = (self.height(s.a), self.height(s.b));
        if ha <= 0.0 && hb <= 0.0 {
            return None;
        }
        if ha.abs() <= ON_HORIZON * (s.a - self.y).length()
            && hb.abs() <= ON_HORIZON * (s.b - self.y).length()
        {
            return None;
        }
        let crossing = || s.a + (s.b - s.a) * (ha / (ha - hb));
        let sa = if ha > 0.0 {
            self.sine(s.a)
        } else {
            self.horizon(crossing())
        };
        let sb = if hb > 0.0 {
            self.sine(s.b)
        } else {
            self.horizon(crossing())
        };
        match sa.total_cmp(&sb) {
            std::cmp::Ordering::Less => Some([sa, sb]),
            std::cmp::Ordering::Greater => Some([sb, sa]),
            std::cmp::Ordering::Equal => None,
        }
    }

    /// Whether the whole box lies on or behind the horizon.
    pub fn behind(&self, b: &Aabb) -> bool {
        b.corners().iter().all(|&c| self.height(c) <= 0.0)
    }

    /// The directions in which anything inside box `b` can be seen (a little wider, never
    /// narrower); `None` when the box lies behind the horizon. A box the receiving point
    /// touches covers every direction.
    pub fn box_span(&self, b: &Aabb) -> Option<[f64; 2]> {
        if b.distance_to(self.y) <= TOUCHING {
            return Some([-1.0, 1.0]);
        }
        let corners = b.corners();
        let heights = corners.map(|c| self.height(c));
        if heights.iter().all(|&h| h <= 0.0) {
            return None;
        }
        // The front part of a convex box not holding y: its front corners and the points
        // where its outline crosses the horizon (all on one side of y).
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..4 {
            let (p, q, hp, hq) = (
                corners[i],
                corners[(i + 1) % 4],
                heights[i],
                heights[(i + 1) % 4],
            );
            if hp > 0.0 {
                let s = self.sine(p);
                (lo, hi) = (lo.min(s), hi.max(s));
            }
            if (hp > 0.0) != (hq > 0.0) {
                let s = self.horizon(p + (q - p) * (hp / (hp - hq)));
                (lo, hi) = (lo.min(s), hi.max(s));
            }
        }
        Some([(lo - WIDEN).max(-1.0), (hi + WIDEN).min(1.0)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn seg(a: DVec2, b: DVec2) -> Segment {
        Segment { a, b, front: true }
    }

    #[test]
    fn sines_name_directions_counter_clockwise_from_the_normal() {
        let view = View::new(v(0.0, 0.0), v(0.0, 1.0));
        assert_eq!(view.sine(v(0.0, 2.0)), 0.0);
        // Counter-clockwise from "up" is to the left.
        assert_close!(view.sine(v(-1.0, 1.0)), 0.5f64.sqrt(), 1e-15);
        assert!((view.sine(v(1.0, 1.0)) + 0.5f64.sqrt()).abs() < 1e-15);
        for sigma in [-1.0, -0.3, 0.0, 0.8, 1.0] {
            let d = view.direction(sigma);
            assert_close!(d.length(), 1.0, 1e-15);
            if sigma.abs() < 1.0 {
                assert_close!(view.sine(d * 3.0), sigma, 1e-15);
            }
        }
        // Depth to the line y = 2 along σ: 2 / cos φ.
        let wall = seg(v(5.0, 2.0), v(-5.0, 2.0));
        assert_close!(view.depth(&wall, 0.6), 2.0 / 0.8, 1e-14);
        assert_eq!(view.depth(&wall, 1.0), f64::INFINITY);
    }

    #[test]
    fn spans_clip_at_the_horizon_and_skip_what_is_behind_or_edge_on() {
        let view = View::new(v(0.0, 0.0), v(0.0, 1.0));
        let [lo, hi] = view.span(&seg(v(1.0, 1.0), v(-1.0, 1.0))).unwrap();
        assert!((lo + 0.5f64.sqrt()).abs() < 1e-15 && (hi - 0.5f64.sqrt()).abs() < 1e-15);
        // Crossing the horizon on the right: seen down to σ = −1.
        let [lo, hi] = view.span(&seg(v(2.0, -1.0), v(2.0, 1.0))).unwrap();
        assert_eq!(lo, -1.0);
        assert!((hi + 2.0 / 5f64.sqrt()).abs() < 1e-15);
        // A post standing on the receiver's line, to the left: from its foot (σ = 1) up.
        let [lo, hi] = view.span(&seg(v(-1.0, 0.0), v(-1.0, 1.0))).unwrap();
        assert_eq!(hi, 1.0);
        assert_close!(lo, 0.5f64.sqrt(), 1e-15);
        assert_eq!(view.span(&seg(v(-1.0, -1.0), v(1.0, -0.5))), None);
        assert_eq!(
            view.span(&seg(v(1.0, 0.0), v(3.0, 0.0))),
            None,
            "on the horizon"
        );
        assert_eq!(view.span(&seg(v(1.0, 1.0), v(2.0, 2.0))), None, "edge-on");
    }

    #[test]
    fn box_spans_hold_every_segment_inside() {
        let view = View::new(v(0.3, 0.1), v(0.6, 0.8));
        let b = Aabb {
            lo: v(-2.0, 0.5),
            hi: v(1.0, 3.0),
        };
        let [lo, hi] = view.box_span(&b).unwrap();
        for k in 0..400 {
            let (x, y) = ((k % 20) as f64 / 19.0, (k / 20) as f64 / 19.0);
            let p = b.lo + (b.hi - b.lo) * v(x, y);
            if view.height(p) > 0.0 {
                let s = view.sine(p);
                assert!(lo <= s && s <= hi, "{s} outside [{lo}, {hi}]");
            }
        }
        // A box crossing the horizon reaches σ = ±1 on its side; one behind has no span.
        let right = Aabb {
            lo: v(2.0, -1.0),
            hi: v(3.0, 1.0),
        };
        assert_eq!(
            View::new(v(0.0, 0.0), v(0.0, 1.0))
                .box_span(&right)
                .unwrap()[0],
            -1.0
        );
        let below = Aabb {
            lo: v(-1.0, -2.0),
            hi: v(1.0, -1.0),
        };
        assert_eq!(View::new(v(0.0, 0.0), v(0.0, 1.0)).box_span(&below), None);
        assert!(View::new(v(0.0, 0.0), v(0.0, 1.0)).behind(&below));
        // A box the point lies in covers everything.
        assert_eq!(view.box_span(&b.expanded(5.0)), Some([-1.0, 1.0]));
    }
}
