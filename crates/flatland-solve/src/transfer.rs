//! Exact transfer from a segment to a point: the closed form without occlusion, and the exact
//! visible part of a segment seen from a point.
//!
//! **Closed form.** A receiver at `y` with normal `n_y` sees a sender segment whose line does
//! not pass through `y`. Along the segment `cos_x dl_x / r = dφ`, the angle the element subtends
//! at `y`, so with `φ` measured from `n_y`
//! `∫ G dl_x = ∫ cos_x cos_y / (2r) dl_x = ∫ cos φ / 2 dφ = (sin φ₂ − sin φ₁) / 2`
//! over the part of the segment in front of `y` (`cos_y > 0`), and 0 when `y` is behind a
//! sender (`cos_x ≤ 0` along the whole segment; surfaces are one-sided). It is exact (no
//! quadrature), bounded by 1 (the whole half-plane), and finite even for a
//! sender touching the receiver's edge at a corner, where the kernel itself grows like `1/r`.
//!
//! **Visibility.** An occluding segment `c` hides from `y` exactly the points `x` of the sender
//! for which `x` lies strictly beyond `c`'s line (seen from `y`) and the direction `x − y` lies
//! in the cone spanned by `c`'s end points. Both conditions are affine in the sender parameter
//! `u`, so each occluder hides one interval of `u`; the visible part is `[0, 1]` minus their
//! union, and the closed form applies to each visible piece. This is the integral of `G·V`
//! without a single ray: the set where it differs from [`flatland_geom::Kernel`]'s ray rule
//! (rays that graze an end point) has measure zero.

use glam::DVec2;

/// A receiving point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// Where it is.
    pub position: DVec2,
    /// Its edge's front normal (unit).
    pub normal: DVec2,
}

/// A sending segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sender {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Its edge's front normal (unit).
    pub normal: DVec2,
}

/// `∫_sender G(x, y) dl_x` with `G = cos_x cos_y / (2r)` and no occlusion: the closed form.
///
/// 0 when `y` lies on the sender's line or behind the sender. Always finite, in `[0, 1]`.
#[must_use]
pub fn point_to_segment(y: &Receiver, x: &Sender) -> f64 {
    if !faces(y, x) {
        return 0.0;
    }
    subtended(y, x.a, x.b)
}

/// `∫_sender G(x, y) V(x, y) dl_x`: the closed form over the parts of the sender that no
/// segment of `occluders` hides from `y` (see the module docs). `scratch` is reused between
/// calls to avoid allocating.
#[must_use]
pub fn point_to_segment_visible(
    y: &Receiver,
    x: &Sender,
    occluders: &[[DVec2; 2]],
    scratch: &mut Vec<[f64; 2]>,
) -> f64 {
    if !faces(y, x) {
        return 0.0;
    }
    scratch.clear();
    scratch.extend(
        occluders
            .iter()
            .filter_map(|&[c0, c1]| shadow(y.position, x.a, x.b, c0, c1)),
    );
    if scratch.is_empty() {
        return subtended(y, x.a, x.b);
    }
    scratch.sort_by(|p, q| p[0].total_cmp(&q[0]));
    let d = x.b - x.a;
    let mut total = 0.0;
    let mut visible_from = 0.0;
    for &[lo, hi] in scratch.iter() {
        if lo > visible_from {
            total += subtended(y, x.a + d * visible_from, x.a + d * lo);
        }
        visible_from = f64::max(visible_from, hi);
        if visible_from >= 1.0 {
            return total;
        }
    }
    total + subtended(y, x.a + d * visible_from, x.b)
}

/// Whether `y` is on the sending side of the sender's line (strictly).
#[inline]
fn faces(y: &Receiver, x: &Sender) -> bool {
    x.normal.dot(y.position - x.a) > 0.0
}

/// `(sin φ₂ − sin φ₁) / 2` over the part of `q0–q1` in front of the receiver.
#[inline]
fn subtended(y: &Receiver, q0: DVec2, q1: DVec2) -> f64 {
    half_plane(y.position, y.normal, q0, q1)
}

#[inline]
fn half_plane(y: DVec2, n: DVec2, q0: DVec2, q1: DVec2) -> f64 {
    let (f0, f1) = (n.dot(q0 - y), n.dot(q1 - y));
    let (c0, c1) = match (f0 > 0.0, f1 > 0.0) {
        (true, true) => (q0, q1),
        (false, false) => return 0.0,
        (true, false) => (q0, q0 + (q1 - q0) * (f0 / (f0 - f1))),
        (false, true) => (q0 + (q1 - q0) * (f0 / (f0 - f1)), q1),
    };
    let (Some(u0), Some(u1)) = ((c0 - y).try_normalize(), (c1 - y).try_normalize()) else {
        return 0.0;
    };
    // sin φ = u · τ with τ ⊥ n; the sign of τ does not matter for the absolute difference.
    let tau = n.perp();
    0.5 * (tau.dot(u1) - tau.dot(u0)).abs()
}

/// The interval of `u ∈ [0, 1]` where the point `p0 + u (p1 − p0)` is hidden from `y` by the
/// segment `c0–c1`, or `None` (also when `y` lies on the occluder's line, where it hides a set
/// of measure zero at most).
fn shadow(y: DVec2, p0: DVec2, p1: DVec2, c0: DVec2, c1: DVec2) -> Option<[f64; 2]> {
    let orient = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
    let side_y = orient(c0, c1, y);
    if side_y == 0.0 {
        return None;
    }
    let sign = side_y.signum();
    let mut interval = [0.0_f64, 1.0_f64];
    // Each condition is α + β u > 0 (or ≥ 0: the boundary has measure zero either way).
    let mut keep = |alpha: f64, beta: f64| {
        if beta == 0.0 {
            if alpha < 0.0 {
                interval = [1.0, 0.0];
            }
        } else {
            let root = -alpha / beta;
            if beta > 0.0 {
                interval[0] = interval[0].max(root);
            } else {
                interval[1] = interval[1].min(root);
            }
        }
    };
    // Beyond the occluder's line, seen from y: the side opposite y's.
    let (g0, g1) = (orient(c0, c1, p0), orient(c0, c1, p1));
    keep(-sign * g0, -sign * (g1 - g0));
    // In the cone of directions from y to the occluder: a = c0 − y, b = c1 − y,
    // orient(y, c0, c1) = side_y, so w is inside iff sign·(a × w) ≥ 0 and sign·(w × b) ≥ 0.
    let (a, b) = (c0 - y, c1 - y);
    let (w0, d) = (p0 - y, p1 - p0);
    keep(sign * a.perp_dot(w0), sign * a.perp_dot(d));
    keep(sign * w0.perp_dot(b), sign * d.perp_dot(b));
    (interval[1] > interval[0] && interval[1].is_finite() && interval[0].is_finite())
        .then_some(interval)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::{gauss_legendre, integrate};
    use flatland_geom::{Edge, EdgeId, Kernel, Scene};
    use flatland_testkit::assert_close;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn sender(a: DVec2, b: DVec2) -> Sender {
        Sender {
            a,
            b,
            normal: (b - a).perp().normalize(),
        }
    }

    /// `∫ G V` along the sender by Gauss–Legendre, the integrand of docs/ALGORITHM.md §2 written out with
    /// its own occlusion test, the sender split wherever the integrand can jump or kink: where
    /// it crosses the receiver's line, an occluder's line, or the line from `y` through an
    /// occluder's end point. Between those cuts the integrand is smooth.
    fn quadrature(y: &Receiver, x: &Sender, occluders: &[[DVec2; 2]]) -> f64 {
        let rule = gauss_legendre(16);
        let d = x.b - x.a;
        // u where p(u) = a + u d meets the line through q with direction w.
        let meet = |q: DVec2, w: DVec2| {
            let den = d.perp_dot(w);
            (den != 0.0).then(|| (q - x.a).perp_dot(w) / den)
        };
        let mut cuts = vec![0.0, 1.0];
        cuts.extend(meet(y.position, y.normal.perp()));
        for &[c0, c1] in occluders {
            cuts.extend(meet(c0, c1 - c0));
            cuts.extend(meet(y.position, c0 - y.position));
            cuts.extend(meet(y.position, c1 - y.position));
        }
        cuts.retain(|u| (0.0..=1.0).contains(u));
        cuts.sort_by(f64::total_cmp);
        let g = |u: f64| {
            let p = x.a + d * u;
            let dd = y.position - p;
            let r = dd.length();
            let cx = x.normal.dot(dd) / r;
            let cy = -y.normal.dot(dd) / r;
            let hidden = occluders.iter().any(|&[c0, c1]| {
                let o = |a: DVec2, b: DVec2, q: DVec2| (b - a).perp_dot(q - a);
                o(c0, c1, y.position) * o(c0, c1, p) < 0.0
                    && o(y.position, p, c0) * o(y.position, p, c1) < 0.0
            });
            if cx <= 0.0 || cy <= 0.0 || hidden {
                0.0
            } else {
                cx * cy / (2.0 * r)
            }
        };
        // Adaptive: bisect until the two halves agree with the whole (a near-singular peak when
        // y is close to the sender needs it).
        fn adaptive(a: f64, b: f64, whole: f64, depth: u32, f: &dyn Fn(f64, f64) -> f64) -> f64 {
            let m = 0.5 * (a + b);
            let (l, r) = (f(a, m), f(m, b));
            if depth == 0 || (l + r - whole).abs() <= 1e-15 {
                l + r
            } else {
                adaptive(a, m, l, depth - 1, f) + adaptive(m, b, r, depth - 1, f)
            }
        }
        let panel = |a: f64, b: f64| integrate(&rule, a, b, g);
        let total: f64 = cuts
            .windows(2)
            .map(|w| adaptive(w[0], w[1], panel(w[0], w[1]), 30, &panel))
            .sum();
        total * d.length()
    }

    #[test]
    fn closed_form_matches_a_hand_computed_case() {
        // y at the origin facing up, a segment from (−1, 1) to (1, 1) facing down:
        // ∫ 1 / (2 (1 + x²)^{3/2}) dx over [−1, 1] = 1/√2.
        let y = Receiver {
            position: v(0.0, 0.0),
            normal: v(0.0, 1.0),
        };
        let x = sender(v(1.0, 1.0), v(-1.0, 1.0));
        assert_close!(point_to_segment(&y, &x), 0.5f64.sqrt(), 1e-15);
        // Seen from behind the sender: nothing.
        assert_eq!(
            point_to_segment(&y, &sender(v(-1.0, 1.0), v(1.0, 1.0))),
            0.0
        );
        // An infinite wall in front fills the half circle: 1.
        let wall = sender(v(1e9, 1.0), v(-1e9, 1.0));
        assert_close!(point_to_segment(&y, &wall), 1.0, 1e-9);
    }

    #[test]
    fn closed_form_and_visible_part_match_quadrature_on_random_configurations() {
        let mut rng = flatland_testkit::rng(11);
        let mut p = || v(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let mut checked = 0;
        let mut scratch = Vec::new();
        for k in 0..400 {
            let y = Receiver {
                position: p(),
                normal: (p() - p()).try_normalize().unwrap_or(v(0.0, 1.0)),
            };
            let x = sender(p(), p());
            let occluders: Vec<[DVec2; 2]> = (0..k % 4).map(|_| [p(), p()]).collect();
            let exact = point_to_segment_visible(&y, &x, &occluders, &mut scratch);
            let by_quadrature = quadrature(&y, &x, &occluders);
            assert!(
                (exact - by_quadrature).abs() < 1e-10 * by_quadrature.max(1e-3),
                "case {k}: closed form {exact} vs quadrature {by_quadrature}"
            );
            if occluders.is_empty() {
                assert_eq!(exact, point_to_segment(&y, &x));
            }
            checked += usize::from(exact > 0.0);
        }
        assert!(checked > 100, "too few non-zero cases: {checked}");
    }

    #[test]
    fn visible_transfer_agrees_with_the_kernel_rays_in_a_scene() {
        // fig3-like: a floor seen from the ceiling past a floating blocker. The exact kernel's
        // k(s, t) / ρ summed along the floor by dense quadrature (one ray per point) must agree
        // with the visible closed form.
        let edges = vec![
            Edge::surface(v(0.0, 0.0), v(4.0, 0.0), 0.5),
            Edge::surface(v(4.0, 3.0), v(0.0, 3.0), 1.0),
            Edge::blocker(v(1.2, 1.7), v(2.9, 1.3)),
        ];
        let kernel = Kernel::new(Scene::new(edges.clone()).unwrap());
        let l = kernel.scene().total_length();
        let floor = sender(edges[0].a, edges[0].b);
        let occluders = [[edges[2].a, edges[2].b]];
        let mut scratch = Vec::new();
        for &yx in &[0.3, 1.7, 2.2, 3.9] {
            let yp = v(yx, 3.0);
            let y = Receiver {
                position: yp,
                normal: v(0.0, -1.0),
            };
            let t = kernel.scene().param_of(EdgeId::new(1), yp).unwrap();
            let n = 200_000;
            let rays: f64 = (0..n)
                .map(|i| kernel.k((i as f64 + 0.5) / n as f64 * 4.0 / l, t))
                .sum::<f64>()
                * (4.0 / n as f64);
            let exact = point_to_segment_visible(&y, &floor, &occluders, &mut scratch);
            assert!(
                (exact - rays).abs() < 1e-5,
                "y = {yp}: closed form {exact} vs rays {rays}"
            );
            assert!(
                exact < point_to_segment(&y, &floor),
                "the blocker must cast a shadow"
            );
        }
    }

    #[test]
    fn fully_hidden_and_touching_occluders() {
        let y = Receiver {
            position: v(0.0, 0.0),
            normal: v(0.0, 1.0),
        };
        let x = sender(v(1.0, 2.0), v(-1.0, 2.0));
        let mut scratch = Vec::new();
        // A wide wall between them hides everything.
        let wall = [[v(-5.0, 1.0), v(5.0, 1.0)]];
        assert_eq!(point_to_segment_visible(&y, &x, &wall, &mut scratch), 0.0);
        // Two halves meeting in the middle also hide everything (no leak at the joint).
        let halves = [[v(-5.0, 1.0), v(0.0, 1.0)], [v(0.0, 1.0), v(5.0, 1.0)]];
        assert!(point_to_segment_visible(&y, &x, &halves, &mut scratch) < 1e-15);
        // An occluder behind the sender, or on y's own line, hides nothing.
        let behind = [[v(-5.0, 3.0), v(5.0, 3.0)], [v(1.0, 0.0), v(3.0, 0.0)]];
        assert_eq!(
            point_to_segment_visible(&y, &x, &behind, &mut scratch),
            point_to_segment(&y, &x)
        );
        // A post standing on the sender hides the part of it behind the post.
        let post = [[v(0.0, 2.0), v(0.0, 1.5)]];
        let seen = point_to_segment_visible(&y, &x, &post, &mut scratch);
        assert!(
            (seen - point_to_segment(&y, &x)).abs() < 1e-15,
            "y sees both sides of a post straight above it"
        );
        let y_left = Receiver {
            position: v(-0.5, 0.0),
            ..y
        };
        let seen = point_to_segment_visible(&y_left, &x, &post, &mut scratch);
        let total = point_to_segment(&y_left, &x);
        assert!(seen < total && seen > 0.5 * total, "{seen} of {total}");
    }
}
