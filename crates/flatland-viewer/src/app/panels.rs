//! The central area at the moment shown: the exact ζ with the cells over it, the learned ζ and
//! the error, the scene lit by its moving lights, the scene lit by the learned kernel, the
//! curves.

use std::sync::Arc;

use egui::{Rect, UiBuilder};

use super::heatmaps::Request;
use super::layout::Layout;
use super::readout::{Learned, readout_text};
use super::top_bar::error_text;
use super::{Shown, ViewerApp};
use crate::relit::{M2_RES, RelitState, TransportPhase};
use crate::views::{self, LitPaint, NEW_FOR, PlotFrame};
use crate::worker::{Command, Lit, Progress};

/// The kernel plot's exact ζ is computed at its width in pixels rounded up to a multiple of
/// this (so a window resized by a few pixels does not ask again).
const PLOT_RES_STEP: usize = 32;

impl ViewerApp {
    /// The world and moment to draw: the newest when live (the world may be newer than any
    /// moment: a scene just edited), else the moment scrubbed to and its own world.
    fn shown_now(&self) -> Option<Shown> {
        let live = self.is_live();
        let moment = self.shown().cloned();
        let world = match (&moment, live) {
            (Some(m), false) => Arc::clone(&m.world),
            _ => Arc::clone(self.world.as_ref()?),
        };
        let moment = moment.filter(|m| m.world.id == world.id);
        // The light-driven learner's new probes are its newest round's.
        let new_from = moment
            .as_ref()
            .map_or(0, |m| match m.status.growth.progress {
                Progress::Rounds { newest_from, .. } => newest_from,
                Progress::Steps { .. } => self.timeline.cells_at(m.at().saturating_sub(NEW_FOR)),
            });
        let kernel_grid = self.kernel_grid.clone().filter(|g| g.world == world.id);
        Some(Shown {
            world,
            moment,
            live,
            new_from,
            kernel_grid,
        })
    }

    /// The lit scene of the moment shown, when it belongs to the scene drawn (not while an
    /// edited scene's reference is being made).
    fn shown_lit<'a>(&self, shown: &'a Shown) -> Option<&'a Lit> {
        let lit = shown.moment.as_ref()?.lit.as_deref()?;
        let current = !shown.live || self.scene == shown.world.scene;
        (lit.setup.world == shown.world.id && current).then_some(lit)
    }

    pub(super) fn main_area(&mut self, ui: &mut egui::Ui) {
        let full = ui.available_rect_before_wrap();
        let Some(shown) = self.shown_now() else {
            ui.centered_and_justified(|ui| {
                ui.label(self.busy.unwrap_or("waiting for the learner…"))
            });
            return;
        };
        let layout = Layout::of(full);
        self.kernel_panels(ui, &layout, &shown);
        self.scene_panels(ui, &layout, &shown);
        let history = shown
            .moment
            .as_ref()
            .map_or(&[][..], |m| m.status.history.as_slice());
        let lit = self.shown_lit(&shown);
        ui.scope_builder(UiBuilder::new().max_rect(layout.curves), |ui| {
            views::curves(ui, history, lit);
        });
    }

    /// The exact ζ with the cells over it, the learned ζ and the error; the readout of the
    /// hovered `(s, t)`.
    fn kernel_panels(&mut self, ui: &mut egui::Ui, layout: &Layout, shown: &Shown) {
        let ctx = ui.ctx().clone();
        let ppp = ctx.pixels_per_point();
        let mut kernel_frame = PlotFrame::new(layout.kernel, true);
        let kernel_plot = kernel_frame.plot;
        let (approx_frame, error_frame) = (
            PlotFrame::new(layout.approx, false),
            PlotFrame::new(layout.error, false),
        );
        let pixels = |f: &PlotFrame| ((f.plot.width() * ppp).round() as usize).clamp(16, 2048);
        let request = Request {
            sides: [pixels(&kernel_frame), pixels(&approx_frame)],
            px_per_point: ppp,
            log: self.settings.log_scale,
            show_samples: self.settings.show_samples,
            show_cells: self.settings.show_cells,
            show_edges: self.settings.show_edges,
        };
        let res = request.sides[0].div_ceil(PLOT_RES_STEP) * PLOT_RES_STEP;
        if res != self.plot_res {
            self.plot_res = res;
            self.worker.send(Command::PlotResolution(res));
        }
        let m2 = self.m2_texture(&ctx, shown.world.id);
        let textures = self.textures.of(&ctx, shown, &request);
        kernel_frame.scale = Some(textures.scale);
        if let Some((_, scale)) = m2 {
            kernel_frame.scale = Some(scale);
            kernel_frame.quantity = "M₂";
        }
        let progress = shown.moment.as_ref().map(|m| m.status.growth.progress);
        let rounds = matches!(progress, Some(Progress::Rounds { .. }));
        let big = views::Overlay {
            ticks: textures.ticks,
            probes: rounds,
        };
        let small = views::Overlay::default();
        let learned_title = match shown.moment.as_ref().map(|m| m.status.params.target) {
            _ if rounds => "learned ζ (the probes' rows)",
            Some(kernel_fit::Target::Visibility) => "learned ζ (unoccluded ζ × V)",
            _ => "learned ζ (SGCS)",
        };
        let panels = [
            (
                kernel_frame,
                match (m2.is_some(), rounds) {
                    (true, _) => "M₂(s, t) learned by the transport",
                    (false, true) => "ζ(s, t) exact, with the probes",
                    (false, false) => "ζ(s, t) exact, with the cells",
                },
                Some(m2.map_or(textures.kernel, |(texture, _)| texture)),
                big,
            ),
            (approx_frame, learned_title, textures.approx, small),
            (error_frame, "|learned − exact|", textures.error, small),
        ];
        let mut hovered = None;
        for (frame, title, texture, overlay) in &panels {
            let st = views::kernel_plot(
                ui,
                frame,
                title,
                *texture,
                &shown.world.scene,
                overlay,
                &self.hover,
            );
            hovered = hovered.or(st);
        }
        self.transport_blocks(ui, kernel_plot, shown.world.id);
        self.hover.st = hovered;
        if let Some([s, t]) = self.hover.st
            && let Some(pointer) = ui.input(|i| i.pointer.hover_pos())
        {
            let text = readout_text(&shown.world.kernel, self.learned_source(shown), s, t);
            views::readout_box(&ctx, pointer, &text);
        }
    }

    /// The learned `M₂(s, t)` of the moving light's transport as a texture and its colour
    /// scale (log, the one rule), when it is asked for in place of ζ and built for `world`.
    fn m2_texture(
        &mut self,
        ctx: &egui::Context,
        world: u64,
    ) -> Option<(egui::TextureId, flatland_pictures::colormap::Scale)> {
        if !self.settings.show_m2 {
            return None;
        }
        let frame = self.lamps.frame.as_ref().filter(|f| f.world == world)?;
        let Some(TransportPhase::Ready { m2, .. }) = frame.transport.as_ref().map(|t| &t.phase)
        else {
            return None;
        };
        // Made by the build's thread after the transport answers: none to show until then.
        let values = m2.get()?;
        let kept = self
            .lamps
            .m2
            .as_ref()
            .filter(|(w, grid, ..)| *w == world && Arc::ptr_eq(grid, m2));
        if kept.is_none() {
            let scale = flatland_pictures::colormap::Scale::fit(values, true);
            let image = crate::colormap::grid_image(values, M2_RES, scale);
            let texture = ctx.load_texture("learned M2", image, egui::TextureOptions::NEAREST);
            self.lamps.m2 = Some((world, Arc::clone(m2), texture, scale));
        }
        self.lamps
            .m2
            .as_ref()
            .map(|(_, _, texture, scale)| (texture.id(), *scale))
    }

    /// The learned transport's blocks over the kernel plot, as they are built (when shown, and
    /// when the moving light's scene is the plot's).
    fn transport_blocks(&mut self, ui: &egui::Ui, plot: Rect, world: u64) {
        let Some(frame) = self.lamps.frame.clone().filter(|f| f.world == world) else {
            return;
        };
        let Some(status) = frame
            .transport
            .as_ref()
            .filter(|_| self.settings.show_blocks)
        else {
            return;
        };
        let painter = ui.painter_at(plot);
        self.lamps.blocks.paint(
            &painter,
            plot,
            (world, &frame.mesh),
            &status.blocks,
            status.clusters,
        );
    }

    /// The learned value under the pointer: the live model, or a past moment's grid.
    fn learned_source<'a>(&'a self, shown: &'a Shown) -> Learned<'a> {
        if shown.live
            && let Some(a) = self
                .approx
                .as_ref()
                .filter(|a| a.grid.world == shown.world.id)
            && let Some(model) = &a.model
        {
            return Learned::Model(model);
        }
        match shown.moment.as_ref().and_then(|m| m.learned.as_deref()) {
            Some(grid) => Learned::Grid(grid),
            None => Learned::Unknown,
        }
    }

    /// The scene (lit by the learned B when there is one; hovered ray, hovered s, dragged end
    /// points when live) and the relit scene with its moving lights.
    fn scene_panels(&mut self, ui: &mut egui::Ui, layout: &Layout, shown: &Shown) {
        let lit = self.shown_lit(shown);
        let tone = self.tone();
        let learned_paint = lit.map(|l| LitPaint {
            mesh: l.setup.mesh(),
            b: &l.solve.b,
            top: l.setup.top / tone.0,
            log: tone.1,
        });
        let scene_title = match lit {
            Some(l) => format!(
                "lit by the learned kernel: B − E rel. L2 {} ({} el., {:.0} ms)",
                error_text(l.solve.errors.rel_l2_reflected, true),
                l.setup.mesh().len(),
                1e3 * l.solve.solve_s
            ),
            None => "scene".to_owned(),
        };
        let scene = if shown.live {
            self.scene.clone()
        } else {
            shown.world.scene.clone()
        };
        let scene_out = views::scene_view(
            ui,
            &views::SceneFrame {
                rect: layout.scene,
                title: &scene_title,
                world: &shown.world,
                lit: learned_paint.as_ref(),
                editable: shown.live,
            },
            &scene,
            &self.hover,
            &mut self.drag,
            &mut self.scene_edges,
        );
        self.hover.scene_s = scene_out.hovered_s;
        if let Some((from, to)) = scene_out.moved {
            self.move_point(from, to);
        }
        self.relit_panel(ui, layout.relit);
    }

    /// The exposure's factor (2^stops) and whether the tone scale is logarithmic.
    fn tone(&self) -> (f64, bool) {
        (
            2f64.powf(f64::from(self.settings.exposure)),
            self.settings.tone_log,
        )
    }

    /// The scene lit by its moving lights (the newest B the relighting thread published), the
    /// lights' marks, and what the user does to them.
    fn relit_panel(&mut self, ui: &mut egui::Ui, rect: Rect) {
        let Some(world) = self.lamps.world.clone() else {
            views::placeholder(ui, rect, "moving light", "waiting for the scene…");
            return;
        };
        let tone = self.tone();
        let frame = self.lamps.frame.clone();
        let paint = frame
            .as_deref()
            .zip(self.lamps.top)
            .map(|(f, top)| LitPaint {
                mesh: &f.mesh,
                b: &f.b,
                top: top / tone.0,
                log: tone.1,
            });
        let title = match (&frame, &self.lamps.state) {
            (Some(f), _) => format!(
                "{}: {:.2} ms per move, {}",
                super::lamps::answer_name(f.answer),
                f.median_ms,
                super::lamps::relit_quality(f),
            ),
            (None, RelitState::Failed(why)) => format!("moving light: {why}"),
            (None, _) => "moving light: building the exact operator…".to_owned(),
        };
        let view = views::RelitFrameView {
            rect,
            title: &title,
            scene: &world.scene,
            lit: paint.as_ref(),
            lights: &self.lamps.lights,
            note: &frame.as_deref().map_or(String::new(), |f| {
                format!(
                    "{} moves · {} el. · {}",
                    f.moves.min(crate::relit::TIMED_MOVES as u64),
                    f.mesh.len(),
                    super::lamps::transport_note(f)
                )
            }),
        };
        let (out, marks) =
            views::relit_view(ui, &view, &mut self.lamps.grabbed, &mut self.lamps.texture);
        self.lamps.marks = marks;
        self.apply_lamps(&out);
    }
}
