//! How values are shown: the one colour map and the one scale rule every picture of the project
//! uses (the CLI's heatmaps and lit scenes, the viewer's plots), so a kernel looks the same
//! wherever it is drawn. Pure functions of numbers; no drawing library.

/// Inferno (matplotlib's, sampled at 17 points): black through purple and orange to pale
/// yellow. Perceptually ordered, so a brighter pixel always means a larger value.
const INFERNO: [[u8; 3]; 17] = [
    [0, 0, 4],
    [12, 8, 38],
    [36, 12, 79],
    [66, 10, 104],
    [93, 18, 110],
    [120, 28, 109],
    [147, 38, 103],
    [174, 48, 92],
    [199, 62, 76],
    [221, 81, 58],
    [237, 105, 37],
    [248, 133, 15],
    [252, 165, 10],
    [250, 198, 45],
    [242, 230, 97],
    [246, 250, 150],
    [252, 255, 164],
];

/// The colour of `x ∈ [0, 1]`, linearly interpolated (clamped; NaN is 0).
#[must_use]
pub fn inferno(x: f64) -> [u8; 3] {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let f = x * (INFERNO.len() - 1) as f64;
    let i = (f as usize).min(INFERNO.len() - 2);
    let w = f - i as f64;
    let (a, b) = (INFERNO[i], INFERNO[i + 1]);
    std::array::from_fn(|c| (f64::from(a[c]) * (1.0 - w) + f64::from(b[c]) * w).round() as u8)
}

/// Decades a log scale shows below its top.
pub const LOG_DECADES: f64 = 4.0;

/// The share of positive values at or below the top colour.
pub const TOP_PERCENTILE: f64 = 0.995;

/// A picture's values span decades ([`Scale::wants_log`]) when the top is more than this many
/// times their median.
pub const WIDE_SPAN: f64 = 20.0;

/// How values map to `[0, 1]` before the colour map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// The value shown at full brightness (and above).
    pub top: f64,
    /// Logarithmic ([`LOG_DECADES`] below `top` to `top`) instead of linear (0 to `top`).
    pub log: bool,
}

impl Scale {
    /// A scale whose top is the [`TOP_PERCENTILE`] of the positive finite values, not their
    /// maximum: the kernel grows like `1/r` at shared corners, and a true maximum would paint
    /// everything else black. 1 when nothing is positive.
    #[must_use]
    pub fn fit(values: &[f64], log: bool) -> Scale {
        let mut positive: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && *v > 0.0)
            .collect();
        let top = if positive.is_empty() {
            1.0
        } else {
            let k = ((positive.len() - 1) as f64 * TOP_PERCENTILE) as usize;
            *positive.select_nth_unstable_by(k, f64::total_cmp).1
        };
        Scale { top, log }
    }

    /// Whether the positive values span so many decades that a linear scale would show most of
    /// them black: the top over the median of the positive values is above [`WIDE_SPAN`] (a
    /// floor plan's kernel, bright near corners and faint across rooms).
    #[must_use]
    pub fn wants_log(values: &[f64]) -> bool {
        let mut positive: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && *v > 0.0)
            .collect();
        if positive.is_empty() {
            return false;
        }
        let k = (positive.len() - 1) / 2;
        let median = *positive.select_nth_unstable_by(k, f64::total_cmp).1;
        Scale::fit(values, false).top > WIDE_SPAN * median
    }

    /// `v` mapped to `[0, 1]`; zero, negative and NaN values are 0.
    #[must_use]
    pub fn unit(&self, v: f64) -> f64 {
        if v.is_nan() || v <= 0.0 {
            return 0.0;
        }
        let x = if self.log {
            1.0 + (v / self.top).log10() / LOG_DECADES
        } else {
            v / self.top
        };
        x.clamp(0.0, 1.0)
    }

    /// The value shown at `x ∈ [0, 1]` (the colour bar's labels).
    #[must_use]
    pub fn value_at(&self, x: f64) -> f64 {
        if self.log {
            self.top * 10f64.powf((x - 1.0) * LOG_DECADES)
        } else {
            self.top * x
        }
    }

    /// The colour of `v`.
    #[must_use]
    pub fn colour(&self, v: f64) -> [u8; 3] {
        inferno(self.unit(v))
    }
}

/// The top of a lit scene's colour scale: the brightest finite B of a non-emitting element
/// (emitters are 10–100× brighter than what they light and would leave the rest dark; they are
/// drawn above the scale), the brightest of all when everything emits or nothing is lit; never
/// 0.
#[must_use]
pub fn radiosity_top(mesh: &flatland_solve::Mesh, b: &[f64]) -> f64 {
    let finite_max =
        |it: &mut dyn Iterator<Item = f64>| it.filter(|v| v.is_finite()).fold(0.0_f64, f64::max);
    let lit = finite_max(
        &mut (0..mesh.len())
            .filter(|&i| mesh.edge_of(i).emission == 0.0)
            .map(|i| b[i]),
    );
    if lit > 0.0 {
        lit
    } else {
        finite_max(&mut b.iter().copied()).max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn inferno_runs_from_black_to_pale_yellow_and_brightens() {
        assert_eq!(inferno(0.0), [0, 0, 4]);
        assert_eq!(inferno(1.0), [252, 255, 164]);
        assert_eq!(inferno(f64::NAN), inferno(0.0));
        assert_eq!(inferno(7.0), inferno(1.0));
        let luma =
            |c: [u8; 3]| 0.3 * f64::from(c[0]) + 0.59 * f64::from(c[1]) + 0.11 * f64::from(c[2]);
        for i in 0..100 {
            let (a, b) = (f64::from(i) / 100.0, f64::from(i + 1) / 100.0);
            assert!(luma(inferno(a)) <= luma(inferno(b)) + 0.5, "{a}");
        }
    }

    #[test]
    fn the_top_ignores_corner_spikes_and_the_scale_clamps() {
        let mut values: Vec<f64> = (0..1000).map(|i| f64::from(i) / 1000.0).collect();
        values.push(1e12);
        values.push(f64::INFINITY);
        let scale = Scale::fit(&values, false);
        assert!(scale.top < 1.0 && scale.top > 0.9, "{}", scale.top);
        assert_eq!(Scale::fit(&[0.0, -1.0], false).top, 1.0);
        assert_eq!(scale.unit(1e12), 1.0);
        assert_eq!(scale.unit(-1.0), 0.0);
        assert_eq!(scale.unit(f64::NAN), 0.0);
    }

    #[test]
    fn the_log_scale_shows_four_decades_and_inverts() {
        let scale = Scale {
            top: 1.0,
            log: true,
        };
        assert_eq!(scale.unit(1.0), 1.0);
        assert_close!(scale.unit(1e-2), 0.5, 1e-12);
        assert_eq!(scale.unit(1e-5), 0.0);
        for x in [0.0, 0.25, 0.5, 1.0] {
            assert_close!(scale.unit(scale.value_at(x)), x, 1e-12);
        }
        let linear = Scale {
            top: 2.0,
            log: false,
        };
        assert_eq!(linear.unit(1.0), 0.5);
        assert_eq!(linear.value_at(0.5), 1.0);
    }

    /// Emitters are left out of a lit scene's top (they would leave the rest dark); with nothing
    /// lit but the emitters, the top is theirs; with nothing lit at all, it is still positive.
    #[test]
    fn the_radiosity_top_is_the_brightest_non_emitter() {
        let kernel = flatland_geom::Kernel::new(flatland_geom::bundled::scene("fig3").unwrap());
        let mesh = flatland_solve::Mesh::new(&kernel, 64).unwrap();
        let emits = |i: usize| mesh.edge_of(i).emission > 0.0;
        assert!((0..mesh.len()).any(emits) && !(0..mesh.len()).all(emits));
        let mut b: Vec<f64> = (0..mesh.len())
            .map(|i| if emits(i) { 1e6 } else { i as f64 })
            .collect();
        let brightest = (0..mesh.len()).filter(|&i| !emits(i)).max().unwrap() as f64;
        assert_eq!(radiosity_top(&mesh, &b), brightest);
        // A non-finite B (a diverged solve) is not the top.
        let last = (0..mesh.len()).rfind(|&i| !emits(i)).unwrap();
        b[last] = f64::INFINITY;
        assert!(radiosity_top(&mesh, &b) < brightest);
        let dark: Vec<f64> = (0..mesh.len())
            .map(|i| if emits(i) { 3.0 } else { 0.0 })
            .collect();
        assert_eq!(radiosity_top(&mesh, &dark), 3.0);
        assert_eq!(
            radiosity_top(&mesh, &vec![0.0; mesh.len()]),
            f64::MIN_POSITIVE
        );
    }

    #[test]
    fn values_spanning_decades_want_a_log_scale() {
        let narrow: Vec<f64> = (1..=100).map(f64::from).collect();
        assert!(!Scale::wants_log(&narrow));
        let wide: Vec<f64> = (0..100).map(|i| 10f64.powi(-(i % 5))).collect();
        assert!(Scale::wants_log(&wide));
        assert!(!Scale::wants_log(&[0.0, 0.0]), "nothing to show");
    }
}
