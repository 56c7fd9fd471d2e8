//! The bound every row of a learned operator obeys: it never sends out more light than its
//! receiver takes in.

/// Makes row `i` of an operator physical, whatever produced it (a network with any weights):
/// every entry finite and ≥ 0 (a negative or NaN entry becomes 0, +∞ the largest float), and
/// the row's sum at most `rho`, the receiving element's reflectance, scaled down if above.
///
/// Why `ρ_i`: a receiving point sees one half-plane, and the transfer of the whole half-plane
/// is 1, so the exact row sums to `ρ_i` at most (exactly in a closed scene). A row above it
/// reflects more light than arrives and makes the solve gain energy (a learned ζ̃ that
/// overshoots gave B − E errors of 27 on a floor plan); a negative entry makes light
/// negative. A row that already obeys both rules is left bit for bit as it is.
pub fn make_physical(row: &mut [f64], rho: f64) {
    let mut sum = 0.0;
    for x in row.iter_mut() {
        if x.is_nan() || *x < 0.0 {
            *x = 0.0;
        } else if *x == f64::INFINITY {
            *x = f64::MAX;
        }
        sum += *x;
    }
    if sum <= rho {
        return;
    }
    // Divide by the largest entry first, so a sum that overflowed still scales right.
    let max = row.iter().copied().fold(0.0, f64::max);
    let relative: f64 = row.iter().map(|x| x / max).sum();
    let scale = rho / max / relative;
    for x in row.iter_mut() {
        *x = (*x * scale).max(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_are_clamped_and_rows_scaled_to_rho() {
        let mut row = [0.2, -0.1, f64::NAN, 0.3];
        make_physical(&mut row, 0.7);
        assert_eq!(
            row,
            [0.2, 0.0, 0.0, 0.3],
            "under ρ: only the bad entries change"
        );
        let mut row = [0.4, 0.4, 0.2];
        make_physical(&mut row, 0.5);
        assert!((row.iter().sum::<f64>() - 0.5).abs() < 1e-15, "{row:?}");
        assert!((row[0] / row[2] - 2.0).abs() < 1e-12, "shares kept");
        // Huge, infinite: finite, the sum ρ.
        for wild in [[1e300, 1e300, 5.0], [f64::INFINITY, 1.0, f64::NEG_INFINITY]] {
            let mut row = wild;
            make_physical(&mut row, 0.6);
            let sum: f64 = row.iter().sum();
            assert!(row.iter().all(|x| x.is_finite() && *x >= 0.0), "{row:?}");
            assert!(sum <= 0.6 * (1.0 + 1e-12) && sum > 0.5, "{row:?}");
        }
        let mut dark = [0.3, 0.2];
        make_physical(&mut dark, 0.0);
        assert_eq!(dark, [0.0, 0.0], "a black receiver reflects nothing");
        let exact = [0.1, 0.25, 0.15];
        let mut same = exact;
        make_physical(&mut same, 0.5);
        assert_eq!(same, exact);
    }
}
