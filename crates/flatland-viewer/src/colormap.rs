//! Value → colour on screen: the project's one colour map and scale rule
//! ([`flatland_pictures::colormap`], the same as the CLI's pictures) as egui colours, and the
//! images built from grids and sample points. Pure functions, so they are cheap to test and run
//! only when the data they show has changed.

use egui::{Color32, ColorImage};
use flatland_pictures::colormap::{Scale, inferno};

/// The colour of `x ∈ [0, 1]` (clamped; NaN is 0): the heatmaps' and the lit scene's.
#[must_use]
pub fn colour(x: f64) -> Color32 {
    let [r, g, b] = inferno(x);
    Color32::from_rgb(r, g, b)
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
                .map(|&v| colour(scale.unit(v))),
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
    fn colours_are_the_projects_colour_map() {
        assert_eq!(colour(0.0), Color32::from_rgb(0, 0, 4));
        assert_eq!(colour(1.0), Color32::from_rgb(252, 255, 164));
        assert_eq!(colour(f64::NAN), colour(0.0));
        assert_eq!(colour(0.37), {
            let [r, g, b] = inferno(0.37);
            Color32::from_rgb(r, g, b)
        });
    }

    #[test]
    fn grid_image_puts_s_upwards() {
        // 2×2 grid: only (s low, t high) is bright.
        let img = grid_image(
            &[0.0, 1.0, 0.0, 0.0],
            2,
            Scale {
                top: 1.0,
                log: false,
            },
        );
        assert_eq!(img.pixels[2 + 1], colour(1.0), "bottom-right pixel");
        assert_eq!(img.pixels[0], colour(0.0));
        let s = samples_image(&[([0.1, 0.9], 3)], 2);
        assert_eq!(s.pixels[2 + 1], set_color(3));
        assert_eq!(s.pixels[0], Color32::TRANSPARENT);
    }
}
