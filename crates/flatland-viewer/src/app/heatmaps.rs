//! The textures of the `(s, t)` panels, each re-made only when the data behind it changes:
//! the exact ζ (at the plot's resolution on screen), the learned ζ̃ and the error of the moment
//! shown, the samples, the cells' overlay and the edges' boundaries (both at the plot's size
//! in screen pixels), and the one colour scale of the three heatmaps, fitted to the reference.

use std::sync::Arc;

use egui::{ColorImage, TextureHandle, TextureId, TextureOptions};
use flatland_lab::colormap::Scale;

use super::Shown;
use crate::colormap::{grid_image, samples_image};
use crate::views::{self, Marks};
use crate::worker::{APPROX_RES, REFERENCE_RES};

/// A texture and the key of the data it was made from: re-uploaded only when the key changes.
struct Cached {
    key: [u64; 4],
    texture: TextureHandle,
}

/// Makes (or keeps) the texture in `slot` for `key`.
fn cached_texture(
    ctx: &egui::Context,
    slot: &mut Option<Cached>,
    name: &str,
    key: [u64; 4],
    make: impl FnOnce() -> ColorImage,
) -> TextureId {
    match slot {
        Some(c) if c.key == key => {}
        Some(c) => {
            c.texture.set(make(), TextureOptions::NEAREST);
            c.key = key;
        }
        None => {
            let texture = ctx.load_texture(name, make(), TextureOptions::NEAREST);
            *slot = Some(Cached { key, texture });
        }
    }
    slot.as_ref().map(|c| c.texture.id()).unwrap_or_default()
}

/// Boundaries rastered for one plot size, and where the drawn ones are.
#[derive(Default)]
struct Boundaries {
    texture: Option<Cached>,
    drawn: Vec<f64>,
}

impl Boundaries {
    fn get(&mut self, ctx: &egui::Context, shown: &Shown, side: usize) -> (TextureId, &[f64]) {
        let key = [shown.world.id, side as u64, 0, 0];
        let mut drawn = None;
        let id = cached_texture(ctx, &mut self.texture, "boundaries", key, || {
            let (image, at) = views::boundaries_image(side, &shown.world.scene);
            drawn = Some(at);
            image
        });
        if let Some(at) = drawn {
            self.drawn = at;
        }
        (id, &self.drawn)
    }
}

/// Every texture of the `(s, t)` panels, kept between frames.
#[derive(Default)]
pub(super) struct Textures {
    kernel: Option<Cached>,
    approx: Option<Cached>,
    error: Option<Cached>,
    samples: Option<Cached>,
    overlay: Option<Cached>,
    big: Boundaries,
    small: Boundaries,
    /// The colour scale and the world and scale kind it was fitted for.
    scale: Option<(u64, bool, Scale)>,
}

/// The textures of one frame's panels, and the heatmaps' colour scale.
pub(super) struct Heatmaps<'a> {
    pub(super) scale: Scale,
    pub(super) kernel: TextureId,
    pub(super) approx: Option<TextureId>,
    pub(super) error: Option<TextureId>,
    pub(super) samples: Option<TextureId>,
    pub(super) overlay: Option<TextureId>,
    /// Boundaries for the big plot and where they are; for the small plots.
    pub(super) boundaries_big: (TextureId, &'a [f64]),
    pub(super) boundaries_small: TextureId,
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
        let kernel = cached_texture(ctx, &mut self.kernel, "kernel", key, || {
            grid_image(values, res, scale)
        });
        let learned = shown.moment.as_ref().and_then(|m| m.learned.clone());
        let (approx, error) = match learned.filter(|g| g.world == world.id) {
            Some(g) => {
                let key = [world.id, u64::from(req.log), Arc::as_ptr(&g) as u64, 0];
                let at = cached_texture(ctx, &mut self.approx, "approx", key, || {
                    grid_image(&g.values, APPROX_RES, scale)
                });
                let et = cached_texture(ctx, &mut self.error, "error", key, || {
                    let err: Vec<f64> = g
                        .values
                        .iter()
                        .zip(&world.exact_small)
                        .map(|(x, y)| (x - y).abs())
                        .collect();
                    grid_image(&err, APPROX_RES, scale)
                });
                (Some(at), Some(et))
            }
            None => (None, None),
        };
        let samples = self.samples(ctx, shown, req);
        let overlay = self.overlay(ctx, shown, req);
        let boundaries_small = self.small.get(ctx, shown, req.sides[1]).0;
        Heatmaps {
            scale,
            kernel,
            approx,
            error,
            samples,
            overlay,
            boundaries_big: self.big.get(ctx, shown, req.sides[0]),
            boundaries_small,
        }
    }

    /// The samples of the moment shown, if they are to be drawn.
    fn samples(&mut self, ctx: &egui::Context, shown: &Shown, req: &Request) -> Option<TextureId> {
        let m = shown.moment.as_ref().filter(|_| req.show_samples)?;
        let samples = &m.status.samples;
        let key = [
            shown.world.id,
            samples.len() as u64,
            m.status.growth.sets as u64,
            0,
        ];
        Some(cached_texture(
            ctx,
            &mut self.samples,
            "samples",
            key,
            || samples_image(samples.as_slice(), 2 * REFERENCE_RES),
        ))
    }

    /// The cells and edges of the moment shown, at the big plot's size in pixels.
    fn overlay(&mut self, ctx: &egui::Context, shown: &Shown, req: &Request) -> Option<TextureId> {
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
        Some(cached_texture(
            ctx,
            &mut self.overlay,
            "overlay",
            key,
            || {
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
            },
        ))
    }
}
