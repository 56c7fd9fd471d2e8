//! The images of the `(s, t)` panels, each re-made only when the data behind it changes: the
//! exact ζ (at the plot's resolution on screen), the learned ζ̃ and the error of the moment
//! shown, the samples, the cells' overlay and the edges' boundaries (both at the plot's size
//! in screen pixels), and the one colour scale of the three heatmaps, fitted to the reference.
//! Each panel's layers are composited on the CPU into one texture ([`views::composite`]), made
//! again when one of them changes: the GPU draws one image per panel, not one per layer.

use std::sync::Arc;

use egui::{ColorImage, TextureHandle, TextureId, TextureOptions};
use flatland_pictures::colormap::Scale;

use super::Shown;
use crate::colormap::{grid_image, samples_image};
use crate::views::{self, Marks};
use crate::worker::{APPROX_RES, Progress, REFERENCE_RES};

/// An image kept to be composited, and the key of the data it was made from.
struct Layer {
    key: [u64; 4],
    image: ColorImage,
}

/// `slot`'s layer for `key`, made again only when the key changed.
fn layer(slot: &mut Option<Layer>, key: [u64; 4], make: impl FnOnce() -> ColorImage) -> &Layer {
    let kept = match slot.take() {
        Some(l) if l.key == key => l,
        _ => Layer { key, image: make() },
    };
    slot.insert(kept)
}

/// A panel's texture, composited from layers; made again when a layer's key or the side
/// changes.
#[derive(Default)]
struct Composite {
    key: Vec<[u64; 4]>,
    texture: Option<TextureHandle>,
}

impl Composite {
    fn get(
        &mut self,
        ctx: &egui::Context,
        name: &str,
        side: usize,
        layers: &[&Layer],
    ) -> TextureId {
        let key = || std::iter::once([side as u64, 0, 0, 0]).chain(layers.iter().map(|l| l.key));
        if self.texture.is_none() || !self.key.iter().copied().eq(key()) {
            let images: Vec<&ColorImage> = layers.iter().map(|l| &l.image).collect();
            let image = views::composite(side.max(1), &images);
            match &mut self.texture {
                Some(texture) => texture.set(image, TextureOptions::NEAREST),
                None => {
                    self.texture = Some(ctx.load_texture(name, image, TextureOptions::NEAREST));
                }
            }
            self.key = key().collect();
        }
        self.texture
            .as_ref()
            .map(TextureHandle::id)
            .unwrap_or_default()
    }
}

/// Boundaries rastered for one plot size, and where the drawn ones are.
#[derive(Default)]
struct Boundaries {
    layer: Option<Layer>,
    drawn: Vec<f64>,
}

impl Boundaries {
    fn get(&mut self, shown: &Shown, side: usize) -> (&Layer, &[f64]) {
        let key = [shown.world.id, side as u64, 0, 0];
        let mut drawn = None;
        let layer = layer(&mut self.layer, key, || {
            let (image, at) = views::boundaries_image(side, &shown.world.scene);
            drawn = Some(at);
            image
        });
        if let Some(at) = drawn {
            self.drawn = at;
        }
        (layer, &self.drawn)
    }
}

/// Every image of the `(s, t)` panels, kept between frames.
#[derive(Default)]
pub(super) struct Textures {
    kernel: Option<Layer>,
    approx: Option<Layer>,
    error: Option<Layer>,
    samples: Option<Layer>,
    overlay: Option<Layer>,
    big: Boundaries,
    small: Boundaries,
    /// What the GPU draws: one texture per panel.
    kernel_panel: Composite,
    approx_panel: Composite,
    error_panel: Composite,
    /// The colour scale and the world and scale kind it was fitted for.
    scale: Option<(u64, bool, Scale)>,
}

/// The textures of one frame's panels, and the heatmaps' colour scale.
pub(super) struct Heatmaps<'a> {
    pub(super) scale: Scale,
    /// The exact ζ with the boundaries, the samples (if shown) and the cells over it.
    pub(super) kernel: TextureId,
    /// The learned ζ̃ and the error, with the boundaries; `None` before the first moment.
    pub(super) approx: Option<TextureId>,
    pub(super) error: Option<TextureId>,
    /// The parameters of the boundaries drawn on the big plot (its axis ticks).
    pub(super) ticks: &'a [f64],
}

/// What the panels need drawn, in screen pixels, and how.
pub(super) struct Request {
    /// Side of the big plot and of a small one.
    pub(super) sides: [usize; 2],
    pub(super) px_per_point: f32,
    pub(super) log: bool,
    pub(super) show_samples: bool,
    pub(super) show_cells: bool,
    pub(super) show_edges: bool,
}

impl Textures {
    /// The colour scale of `shown`'s world.
    fn scale(&mut self, shown: &Shown, log: bool) -> Scale {
        match self.scale {
            Some((id, l, s)) if id == shown.world.id && l == log => s,
            _ => {
                let s = Scale::fit(shown.world.reference.grid(), log);
                self.scale = Some((shown.world.id, log, s));
                s
            }
        }
    }

    /// The textures of `shown`, made again where their data changed.
    pub(super) fn of<'a>(
        &'a mut self,
        ctx: &egui::Context,
        shown: &Shown,
        req: &Request,
    ) -> Heatmaps<'a> {
        let scale = self.scale(shown, req.log);
        let world = &shown.world;
        // At the plot's resolution once the learner has made it; the reference's until then.
        let (values, res) = match &shown.kernel_grid {
            Some(g) => (&g.values[..], g.res),
            None => (world.reference.grid(), REFERENCE_RES),
        };
        let key = [world.id, u64::from(req.log), res as u64, 0];
        let kernel = layer(&mut self.kernel, key, || grid_image(values, res, scale));
        let (big, ticks) = self.big.get(shown, req.sides[0]);
        let samples = samples(&mut self.samples, shown, req);
        let overlay = overlay(&mut self.overlay, shown, req);
        let layers: Vec<&Layer> = [Some(kernel), Some(big), samples, overlay]
            .into_iter()
            .flatten()
            .collect();
        let kernel = self.kernel_panel.get(ctx, "kernel", req.sides[0], &layers);
        let learned = shown.moment.as_ref().and_then(|m| m.learned.clone());
        let (approx, error) = match learned.filter(|g| g.world == world.id) {
            Some(g) => {
                let key = [world.id, u64::from(req.log), Arc::as_ptr(&g) as u64, 0];
                let approx = layer(&mut self.approx, key, || {
                    grid_image(&g.values, APPROX_RES, scale)
                });
                let error = layer(&mut self.error, key, || {
                    let err: Vec<f64> = g
                        .values
                        .iter()
                        .zip(&world.exact_small)
                        .map(|(x, y)| (x - y).abs())
                        .collect();
                    grid_image(&err, APPROX_RES, scale)
                });
                let (small, _) = self.small.get(shown, req.sides[1]);
                let side = req.sides[1];
                (
                    Some(self.approx_panel.get(ctx, "approx", side, &[approx, small])),
                    Some(self.error_panel.get(ctx, "error", side, &[error, small])),
                )
            }
            None => (None, None),
        };
        Heatmaps {
            scale,
            kernel,
            approx,
            error,
            ticks,
        }
    }
}

/// The samples of the moment shown, if they are to be drawn.
fn samples<'s>(slot: &'s mut Option<Layer>, shown: &Shown, req: &Request) -> Option<&'s Layer> {
    let m = shown.moment.as_ref().filter(|_| req.show_samples)?;
    let samples = &m.status.samples;
    // Samples are a network's: the light-driven learner draws none.
    let Progress::Steps { sets, .. } = m.status.growth.progress else {
        return None;
    };
    let key = [shown.world.id, samples.len() as u64, sets as u64, 0];
    Some(layer(slot, key, || {
        samples_image(samples.as_slice(), 2 * REFERENCE_RES)
    }))
}

/// The cells and edges of the moment shown, at the big plot's size in pixels.
fn overlay<'s>(slot: &'s mut Option<Layer>, shown: &Shown, req: &Request) -> Option<&'s Layer> {
    let m = shown.moment.as_ref()?;
    let growth = &m.status.growth;
    let side = req.sides[0];
    let flags = u64::from(req.show_cells)
        | u64::from(req.show_edges) << 1
        | u64::from(req.px_per_point.to_bits()) << 2;
    let key = [
        Arc::as_ptr(growth) as u64,
        side as u64,
        flags,
        shown.new_from as u64,
    ];
    Some(layer(slot, key, || {
        views::overlay_image(
            side,
            req.px_per_point,
            &Marks {
                cells: &growth.cells,
                edges: &growth.face_edges,
                new_from: shown.new_from,
                show_cells: req.show_cells,
                show_edges: req.show_edges,
            },
        )
    }))
}

#[cfg(test)]
mod tests {
    use egui::Color32;
    use egui::epaint::ImageData;

    use super::*;

    /// The images uploaded to texture `id` since the last call, each as its first pixel and
    /// its size.
    fn uploads(ctx: &egui::Context, id: TextureId) -> Vec<(Color32, [usize; 2])> {
        let mut delta = ctx.tex_manager().write().take_delta();
        let images = delta
            .set
            .get(&id)
            .into_iter()
            .flatten()
            .map(|d| match &d.image {
                ImageData::Color(image) => (image.pixels[0], image.size),
            })
            .collect();
        // The test stands in for the painter, and reading is all it does with them: marked
        // handled, or epaint's debug assertion fails when the delta is dropped.
        delta.clear();
        images
    }

    #[test]
    fn a_panel_is_composited_again_only_when_a_layer_or_its_side_changes() {
        let ctx = egui::Context::default();
        let mut panel = Composite::default();
        let (mut base, mut over) = (None, None);
        let made = std::cell::Cell::new(0);
        let filled = |colour: Color32| {
            made.set(made.get() + 1);
            ColorImage::filled([2, 2], colour)
        };
        let red = layer(&mut base, [1, 0, 0, 0], || filled(Color32::RED));
        let none = layer(&mut over, [7, 0, 0, 0], || filled(Color32::TRANSPARENT));
        let id = panel.get(&ctx, "panel", 4, &[red, none]);
        assert_eq!(uploads(&ctx, id), [(Color32::RED, [4, 4])]);
        assert_eq!(panel.get(&ctx, "panel", 4, &[red, none]), id);
        assert_eq!(uploads(&ctx, id), [], "the same layers: kept");
        let red = layer(&mut base, [1, 0, 0, 0], || filled(Color32::GREEN));
        assert_eq!(made.get(), 2, "the same key: the layer is not made again");
        panel.get(&ctx, "panel", 6, &[red]);
        assert_eq!(
            uploads(&ctx, id),
            [(Color32::RED, [6, 6])],
            "a new side, a layer less"
        );
        let blue = layer(&mut base, [2, 0, 0, 0], || filled(Color32::BLUE));
        panel.get(&ctx, "panel", 6, &[blue]);
        assert_eq!(
            uploads(&ctx, id),
            [(Color32::BLUE, [6, 6])],
            "a layer's new key"
        );
        assert_eq!(made.get(), 3);
    }
}
