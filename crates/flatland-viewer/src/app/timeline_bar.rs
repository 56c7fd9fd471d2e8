//! The timeline bar under the plots: Live, Replay at a chosen speed, a slider through every
//! moment kept, and what the moment shown is (training time, step, cells).

use egui::{RichText, Slider};

use super::ViewerApp;
use crate::worker::Progress;

/// The replay speeds offered, times the speed the run was recorded at.
const SPEEDS: [f32; 6] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0];

impl ViewerApp {
    pub(super) fn timeline_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            self.replay_buttons(ui);
            ui.separator();
            self.timeline_slider(ui);
        });
    }

    /// Live, Replay or Stop replay, and the replay speed.
    fn replay_buttons(&mut self, ui: &mut egui::Ui) {
        if ui
            .selectable_label(self.is_live(), "Live")
            .on_hover_text("follow the running learner")
            .clicked()
        {
            self.go_live();
        }
        if self.replaying() {
            if ui.button("Stop replay").clicked() {
                self.stop_replay();
            }
        } else if ui
            .button("Replay")
            .on_hover_text(
                "play the run back from the moment shown (from the start when live); the \
                 learner keeps learning meanwhile",
            )
            .clicked()
        {
            self.replay(self.cursor.speed);
        }
        for speed in SPEEDS {
            let selected = self.cursor.speed == speed;
            let text = match speed {
                0.25 => "×¼".to_owned(),
                0.5 => "×½".to_owned(),
                s => format!("×{s}"),
            };
            if ui
                .selectable_label(selected, text)
                .on_hover_text("replay speed, against the speed it was recorded at")
                .clicked()
            {
                self.cursor.speed = speed;
                if self.replaying() {
                    self.cursor.replaying = Some(speed);
                }
            }
        }
    }

    /// The slider over the kept moments and the description of the one shown.
    fn timeline_slider(&mut self, ui: &mut egui::Ui) {
        let n = self.timeline.len();
        let Some(mut position) = self.shown_position() else {
            ui.label(RichText::new("no moments yet").weak());
            return;
        };
        ui.spacing_mut().slider_width = (ui.available_width() - 380.0).max(120.0);
        let slider = Slider::new(&mut position, 0..=n - 1)
            .show_value(false)
            .text("timeline");
        let response = ui
            .add(slider)
            .on_hover_text("every moment the learner published; drag to see the run then");
        if response.changed() {
            if position + 1 == n {
                self.go_live();
            } else {
                self.scrub_to(position);
            }
        }
        if let Some(m) = self.shown() {
            // The light-driven learner's steps are rounds, its cells probes.
            let (step, cells) = match m.status.growth.progress {
                Progress::Rounds { .. } => ("round", "probes"),
                Progress::Steps { .. } => ("step", "cells"),
            };
            let text = format!(
                "{} {}/{} · {:.1} s · {step} {} · {} {cells}",
                if self.is_live() { "live" } else { "moment" },
                position + 1,
                n,
                m.at().as_secs_f64(),
                m.steps(),
                m.cells(),
            );
            ui.label(RichText::new(text).monospace().size(11.0));
        }
    }
}
