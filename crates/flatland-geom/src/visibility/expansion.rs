//! Exact sums and products of `f64`s as nonoverlapping expansions (Shewchuk 1997): the sign of
//! the one degree-4 expression orientation tests cannot decide (which of two crossings is first).

use std::cmp::Ordering;

use glam::DVec2;

/// A number held exactly as a sum of `f64` components, nonoverlapping, in increasing magnitude,
/// zeros left out: the last component carries the sign. Exact while no component over- or
/// underflows; the callers scale by powers of two first ([`to_unit`],
/// [`Expansion::normalized_pair`]), so that holds wherever the orientation predicates hold.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Expansion(Vec<f64>);

/// `a + b` exactly: the rounded sum and its rounding error (Knuth's two-sum).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let b_virtual = s - a;
    let a_virtual = s - b_virtual;
    (s, (a - a_virtual) + (b - b_virtual))
}

/// `a · b` exactly: the rounded product and its rounding error (one fused multiply–add).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl Expansion {
    /// Adds `b` exactly (Grow-Expansion with zero elimination).
    fn add(&mut self, b: f64) {
        let mut q = b;
        let mut out = Vec::with_capacity(self.0.len() + 1);
        for &e in &self.0 {
            let (sum, error) = two_sum(q, e);
            if error != 0.0 {
                out.push(error);
            }
            q = sum;
        }
        if q != 0.0 {
            out.push(q);
        }
        self.0 = out;
    }

    /// `(a − c) × (b − c)` exactly: twice the signed area of `a, b, c`, as `orient2d` signs it.
    pub(super) fn orient(a: DVec2, b: DVec2, c: DVec2) -> Expansion {
        let diff = |x: f64, y: f64| {
            let (hi, lo) = two_sum(x, -y);
            [hi, lo]
        };
        let (acx, acy, bcx, bcy) = (
            diff(a.x, c.x),
            diff(a.y, c.y),
            diff(b.x, c.x),
            diff(b.y, c.y),
        );
        let mut det = Expansion::default();
        for (u, v, sign) in [(acx, bcy, 1.0), (acy, bcx, -1.0)] {
            for &x in &u {
                for &y in &v {
                    let (p, e) = two_product(x, y);
                    det.add(sign * e);
                    det.add(sign * p);
                }
            }
        }
        det
    }

    /// The exact product.
    pub(super) fn times(&self, other: &Expansion) -> Expansion {
        let mut out = Expansion::default();
        for &x in &self.0 {
            for &y in &other.0 {
                let (p, e) = two_product(x, y);
                out.add(e);
                out.add(p);
            }
        }
        out
    }

    /// The exact difference.
    pub(super) fn minus(mut self, other: &Expansion) -> Expansion {
        for &y in &other.0 {
            self.add(-y);
        }
        self
    }

    /// The sign: `Less` below zero, `Equal` at zero, `Greater` above.
    pub(super) fn sign(&self) -> Ordering {
        self.0.last().map_or(Ordering::Equal, |m| m.total_cmp(&0.0))
    }

    /// `self · factor` for a power of two `factor` (exact while no component underflows).
    fn scaled(mut self, factor: f64) -> Expansion {
        self.0.iter_mut().for_each(|c| *c *= factor);
        self.0.retain(|&c| c != 0.0);
        self
    }

    /// `(x, y)` scaled by one power of two so the larger magnitude is about 1, and negated if
    /// needed so `x > 0`: a pair whose ratio and sign pattern matter, not its size, made safe
    /// to multiply by another such pair.
    pub(super) fn normalized_pair(x: Expansion, y: Expansion) -> (Expansion, Expansion) {
        let top = |e: &Expansion| e.0.last().map_or(0.0, |m| m.abs());
        let largest = top(&x).max(top(&y));
        let mut factor = power_of_two(-exponent(largest));
        if x.sign() == Ordering::Less {
            factor = -factor;
        }
        (x.scaled(factor), y.scaled(factor))
    }
}

/// `points` scaled by one power of two so the largest coordinate is about 1: orientations
/// scale by its square, exactly, so their signs and ratios stay, and their exact products stay
/// far from overflow and underflow whatever the scene's scale.
pub(super) fn to_unit<const N: usize>(points: [DVec2; N]) -> [DVec2; N] {
    let largest = points
        .iter()
        .fold(0.0, |m: f64, p| m.max(p.abs().max_element()));
    let factor = power_of_two(-exponent(largest));
    points.map(|p| p * factor)
}

/// The binary exponent of a positive normal `x` (`x ∈ [2^e, 2^(e+1))`), 0 for 0 and
/// subnormals (left unscaled: they are past exactness anyway).
fn exponent(x: f64) -> i32 {
    let biased = ((x.to_bits() >> 52) & 0x7ff) as i32;
    if biased == 0 { 0 } else { biased - 1023 }
}

/// `2^k`, for `k` in the normal range (clamped to it).
fn power_of_two(k: i32) -> f64 {
    f64::from_bits(((k.clamp(-1022, 1023) + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::rng;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// The value of an expansion of integers below 2^120, as an integer.
    fn value(e: &Expansion) -> i128 {
        e.0.iter().map(|&c| c as i128).sum()
    }

    #[test]
    fn orientations_and_products_are_exact_where_floats_round() {
        // Coordinates up to 2^29: determinants reach 2^61 (past f64's 53 bits), products 2^122.
        let mut r = rng(5);
        let big = 1i64 << 29;
        let mut int = || r.random_range(-big..big);
        for _ in 0..2000 {
            let p: Vec<(i64, i64)> = (0..6).map(|_| (int(), int())).collect();
            let f = |k: usize| v(p[k].0 as f64, p[k].1 as f64);
            let exact = |a: (i64, i64), b: (i64, i64), c: (i64, i64)| {
                i128::from(a.0 - c.0) * i128::from(b.1 - c.1)
                    - i128::from(a.1 - c.1) * i128::from(b.0 - c.0)
            };
            let d1 = Expansion::orient(f(0), f(1), f(2));
            let d2 = Expansion::orient(f(3), f(4), f(5));
            let (e1, e2) = (exact(p[0], p[1], p[2]), exact(p[3], p[4], p[5]));
            assert_eq!(value(&d1), e1);
            assert_eq!(d1.sign(), e1.cmp(&0));
            let product = d1.times(&d2);
            // The product's sign, and its difference from a nearby product, exactly.
            assert_eq!(product.sign(), (e1 * e2).cmp(&0));
            let other = d2.times(&Expansion::orient(f(1), f(2), f(3)));
            let e3 = e2 * exact(p[1], p[2], p[3]);
            assert_eq!(product.minus(&other).sign(), (e1 * e2).cmp(&e3));
        }
    }

    #[test]
    fn a_difference_below_every_rounding_has_its_sign() {
        // (2^60 + 1)·(2^60 − 1) − 2^120 = −1: invisible to f64, exact here.
        let x = Expansion(vec![1.0, 2f64.powi(60)]);
        let y = Expansion(vec![-1.0, 2f64.powi(60)]);
        let square = Expansion(vec![2f64.powi(120)]);
        assert_eq!(x.times(&y).minus(&square).sign(), Ordering::Less);
        assert_eq!(x.times(&x).minus(&square).sign(), Ordering::Greater);
        assert_eq!(square.clone().minus(&square).sign(), Ordering::Equal);
    }

    #[test]
    fn normalizing_a_pair_keeps_its_ratio_and_makes_the_first_positive() {
        let x = Expansion(vec![-3.0 * 2f64.powi(300)]);
        let y = Expansion(vec![5.0 * 2f64.powi(300)]);
        let (x, y) = Expansion::normalized_pair(x, y);
        assert_eq!(
            (x.0.as_slice(), y.0.as_slice()),
            (&[0.75][..], &[-1.25][..])
        );
        assert_eq!(exponent(1.0), 0);
        assert_eq!(exponent(0.75), -1);
        assert_eq!(power_of_two(-2), 0.25);
        let [p, q] = to_unit([v(3.0e200, -1.0e200), v(0.0, 2.0e199)]);
        assert!((1.0..2.0).contains(&p.x), "{p}");
        assert_eq!(p.x / q.y, 3.0e200 / 2.0e199);
    }
}
