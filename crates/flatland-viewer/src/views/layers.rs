//! The layers of an `(s, t)` panel (heatmap, boundaries, samples, cells) composited into one
//! image on the CPU. Drawn as separate textures, every layer costs a software rasterizer a
//! blended fill of the whole plot on every frame; they change only when their data does.
//!
//! Measured under Xvfb with Mesa's llvmpipe on 2 cores (`floorplan-1000`, the visibility
//! network, paused, the pointer sweeping the kernel plot): the rasterizer's CPU per frame went
//! from 18.7 to 14.4 ms, and the UI thread's from 4.9 to 4.1 ms (the layers change far less
//! often than frames are drawn).

use egui::{Color32, ColorImage};

use super::raster::blend;

/// `layers` drawn one over the other into a `side × side` image, the first at the bottom, on
/// black: premultiplied "over", as egui's renderer blends, each layer stretched over the image
/// and sampled at the nearest pixel, as a NEAREST texture stretched over the plot is.
#[must_use]
pub fn composite(side: usize, layers: &[&ColorImage]) -> ColorImage {
    let mut out = ColorImage::filled([side, side], Color32::BLACK);
    for layer in layers {
        let [w, h] = layer.size;
        if w == 0 || h == 0 {
            continue;
        }
        let cols: Vec<usize> = (0..side).map(|x| nearest(x, side, w)).collect();
        for y in 0..side {
            let row = &layer.pixels[nearest(y, side, h) * w..][..w];
            let dst = &mut out.pixels[y * side..][..side];
            for (d, &c) in dst.iter_mut().zip(&cols) {
                let src = row[c];
                if src.a() == 255 {
                    *d = src;
                } else if src != Color32::TRANSPARENT {
                    *d = blend(*d, src);
                }
            }
        }
    }
    out
}

/// The pixel of a layer `m` pixels wide under the centre of pixel `i` of `n`.
fn nearest(i: usize, n: usize, m: usize) -> usize {
    ((2 * i + 1) * m / (2 * n)).min(m - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_are_stretched_to_the_side_and_blended_over_the_ones_below() {
        // A 2×2 opaque base: red, green / blue, white.
        let base = ColorImage::new(
            [2, 2],
            vec![Color32::RED, Color32::GREEN, Color32::BLUE, Color32::WHITE],
        );
        // A 4×4 layer, transparent but for a half-covered black pixel at (1, 0).
        let mut over = ColorImage::filled([4, 4], Color32::TRANSPARENT);
        let half = Color32::from_rgba_premultiplied(0, 0, 0, 128);
        over.pixels[1] = half;
        let out = composite(4, &[&base, &over]);
        assert_eq!(out.size, [4, 4]);
        // Each base pixel covers 2×2 output pixels.
        assert_eq!(out.pixels[4 * 3], Color32::BLUE, "bottom left");
        assert_eq!(out.pixels[4 * 3 + 3], Color32::WHITE, "bottom right");
        assert_eq!(out.pixels[4 + 3], Color32::GREEN, "top right (second row)");
        // The half-covered pixel darkens red by half; its neighbours stay red.
        assert_eq!(out.pixels[1], blend(Color32::RED, half));
        assert_eq!(out.pixels[1].r(), 127);
        assert_eq!((out.pixels[0], out.pixels[5]), (Color32::RED, Color32::RED));
    }

    #[test]
    fn nearest_picks_the_pixel_under_each_centre() {
        // Upscaling 3 → 7 and downscaling 7 → 3 both stay in range and keep the order.
        let up: Vec<usize> = (0..7).map(|i| nearest(i, 7, 3)).collect();
        assert_eq!(up, [0, 0, 1, 1, 1, 2, 2]);
        let down: Vec<usize> = (0..3).map(|i| nearest(i, 3, 7)).collect();
        assert_eq!(down, [1, 3, 5]);
        assert_eq!(nearest(5, 6, 6), 5, "same size: identity");
    }

    #[test]
    fn nothing_over_an_empty_list_is_black() {
        let out = composite(3, &[]);
        assert!(out.pixels.iter().all(|&p| p == Color32::BLACK));
        let empty = ColorImage::filled([0, 0], Color32::WHITE);
        assert_eq!(composite(2, &[&empty]).pixels, vec![Color32::BLACK; 4]);
    }
}
