//! A ray against segments, exactly: where it first meets one, and which of two contacts is first.

use std::cmp::Ordering;

use glam::DVec2;

use super::expansion::{Expansion, to_unit};
use super::predicates::{collinear_overlap, orient, strictly_opposite, strictly_same_side};

/// A ray as the open segment from `o` to a far point `f` (beyond every segment it is cast
/// against, so `f` itself never matters): `o` never blocks, exactly as a sender never does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ray {
    pub o: DVec2,
    pub f: DVec2,
}

/// Where a ray first meets a closed segment, in the form the exact order needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Contact {
    /// At a point exactly on the ray's line: an end point of the segment touching the ray, the
    /// first point of a collinear overlap, or `o` itself when the segment runs along the ray
    /// across `o`.
    At(DVec2),
    /// Strictly inside the segment `[a, b]`, whose end points lie strictly on opposite sides of
    /// the ray's line; `oa`, `ob` are `orient(o, f, a)` and `orient(o, f, b)` (exact signs,
    /// rounded values): they place the point along the segment.
    Crossing {
        a: DVec2,
        b: DVec2,
        oa: f64,
        ob: f64,
    },
}

impl Ray {
    /// Where the ray meets the closed segment `[a, b]`, by the crate's rule: touching an end
    /// point or running along the segment meets it; `None` if it misses. Decides exactly what
    /// [`open_segment_hits`](super::open_segment_hits)`(o, f, a, b)` decides, at the same cost.
    #[inline]
    pub(crate) fn contact(&self, a: DVec2, b: DVec2) -> Option<Contact> {
        let (o, f) = (self.o, self.f);
        let oa = orient(o, f, a);
        let ob = orient(o, f, b);
        if strictly_same_side(oa, ob) {
            return None;
        }
        if oa == 0.0 && ob == 0.0 {
            return collinear_overlap(o, f, a, b).then(|| self.first_of_overlap(a, b));
        }
        if !strictly_opposite(orient(a, b, o), orient(a, b, f)) {
            return None;
        }
        // The lines cross strictly between o and f; on the segment that is a, b or inside.
        Some(if oa == 0.0 {
            Contact::At(a)
        } else if ob == 0.0 {
            Contact::At(b)
        } else {
            Contact::Crossing { a, b, oa, ob }
        })
    }

    /// The first point of a collinear `[a, b]` the open ray overlaps: its nearer end point, or
    /// `o` if the segment reaches back past it.
    fn first_of_overlap(&self, a: DVec2, b: DVec2) -> Contact {
        let near = if self.along(a, b) == Ordering::Greater {
            b
        } else {
            a
        };
        if self.along(near, self.o) == Ordering::Greater {
            Contact::At(near)
        } else {
            Contact::At(self.o)
        }
    }

    /// The order along the ray of two points exactly on its line (`Less`: `p` first).
    fn along(&self, p: DVec2, q: DVec2) -> Ordering {
        let (o, f) = (self.o, self.f);
        let (pk, qk, forward) = if o.x != f.x {
            (p.x, q.x, f.x > o.x)
        } else {
            (p.y, q.y, f.y > o.y)
        };
        let order = pk.partial_cmp(&qk).unwrap_or(Ordering::Equal);
        if forward { order } else { order.reverse() }
    }

    /// Which of two contacts (each with its segment) comes first along the ray, exactly:
    /// `Less` if `x` does, `Equal` if they are one point.
    pub(crate) fn order(&self, x: &Contact, y: &Contact) -> Ordering {
        match (*x, *y) {
            (Contact::At(p), Contact::At(q)) => self.along(p, q),
            (Contact::At(p), Contact::Crossing { a, b, .. }) => self.point_before_line(p, a, b),
            (Contact::Crossing { a, b, .. }, Contact::At(q)) => {
                self.point_before_line(q, a, b).reverse()
            }
            (Contact::Crossing { a, b, .. }, Contact::Crossing { a: c, b: d, .. }) => {
                self.crossings(a, b, c, d)
            }
        }
    }

    /// Where `p` (on the ray) is against the crossing of the line `a–b`: points before it lie
    /// strictly on `o`'s side of that line.
    fn point_before_line(&self, p: DVec2, a: DVec2, b: DVec2) -> Ordering {
        let (side_o, side_p) = (orient(a, b, self.o), orient(a, b, p));
        if side_p == 0.0 {
            Ordering::Equal
        } else if strictly_same_side(side_o, side_p) {
            Ordering::Less
        } else {
            Ordering::Greater
        }
    }

    /// The order of the crossings of `[a, b]` and `[c, d]`. Where one segment does not cross
    /// the other's line, its whole inside lies on one side of that line, which orders the two
    /// crossings; only segments that cross each other need the exact degree-4 comparison.
    fn crossings(&self, a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Ordering {
        if let Some(side) = side_of_inside(a, b, c, d) {
            // Where [c, d] crosses the ray, against the line a–b.
            return if side == 0.0 {
                Ordering::Equal
            } else if strictly_same_side(side, orient(a, b, self.o)) {
                Ordering::Greater
            } else {
                Ordering::Less
            };
        }
        if let Some(side) = side_of_inside(c, d, a, b) {
            return if side == 0.0 {
                Ordering::Equal
            } else if strictly_same_side(side, orient(c, d, self.o)) {
                Ordering::Less
            } else {
                Ordering::Greater
            };
        }
        self.crossings_exactly(a, b, c, d)
    }

    /// The crossing of line `a–b` is at `τ₁ = α₁ / (α₁ − β₁)` along `o → f`, with `α₁`, `β₁` the
    /// orientations of `o` and `f` against it (of opposite signs; `α₁ > 0` after a sign flip),
    /// and so on for `c–d`. `τ₁ < τ₂ ⟺ α₂ β₁ − α₁ β₂ < 0`, decided in exact arithmetic.
    fn crossings_exactly(&self, a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Ordering {
        let [a, b, c, d, o, f] = to_unit([a, b, c, d, self.o, self.f]);
        let line = |p: DVec2, q: DVec2| {
            Expansion::normalized_pair(Expansion::orient(p, q, o), Expansion::orient(p, q, f))
        };
        let (alpha1, beta1) = line(a, b);
        let (alpha2, beta2) = line(c, d);
        alpha2.times(&beta1).minus(&alpha1.times(&beta2)).sign()
    }

    /// The contact's point and its fraction `u` along `[a, b]` (`a + (b − a) u`, within
    /// rounding of the exact point; `u ∈ [0, 1]`).
    pub(crate) fn locate(&self, contact: &Contact, a: DVec2, b: DVec2) -> (DVec2, f64) {
        match *contact {
            Contact::At(p) => {
                let d = b - a;
                (p, ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0))
            }
            Contact::Crossing { oa, ob, .. } => {
                let u = (oa / (oa - ob)).clamp(0.0, 1.0);
                (a + (b - a) * u, u)
            }
        }
    }
}

/// If the closed `[c, d]` does not cross the line `a–b` strictly, the side (sign of `orient`)
/// of its points other than those on the line: 0 if all lie on it.
fn side_of_inside(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Option<f64> {
    let (sc, sd) = (orient(a, b, c), orient(a, b, d));
    if strictly_opposite(sc, sd) {
        None
    } else {
        Some(if sc != 0.0 { sc } else { sd })
    }
}

#[cfg(test)]
mod tests {
    use super::super::open_segment_hits;
    use super::*;
    use crate::test_support::rng;
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// The contact's exact position along the ray of integer points, as a fraction `num / den`
    /// of `o → f` (`den > 0`).
    fn exact_tau(ray: &Ray, contact: &Contact, a: DVec2, b: DVec2) -> (i128, i128) {
        let int = |p: DVec2| (p.x as i128, p.y as i128);
        let cross = |p: (i128, i128), q: (i128, i128), r: (i128, i128)| {
            (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
        };
        let (o, f) = (int(ray.o), int(ray.f));
        match *contact {
            Contact::At(p) => {
                let (p, axis) = (int(p), usize::from(ray.o.x == ray.f.x));
                let pick = |q: (i128, i128)| if axis == 0 { q.0 } else { q.1 };
                let den = pick(f) - pick(o);
                let num = pick(p) - pick(o);
                if den < 0 { (-num, -den) } else { (num, den) }
            }
            Contact::Crossing { .. } => {
                let (alpha, beta) = (cross(int(a), int(b), o), cross(int(a), int(b), f));
                let (num, den) = (alpha, alpha - beta);
                if den < 0 { (-num, -den) } else { (num, den) }
            }
        }
    }

    proptest! {
        /// On small integer coordinates every position is an exact fraction: the contact agrees
        /// with the segment test, and the order of any two contacts with the fractions.
        #[test]
        fn contacts_and_their_order_are_exact(seed in any::<u64>()) {
            let mut r = rng(seed);
            let int = |r: &mut rand_chacha::ChaCha8Rng| {
                v(f64::from(r.random_range(-6..=6)), f64::from(r.random_range(-6..=6)))
            };
            for _ in 0..200 {
                let ray = Ray { o: int(&mut r), f: int(&mut r) * 3.0 };
                if ray.o == ray.f {
                    continue;
                }
                let segments: Vec<(DVec2, DVec2)> =
                    (0..2).map(|_| (int(&mut r), int(&mut r))).collect();
                let mut contacts = Vec::new();
                for &(a, b) in &segments {
                    let c = ray.contact(a, b);
                    prop_assert_eq!(c.is_some(), open_segment_hits(ray.o, ray.f, a, b));
                    if let Some(c) = c {
                        let (num, den) = exact_tau(&ray, &c, a, b);
                        prop_assert!(num >= 0 && num < den, "{:?} {:?}", c, (num, den));
                        contacts.push((c, num, den));
                    }
                }
                if let [(x, n1, d1), (y, n2, d2)] = contacts[..] {
                    let truth = (n1 * d2).cmp(&(n2 * d1));
                    prop_assert_eq!(ray.order(&x, &y), truth, "{:?} {:?} {:?}", ray, x, y);
                    prop_assert_eq!(ray.order(&y, &x), truth.reverse());
                }
            }
        }
    }

    #[test]
    fn crossing_segments_are_ordered_exactly_where_floats_cannot() {
        // Two segments crossing at (0, 0); the ray passes 2^-60 below that point, so the crossing
        // of the steeper one comes first, by far less than any rounding of the positions.
        let ray = Ray {
            o: v(-1.0, -(2f64.powi(-60))),
            f: v(3.0, -(2f64.powi(-60))),
        };
        let (a, b) = (v(-1.0, -1.0), v(1.0, 1.0));
        let (c, d) = (v(-1.0, -3.0), v(1.0, 3.0));
        let (x, y) = (ray.contact(a, b).unwrap(), ray.contact(c, d).unwrap());
        assert!(matches!(x, Contact::Crossing { .. }) && matches!(y, Contact::Crossing { .. }));
        // Line y = x is crossed at x = −2^-60, y = 3x at x = −2^-60 / 3: later along +x.
        assert_eq!(ray.order(&x, &y), Ordering::Less);
        assert_eq!(ray.order(&y, &x), Ordering::Greater);
        let through = Ray {
            o: v(-1.0, 0.0),
            f: v(3.0, 0.0),
        };
        let (x, y) = (
            through.contact(a, b).unwrap(),
            through.contact(c, d).unwrap(),
        );
        assert_eq!(
            through.order(&x, &y),
            Ordering::Equal,
            "both through (0, 0)"
        );
    }

    #[test]
    fn grazing_contacts_follow_the_rule() {
        let ray = Ray {
            o: v(0.0, 0.0),
            f: v(10.0, 0.0),
        };
        assert_eq!(
            ray.contact(v(2.0, 0.0), v(2.0, 1.0)),
            Some(Contact::At(v(2.0, 0.0))),
            "end point"
        );
        assert_eq!(
            ray.contact(v(3.0, 0.0), v(1.0, 0.0)),
            Some(Contact::At(v(1.0, 0.0))),
            "along"
        );
        assert_eq!(
            ray.contact(v(-1.0, 0.0), v(1.0, 0.0)),
            Some(Contact::At(v(0.0, 0.0))),
            "across o"
        );
        assert_eq!(
            ray.contact(v(0.0, 0.0), v(0.0, 1.0)),
            None,
            "o never blocks"
        );
        assert_eq!(
            ray.contact(v(-2.0, 0.0), v(0.0, 0.0)),
            None,
            "collinear, ending at o"
        );
        let leftwards = Ray {
            o: v(0.0, 0.0),
            f: v(-10.0, 0.0),
        };
        assert_eq!(
            leftwards.contact(v(-3.0, 0.0), v(-1.0, 0.0)),
            Some(Contact::At(v(-1.0, 0.0)))
        );
    }
}
