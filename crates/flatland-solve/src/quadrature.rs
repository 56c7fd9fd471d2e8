//! Gauss–Legendre rules, computed once per order by Newton's method on `P_n`.

/// Nodes in `(-1, 1)` (ascending) and weights (summing to 2) of the `n`-point Gauss–Legendre
/// rule, exact for polynomials of degree `2n − 1`. `n = 0` gives the empty rule.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        // Tricomi's initial guess for the i-th largest root, then Newton to full precision.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            derivative = dp;
            let step = p / dp;
            x -= step;
            if step.abs() <= 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(n, x);
        if dp != 0.0 {
            derivative = dp;
        }
        let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
        nodes[n - 1 - i] = x;
        nodes[i] = -x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

/// `P_n(x)` and `P_n'(x)` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

#[cfg(test)]
/// `∫_a^b f` by the rule `(nodes, weights)` of [`gauss_legendre`].
pub fn integrate(rule: &(Vec<f64>, Vec<f64>), a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let (half, mid) = (0.5 * (b - a), 0.5 * (a + b));
    rule.0
        .iter()
        .zip(&rule.1)
        .map(|(&x, &w)| w * f(mid + half * x))
        .sum::<f64>()
        * half
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn rules_integrate_polynomials_of_degree_2n_minus_1_exactly() {
        for n in 1..=24 {
            let rule = gauss_legendre(n);
            assert_close!(rule.1.iter().sum::<f64>(), 2.0, 1e-13, "n = {n}");
            assert!(rule.0.windows(2).all(|w| w[0] < w[1]), "n = {n}");
            for degree in 0..2 * n {
                let got = integrate(&rule, 0.0, 1.0, |x| x.powi(degree as i32));
                let exact = 1.0 / (degree as f64 + 1.0);
                assert!(
                    (got - exact).abs() < 1e-13,
                    "n = {n}, x^{degree}: {got} vs {exact}"
                );
            }
        }
        assert!(gauss_legendre(0).0.is_empty());
        let (x, w) = gauss_legendre(2);
        assert!((x[1] - 1.0 / 3f64.sqrt()).abs() < 1e-15 && (w[0] - 1.0).abs() < 1e-15);
    }
}
