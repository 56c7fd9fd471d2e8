//! The top bar: play, step, reset, the numbers of the moment shown, the frame rate, and the
//! message line under it (busy work, errors, notes, why the fit stopped).

use egui::{Color32, DragValue, RichText};
use flatland_light::LightStop;
use flatland_solve::Errors;
use kernel_fit::{FitParams, StopReason};

use super::ViewerApp;
use crate::learner::Learner;
use crate::settings::with_preset;
use crate::worker::{Lit, Progress, Status};

impl ViewerApp {
    /// The top bar's numbers: the learner, its progress, the held-out error of ζ and (with the
    /// lit scene) of the solved `B − E`, its speed.
    fn stats_text(&self, st: &Status, lit: Option<&Lit>, heldout_defined: bool) -> String {
        let g = &st.growth;
        let (rays, sets) = match g.progress {
            Progress::Steps { rays, sets } => (rays, sets),
            Progress::Rounds {
                estimated_error, ..
            } => return light_stats(g.steps, estimated_error, g.cells.len(), lit),
        };
        let mut parts = vec![
            learner_name(self.fit_learner, &st.params),
            format!("steps {}", g.steps),
            format!("rays {rays}"),
            format!("cells {}/{}", g.cells.len(), self.sent_params.target_cells),
        ];
        if let Some(faces) = st.occupied_faces {
            parts.push(format!("in {faces} faces"));
        }
        parts.push(format!("samples {} in {sets} sets", st.samples.len()));
        let err = st.history.as_slice().last().map_or("–".into(), |h| {
            error_text(h.rel_l2_heldout, heldout_defined)
        });
        parts.push(format!("ζ held out {err}"));
        if let Some(l) = lit {
            let err = error_text(l.solve.errors.rel_l2_reflected, true);
            parts.push(format!("solved B−E {err}"));
        }
        if st.steps_per_s > 0.0 && self.is_live() {
            parts.push(format!("{:.0} steps/s", st.steps_per_s));
        }
        parts.join("  ")
    }

    pub(super) fn top_bar(&mut self, ui: &mut egui::Ui) {
        let defined = self.world.as_ref().map_or([true; 2], |w| w.defined);
        ui.horizontal(|ui| {
            self.run_buttons(ui);
            ui.separator();
            let stats = self
                .shown()
                .map(|m| self.stats_text(&m.status, m.lit.as_deref(), defined[1]))
                .unwrap_or_default();
            ui.label(RichText::new(stats).monospace().size(11.0));
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                ui.label(RichText::new(format!("{:.0} fps", self.fps.now)).weak());
            });
        });
        let (text, is_error) = self.message_line(defined).unwrap_or_default();
        // The line is always there (empty if nothing to say) so the layout never jumps under
        // the pointer, e.g. while an end point is being dragged.
        ui.horizontal(|ui| {
            ui.set_min_height(ui.spacing().interact_size.y);
            let color = if is_error {
                Color32::from_rgb(255, 110, 90)
            } else {
                ui.visuals().weak_text_color()
            };
            ui.label(RichText::new(text).color(color));
            if is_error && ui.small_button("dismiss").clicked() {
                self.message = None;
            }
        });
    }

    /// Play or Pause, Step × step size, Reset.
    fn run_buttons(&mut self, ui: &mut egui::Ui) {
        if self.running() {
            if ui.button("Pause").clicked() {
                self.pause();
            }
        } else if ui.button("Play").clicked() {
            self.play();
        }
        if ui
            .button("Step")
            .on_hover_text("train `step size` steps, then pause")
            .clicked()
        {
            self.step();
        }
        let times = ui.label("×");
        ui.add(DragValue::new(&mut self.settings.step_size).range(1..=1_000_000))
            .labelled_by(times.id)
            .on_hover_text("step size: steps per press of Step");
        if ui
            .button("Reset")
            .on_hover_text("a fresh fit (seed, |S₀|, subdivision apply)")
            .clicked()
        {
            self.reset();
        }
    }

    /// Busy work, else the message, else why the fit stopped.
    fn message_line(&self, defined: [bool; 2]) -> Option<(String, bool)> {
        if let Some(b) = self.busy {
            return Some((b.to_string(), false));
        }
        if let Some((m, e)) = &self.message {
            return Some((m.clone(), *e));
        }
        let st = self.status.as_ref()?;
        if let Progress::Rounds { stopped, .. } = st.growth.progress {
            return stopped.map(|r| (format!("stopped: {}", light_stop_text(r)), false));
        }
        let r = st.stopped?;
        let errs = st
            .summary
            .as_ref()
            .map(|s| {
                format!(
                    "; final rel. L2 of ζ: {}",
                    format_errors(&s.errors, defined)
                )
            })
            .unwrap_or_default();
        let hint = if r == StopReason::TargetCells {
            "; raise the target cells and press Play to go on"
        } else {
            ""
        };
        Some((format!("stopped: {}{errs}{hint}", stop_text(r)), false))
    }
}

/// The light-driven learner's numbers: its rounds and probes, its own estimate of the error of
/// `B − E` and the error measured against the exact solve, each saying what it covers: the
/// estimate is of its kernel against the exact one on its own elements; the measure is of its
/// B read as a function against the exact solve on a finer mesh, so it holds the mesh's error too.
fn light_stats(rounds: u64, estimated: Option<f64>, probes: usize, lit: Option<&Lit>) -> String {
    let mut parts = vec![
        Learner::Light.title().to_string(),
        format!("round {rounds}"),
        format!("probes {probes}"),
    ];
    if let Some(e) = estimated {
        let on = lit.map_or_else(
            || "its mesh".to_string(),
            |l| format!("its {} el.", l.setup.lit.mesh().len()),
        );
        parts.push(format!(
            "estimated B−E {} (its kernel vs exact on {on})",
            error_text(e, true)
        ));
    }
    if let Some(l) = lit {
        let err = error_text(l.solve.errors.rel_l2_reflected, true);
        let finer = l.setup.lit.reference().mesh().len();
        parts.push(format!(
            "measured B−E {err} (as a function vs exact on {finer} el.: with the mesh's error)"
        ));
    }
    parts.join("  ")
}

/// Why the light-driven learner stopped, in words.
#[must_use]
pub fn light_stop_text(reason: LightStop) -> &'static str {
    match reason {
        LightStop::Tolerance => "the estimated error of B − E is within the tolerance (1 %)",
        LightStop::Exact => "no doubt is left: the operator is exact on this mesh",
        LightStop::Cells => "cell budget spent",
        LightStop::Time => "time budget spent",
    }
}

/// A stop reason in words.
#[must_use]
pub fn stop_text(reason: StopReason) -> &'static str {
    match reason {
        StopReason::TargetCells => "target cell count reached",
        StopReason::TargetError => "target error reached",
        StopReason::RayBudget => "ray budget spent",
        StopReason::StepBudget => "step budget spent",
        StopReason::Interrupted => "interrupted",
        StopReason::Exact => {
            "exact: geometry decides every visibility in this scene, there is nothing to learn"
        }
        StopReason::Converged => {
            "converged: every sample is predicted exactly and a θ scan found nothing left to learn"
        }
    }
}

/// A network as it runs, in a few words: its title, whether its parameters are its preset's,
/// and what it learns.
fn learner_name(learner: Learner, p: &FitParams) -> String {
    let target = match p.target {
        kernel_fit::Target::Visibility => "V",
        kernel_fit::Target::Zeta => "ζ",
        kernel_fit::Target::FactoredEmission => "k",
    };
    let changed = learner
        .preset()
        .is_some_and(|preset| with_preset(preset, p) != *p);
    let title = learner.title();
    if changed {
        format!("{title}, changed ({target})")
    } else {
        format!("{title} ({target})")
    }
}

/// Both final errors, formatted; "undefined" where [`crate::worker::World::defined`] says so.
#[must_use]
pub(super) fn format_errors(e: &Errors, defined: [bool; 2]) -> String {
    format!(
        "grid {}, held out {}",
        error_text(e.grid, defined[0]),
        error_text(e.heldout, defined[1])
    )
}

/// A relative error with three decimals, or "undefined".
#[must_use]
pub(super) fn error_text(value: f64, defined: bool) -> String {
    if defined {
        format!("{value:.3}")
    } else {
        "undefined".to_owned()
    }
}
