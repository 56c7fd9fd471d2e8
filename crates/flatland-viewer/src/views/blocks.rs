//! The learned transport's blocks over an `(s, t)` plot: each block of `M₂` joins a cluster of
//! senders (its elements' parameter intervals, `s`, upwards) to the receivers its light
//! reaches (`t`, to the right); filled in the colour of its rank, over the kernel, as the
//! build makes them — the paper's view of cells growing over the kernel they learn, for the
//! kernel where the cells now pay (`M₂`, the later bounces).

use std::time::{Duration, Instant};

use egui::{Color32, ColorImage, FontId, Painter, Rect, TextureHandle, TextureOptions};
use flatland_solve::Mesh;
use flatland_transport::BlockFootprint;

use super::widgets::uv;
use crate::relit::BlockLog;

/// Most pixels a side of the blocks' image has (more would not show).
const MAX_SIDE: usize = 1024;
/// How often, at most, the image is drawn again while blocks keep coming.
const REDRAW: Duration = Duration::from_millis(250);
/// How much of the kernel shows through a block.
const BLOCK_ALPHA: f32 = 0.35;

/// The colour of a block of `rank`, the largest rank being `top`: blue (rank 1) through green
/// to red (the largest); a block whose light was all cut (rank 0) is grey.
#[must_use]
pub fn rank_colour(rank: usize, top: usize) -> Color32 {
    if rank == 0 {
        return Color32::from_gray(128).gamma_multiply(BLOCK_ALPHA);
    }
    // Ranks spread over a few decades: their log places them.
    let x = ((rank as f32).ln() / (top.max(2) as f32).ln()).clamp(0.0, 1.0);
    let hsva = egui::ecolor::Hsva::new(0.66 * (1.0 - x), 0.85, 1.0, 1.0);
    Color32::from(hsva).gamma_multiply(BLOCK_ALPHA)
}

/// The blocks as an image of `side × side` pixels (row 0 at `s = 1`, column 0 at `t = 0`),
/// transparent where no block lies. Blocks of different clusters never overlap (an element
/// sends from one cluster only).
#[must_use]
pub fn blocks_image(blocks: &[BlockFootprint], mesh: &Mesh, side: usize) -> ColorImage {
    let mut image = ColorImage::filled([side, side], Color32::TRANSPARENT);
    let top = blocks.iter().map(|b| b.rank).max().unwrap_or(1);
    let elements = mesh.elements();
    // A run's parameter interval as pixels, at least one wide.
    let pixels = |run: &std::ops::Range<u32>| {
        let (first, last) = (run.start as usize, run.end as usize - 1);
        let (lo, hi) = (elements[first].s[0], elements[last].s[1]);
        let a = ((lo * side as f64).floor() as usize).min(side - 1);
        let b = ((hi * side as f64).ceil() as usize).clamp(a + 1, side);
        (a, b)
    };
    for block in blocks {
        let colour = rank_colour(block.rank, top);
        for senders in &block.senders {
            let (s0, s1) = pixels(senders);
            for receivers in &block.receivers {
                let (t0, t1) = pixels(receivers);
                // s upwards: row `side − 1 − k` holds parameter pixel k.
                for k in s0..s1 {
                    let row = (side - 1 - k) * side;
                    image.pixels[row + t0..row + t1].fill(colour);
                }
            }
        }
    }
    image
}

/// The blocks' image of one plot, drawn again when more blocks came (at most every
/// [`REDRAW`]) or the scene or size changed.
#[derive(Default)]
pub struct BlocksTexture {
    cached: Option<(BlocksKey, TextureHandle, Instant)>,
}

/// What the image shows: the world, the blocks drawn, the pixels per side.
#[derive(Clone, Copy, PartialEq, Eq)]
struct BlocksKey {
    world: u64,
    blocks: usize,
    side: usize,
}

impl BlocksTexture {
    /// Paints the blocks `log` of world `world` (on `mesh`) over `plot`, with a line saying
    /// how many of `clusters` are built and what the colours mean.
    pub fn paint(
        &mut self,
        painter: &Painter,
        plot: Rect,
        (world, mesh): (u64, &Mesh),
        log: &BlockLog,
        clusters: usize,
    ) {
        let count = log.len();
        let ppp = painter.ctx().pixels_per_point();
        let side = ((plot.width() * ppp).round() as usize).clamp(16, MAX_SIDE);
        let key = BlocksKey {
            world,
            blocks: count,
            side,
        };
        let stale = match &self.cached {
            None => true,
            Some((k, _, at)) => {
                k.world != world
                    || k.side != side
                    || (k.blocks != count && (count == clusters || at.elapsed() >= REDRAW))
            }
        };
        if stale {
            let list = log.blocks();
            let image = blocks_image(&list, mesh, side);
            let key = BlocksKey {
                blocks: list.len(),
                ..key
            };
            match &mut self.cached {
                Some((k, texture, at)) => {
                    texture.set(image, TextureOptions::NEAREST);
                    (*k, *at) = (key, Instant::now());
                }
                None => {
                    let texture = painter.ctx().load_texture(
                        "transport blocks",
                        image,
                        TextureOptions::NEAREST,
                    );
                    self.cached = Some((key, texture, Instant::now()));
                }
            }
        }
        let Some((shown, texture, _)) = &self.cached else {
            return;
        };
        painter.image(texture.id(), plot, uv(), Color32::WHITE);
        let text = format!(
            "M₂ blocks {}/{clusters}, rank blue (low) to red",
            shown.blocks
        );
        let at = plot.left_top() + egui::vec2(4.0, 3.0);
        let font = FontId::proportional(11.0);
        let galley = painter.layout_no_wrap(text, font, Color32::WHITE);
        let back = Rect::from_min_size(at, galley.size()).expand(2.0);
        painter.rect_filled(back, 2.0, Color32::from_black_alpha(170));
        painter.galley(at, galley, Color32::WHITE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::Kernel;

    #[test]
    fn a_block_fills_its_senders_rows_and_its_receivers_columns() {
        let kernel = Kernel::new(flatland_geom::bundled::scene("floorplan").unwrap());
        let mesh = Mesh::new(&kernel, 400).unwrap();
        let n = mesh.len() as u32;
        // The first tenth of the elements send to the last tenth, at rank 3.
        let block = BlockFootprint {
            cluster: 0,
            senders: std::iter::once(0..n / 10).collect(),
            receivers: std::iter::once(n - n / 10..n).collect(),
            rank: 3,
        };
        let side = 100;
        let image = blocks_image(&[block], &mesh, side);
        let pixel = |s: f64, t: f64| {
            let row = side - 1 - (s * side as f64) as usize;
            image.pixels[row * side + (t * side as f64) as usize]
        };
        let s_in = mesh.elements()[(n / 20) as usize].s_mid;
        let t_in = mesh.elements()[(n - n / 20) as usize].s_mid;
        assert_eq!(pixel(s_in, t_in), rank_colour(3, 3), "inside");
        assert_eq!(
            pixel(t_in, s_in),
            Color32::TRANSPARENT,
            "the transpose is not"
        );
        assert_eq!(
            pixel(0.5, t_in),
            Color32::TRANSPARENT,
            "other senders are not"
        );
        assert!(image.pixels.contains(&Color32::TRANSPARENT));
    }

    #[test]
    fn ranks_run_from_blue_to_red_and_cut_blocks_are_grey() {
        let (low, high) = (rank_colour(1, 20), rank_colour(20, 20));
        assert!(low.b() > low.r() && high.r() > high.b(), "{low:?} {high:?}");
        let cut = rank_colour(0, 20);
        assert_eq!(cut.r(), cut.b());
    }
}
