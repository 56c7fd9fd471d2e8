//! Value → colour: the heatmap and radiosity colour maps, the heatmap scale (linear or log), and
//! the images built from grids and sample points. Pure functions, so they are cheap to test and
//! run only when the data they show has changed.

use egui::{Color32, ColorImage};

// The two colour maps and the scale rule are those of the `flatland` CLI's pictures (viridis
// heatmaps scaled to the 99.5th percentile over four decades; inferno for radiosity), so a
// picture from `flatland kernel` or `flatland solve` and the viewer read the same.

/// Viridis (matplotlib's, 17 samples): the kernel heatmaps. Perceptually ordered, so a brighter
/// pixel always means a larger value; the cells, drawn white and cyan, stay visible over it.
const VIRIDIS: [[u8; 3]; 17] = [
    [68, 1, 84],
    [72, 21, 104],
    [72, 38, 119],
    [69, 55, 129],
    [63, 71, 136],
    [57, 85, 140],
    [50, 100, 142],
    [45, 113, 142],
    [40, 125, 142],
    [35, 138, 141],
    [31, 150, 139],
    [32, 163, 134],
    [41, 175, 127],
    [62, 188, 116],
    [86, 198, 103],
    [119, 209, 83],
    [253, 231, 37],
];

/// Inferno (matplotlib's, 17 samples): black through purple and orange to pale yellow, the
/// colours of light, for the radiosity of the lit scene.
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

/// `x ∈ [0, 1]` (clamped; NaN is 0) interpolated linearly in `table`.
fn interpolate(table: &[[u8; 3]], x: f32) -> Color32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let f = x * (table.len() - 1) as f32;
    let i = (f.floor() as usize).min(table.len() - 2);
    let u = f - i as f32;
    let [a, b] = [table[i], table[i + 1]];
    let mix = |k: usize| (f32::from(a[k]) + u * (f32::from(b[k]) - f32::from(a[k]))).round() as u8;
    Color32::from_rgb(mix(0), mix(1), mix(2))
}

/// The heatmap colour of `x ∈ [0, 1]` (viridis; clamped, NaN is 0).
#[must_use]
pub fn heat_colour(x: f32) -> Color32 {
    interpolate(&VIRIDIS, x)
}

/// The colour of a radiosity at `x ∈ [0, 1]` of its scale (inferno; clamped, NaN is 0).
#[must_use]
pub fn light_colour(x: f32) -> Color32 {
    interpolate(&INFERNO, x)
}

/// How values map to `[0, 1]` before the colour map.
///
/// `max` is the 99.5th percentile of the positive values, not the maximum: the kernel grows
/// like `1/r` near shared vertices, and a true maximum would paint everything else black.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// The value shown at full brightness (and above).
    pub max: f64,
    /// Logarithmic (`decades` below `max` to `max`) instead of linear (`0` to `max`).
    pub log: bool,
    /// Decades shown by the log scale.
    pub decades: f64,
}

impl Scale {
    /// A scale fitted to `values` (see the type docs).
    #[must_use]
    pub fn fit(values: &[f64], log: bool) -> Scale {
        let mut positive: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && *v > 0.0)
            .collect();
        let max = if positive.is_empty() {
            1.0
        } else {
            let k = ((positive.len() - 1) as f64 * 0.995) as usize;
            let (_, v, _) = positive.select_nth_unstable_by(k, f64::total_cmp);
            *v
        };
        Scale {
            max,
            log,
            decades: 4.0,
        }
    }

    /// `v` mapped to `[0, 1]`; zero, negative and NaN values are 0.
    #[must_use]
    pub fn unit(&self, v: f64) -> f32 {
        if v.is_nan() || v <= 0.0 {
            return 0.0;
        }
        let x = if self.log {
            (v / self.max).log10() / self.decades + 1.0
        } else {
            v / self.max
        };
        x.clamp(0.0, 1.0) as f32
    }
}

/// A `res × res` grid (row-major, row `i` ↔ `s = (i + ½)/res`, column `j` ↔ `t`) as an image
/// with `t` to the right and `s` upwards (row 0 of the grid is the bottom row of the image).
#[must_use]
pub fn grid_image(values: &[f64], res: usize, scale: Scale) -> ColorImage {
    assert_eq!(
        values.len(),
        res * res,
        "grid_image: {} values for res {res}",
        values.len()
    );
    let mut pixels = Vec::with_capacity(res * res);
    for row in (0..res).rev() {
        pixels.extend(
            values[row * res..(row + 1) * res]
                .iter()
                .map(|&v| heat_colour(scale.unit(v))),
        );
    }
    ColorImage::new([res, res], pixels)
}

/// The colour of sample set `set`: S₀ light grey, later sets spread around the hue circle.
#[must_use]
pub fn set_color(set: u32) -> Color32 {
    if set == 0 {
        return Color32::from_rgb(200, 200, 200);
    }
    // Golden-ratio hue steps keep consecutive sets apart.
    let hue = (f32::from(set as u16) * 0.618_034).fract();
    egui::ecolor::Hsva::new(hue, 0.85, 1.0, 1.0).into()
}

/// Sample points `(s, t)` splatted into a transparent `res × res` image (same orientation as
/// [`grid_image`]), coloured by set; later sets are drawn over earlier ones.
#[must_use]
pub fn samples_image(samples: &[([f32; 2], u32)], res: usize) -> ColorImage {
    let mut image = ColorImage::filled([res, res], Color32::TRANSPARENT);
    let n = res as f32;
    for &([s, t], set) in samples {
        if !(s.is_finite() && t.is_finite()) {
            continue;
        }
        let col = ((t * n) as usize).min(res - 1);
        let row = res - 1 - ((s * n) as usize).min(res - 1);
        image.pixels[row * res + col] = set_color(set);
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_maps_run_dark_to_bright_and_are_total() {
        let luma = |c: Color32| u32::from(c.r()) + u32::from(c.g()) + u32::from(c.b());
        for map in [heat_colour, light_colour] {
            let mut last = 0;
            for i in 0..=100 {
                let l = luma(map(i as f32 / 100.0));
                assert!(l >= last, "brightness drops at {i}: {l} < {last}");
                last = l;
            }
            assert_eq!(map(f32::NAN), map(0.0));
            assert_eq!(map(2.0), map(1.0));
        }
        // The CLI's end points.
        assert_eq!(heat_colour(0.0), Color32::from_rgb(68, 1, 84));
        assert_eq!(heat_colour(1.0), Color32::from_rgb(253, 231, 37));
        assert_eq!(light_colour(0.0), Color32::from_rgb(0, 0, 4));
        assert_eq!(light_colour(1.0), Color32::from_rgb(252, 255, 164));
    }

    #[test]
    fn scale_ignores_the_singular_tail_and_handles_zeros() {
        let mut values = vec![1.0; 990];
        values.extend([1e9; 5]);
        values.extend([0.0; 5]);
        let lin = Scale::fit(&values, false);
        assert_eq!(lin.max, 1.0);
        assert_eq!(lin.unit(0.5), 0.5);
        assert_eq!(lin.unit(0.0), 0.0);
        assert_eq!(lin.unit(f64::NAN), 0.0);
        let log = Scale::fit(&values, true);
        assert!((log.unit(1e-2) - 0.5).abs() < 1e-6);
        assert_eq!(Scale::fit(&[0.0, 0.0], true).max, 1.0);
    }

    #[test]
    fn grid_image_puts_s_upwards() {
        // 2×2 grid: only (s low, t high) is bright.
        let img = grid_image(
            &[0.0, 1.0, 0.0, 0.0],
            2,
            Scale {
                max: 1.0,
                log: false,
                decades: 4.0,
            },
        );
        assert_eq!(img.pixels[2 + 1], heat_colour(1.0), "bottom-right pixel");
        assert_eq!(img.pixels[0], heat_colour(0.0));
        let s = samples_image(&[([0.1, 0.9], 3)], 2);
        assert_eq!(s.pixels[2 + 1], set_color(3));
        assert_eq!(s.pixels[0], Color32::TRANSPARENT);
    }
}
