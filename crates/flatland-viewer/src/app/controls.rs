//! The controls panel: scene, run, learner (which runs, and what a network learns), network,
//! sampling, fit, view, export. Every parameter with its valid range and a hover text; a change
//! to what only a new fit can change starts one (see `ViewerApp::sync_params`).

use std::path::PathBuf;

use egui::{DragValue, RichText};
use kernel_fit::Schema;
use kernel_fit::schema::{Bound, Range};
use kernel_fit::{Gating, Resampling, Target};
use sgcs::{InsertRule, Insertion, OutputMode, OutputRule, Resource};

use super::ViewerApp;
use crate::learner::Learner;
use crate::scenes::SceneChoice;
use crate::worker::Command;

impl ViewerApp {
    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        self.scene_controls(ui);
        ui.separator();
        self.run_controls(ui);
        ui.separator();
        self.learner_controls(ui);
        ui.separator();
        // The light-driven learner has none of the network's parameters.
        let network = self.settings.learner.preset().is_some();
        ui.add_enabled_ui(network, |ui| {
            self.network_controls(ui);
            ui.separator();
            self.sampling_controls(ui);
            ui.separator();
            self.fit_controls(ui);
        });
        ui.separator();
        self.view_controls(ui);
        ui.separator();
        self.export_controls(ui);
    }

    fn scene_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Scene");
        ui.horizontal_wrapped(|ui| {
            for (name, about) in crate::scenes::offered() {
                let selected = self.settings.scene == SceneChoice::Bundled(name.to_string());
                if ui
                    .selectable_label(selected, name)
                    .on_hover_text(about)
                    .clicked()
                {
                    self.open_bundled(name);
                }
            }
        });
        ui.label(RichText::new(&self.scene_label).strong());
        self.import_warnings(ui);
        ui.horizontal(|ui| {
            let edit = egui::TextEdit::singleline(&mut self.path_input)
                .hint_text("scene file (.ron/.json/.svg)")
                .desired_width(170.0);
            let r = ui.add(edit);
            let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if ui.button("Open").clicked() || enter {
                let path = PathBuf::from(self.path_input.trim());
                self.open_file(&path);
            }
        });
        ui.label(
            RichText::new("or drop a file on the window; drag end points in the scene view")
                .small()
                .weak(),
        );
        egui::Grid::new("scene-grid").num_columns(3).show(ui, |ui| {
            let l = ui.label("subdivision");
            ui.add(DragValue::new(&mut self.settings.subdivide).range(1..=1000))
                .labelled_by(l.id);
            ui.label(RichText::new("[1, 1000], on Reset").small().weak());
            ui.end_row();
        });
    }

    /// What importing the scene's drawing said, folded under a count.
    fn import_warnings(&self, ui: &mut egui::Ui) {
        let n = self.scene_warnings.len();
        if n == 0 {
            return;
        }
        let title = if n == 1 {
            "1 import warning".to_owned()
        } else {
            format!("{n} import warnings")
        };
        egui::CollapsingHeader::new(RichText::new(title).small())
            .id_salt("import-warnings")
            .show(ui, |ui| {
                for warning in &self.scene_warnings {
                    ui.label(RichText::new(warning).small().weak());
                }
            });
    }

    /// The pace of growth (see the learner's `train` module for why cells, not steps).
    fn run_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Run");
        ui.horizontal(|ui| {
            ui.spacing_mut().slider_width = 80.0;
            let r = ui
                .add_enabled(
                    !self.settings.unlimited,
                    egui::Slider::new(&mut self.settings.growth, 1.0..=2000.0)
                        .logarithmic(true)
                        .text("cells/s")
                        .max_decimals(0),
                )
                .on_hover_text(
                    "how fast the network may grow, in cells per second of training: the same \
                     on a fast machine as on a slow one (training between insertions runs at \
                     full speed)",
                );
            let u = ui
                .checkbox(&mut self.settings.unlimited, "max")
                .on_hover_text("grow as fast as this machine can");
            if r.changed() || u.changed() {
                self.send_pace();
            }
        });
    }

    /// Which learner runs, and what a network learns (ALGORITHM.md §4).
    fn learner_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Learner");
        self.learner_selector(ui);
        let network = self.settings.learner.preset().is_some();
        ui.add_enabled_ui(network, |ui| self.network_learner_controls(ui));
    }

    /// What a network learner learns, and how (target, gating, importance, weighting).
    fn network_learner_controls(&mut self, ui: &mut egui::Ui) {
        let p = &mut self.settings.params;
        let mut target = p.target;
        choice(
            ui,
            "target",
            "what the network learns (starts a new fit)",
            &mut target,
            &[
                (
                    Target::Visibility,
                    "V",
                    "the visibility only, on pairs of surface edges where geometry cannot \
                     decide it: learned ζ = exact unoccluded ζ × learned V (the default)",
                ),
                (Target::Zeta, "ζ", "ζ itself, everywhere (the paper)"),
                (
                    Target::FactoredEmission,
                    "k",
                    "k = ζ / E', the emission factored out exactly",
                ),
            ],
        );
        // What only some learners have comes along with the target (`FitParams::learning`).
        *p = p.learning(target);
        let visibility = p.target == Target::Visibility;
        ui.add_enabled_ui(visibility, |ui| {
            choice(
                ui,
                "gating",
                "which known discontinuities no cell may straddle (target V only; starts a new \
                 fit)",
                &mut p.gating,
                &[
                    (Gating::Off, "off", "every cell responds everywhere"),
                    (
                        Gating::Pairs,
                        "pairs",
                        "a cell responds only to rays between the same two surface edges as \
                         its centre ray",
                    ),
                    (
                        Gating::Faces,
                        "faces",
                        "and only to rays of its own face of the visibility structure, where V \
                         is constant (the default)",
                    ),
                ],
            );
            egui::Grid::new("learner-grid")
                .num_columns(3)
                .striped(true)
                .show(ui, |ui| {
                    schema_row(ui, p, "importance", "importance", 0.0..=0.99, 1e-2);
                });
            ui.checkbox(&mut p.weighted, "weighted errors")
                .on_hover_text(
                    "each sample's error counts with its importance weight p/q, so growth follows \
                 the error of ζ, not of V (target V only; starts a new fit)",
                );
        });
    }

    /// The light-driven learner, the visibility network or the paper's network: choosing one
    /// starts it afresh. Labelled with the method's title; its name is `--learner`'s.
    fn learner_selector(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            ui.label("learner").on_hover_text(
                "which learner runs; choosing one starts it afresh (target cells and seed are \
                 kept)",
            );
            for learner in Learner::ALL {
                let selected = self.settings.learner == learner;
                let about = learner_about(learner);
                let hover = format!("{about} (`--learner {}`)", learner.name());
                if ui
                    .selectable_label(selected, learner.title())
                    .on_hover_text(hover)
                    .clicked()
                {
                    self.choose_learner(learner);
                }
            }
            if self.settings.learner.preset().is_some() && !self.settings.is_preset() {
                ui.label(RichText::new("(changed)").weak())
                    .on_hover_text("parameters differ from the preset's");
            }
        });
    }

    /// `sgcs::Params` (ALGORITHM.md §3, §8).
    fn network_controls(&mut self, ui: &mut egui::Ui) {
        let n = &mut self.settings.params.network;
        ui.heading("Network");
        network_rates(ui, n);
        network_rules(ui, n);
    }

    /// Sets and θ (ALGORITHM.md §3).
    fn sampling_controls(&mut self, ui: &mut egui::Ui) {
        let p = &mut self.settings.params;
        ui.heading("Sampling");
        egui::Grid::new("sampling-grid")
            .num_columns(3)
            .striped(true)
            .show(ui, |ui| {
                schema_row(ui, p, "omega", "ω", 0.0..=100.0, 1e-2);
                schema_row(ui, p, "phi", "φ", 1e-6..=100.0, 1e-2);
                schema_row(ui, p, "psi", "ψ", 1e-4..=1.0, 1e-3);
                schema_row(ui, p, "initial_samples", "|S₀|", 3.0..=1_000_000.0, 10.0);
                schema_row(ui, p, "min_set_size", "min |S_j|", 1.0..=1_000_000.0, 1.0);
                schema_row(ui, p, "scan_factor", "scan ×", 1.0..=100_000.0, 1.0);
            });
        choice(
            ui,
            "new sets",
            "how the sets S₁, S₂, … are chosen",
            &mut p.resampling,
            &[
                (
                    Resampling::Theta,
                    "θ",
                    "rays only in critical zones or outside the network (the paper)",
                ),
                (
                    Resampling::Uniform,
                    "uniform",
                    "uniform random: the control that shows what θ earns",
                ),
            ],
        );
    }

    fn fit_controls(&mut self, ui: &mut egui::Ui) {
        let p = &mut self.settings.params;
        ui.heading("Fit");
        egui::Grid::new("fit-grid")
            .num_columns(3)
            .striped(true)
            .show(ui, |ui| {
                schema_row(ui, p, "target_cells", "target cells", 3.0..=20_000.0, 5.0);
                row(
                    ui,
                    "seed",
                    "every random choice (starts a new fit)",
                    &mut p.seed,
                    0..=u64::MAX,
                    "any",
                    1.0,
                );
                schema_row(ui, p, "ridge", "ridge", 1e-12..=1.0, 1e-7);
                schema_row(ui, p, "eval_every", "eval every", 0.0..=1_000_000.0, 100.0);
            });
        let learns_zeta = p.target != Target::Visibility;
        ui.add_enabled(
            learns_zeta,
            egui::Checkbox::new(&mut p.refit, "least-squares refit at the end"),
        )
        .on_hover_text("refit every output weight (targets ζ and k; V needs none)");
    }

    fn view_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("View");
        ui.checkbox(
            &mut self.settings.log_scale,
            format!(
                "log colour scale ({} decades)",
                flatland_pictures::colormap::LOG_DECADES
            ),
        );
        ui.checkbox(
            &mut self.settings.show_cells,
            "cells (size ~ δ_c, cyan = critical, ringed = new)",
        );
        ui.checkbox(&mut self.settings.show_edges, "network edges within a face")
            .on_hover_text(
                "the network's edges that join two cells of one face of the visibility \
                 structure (the paper's network: of one pair of surface edges); edges across \
                 faces join cells that never answer the same ray",
            );
        ui.checkbox(&mut self.settings.show_samples, "samples, coloured by set");
        self.moving_light_controls(ui);
        ui.add(
            egui::Slider::new(&mut self.settings.exposure, -4.0..=8.0)
                .step_by(0.5)
                .text("exposure (stops)"),
        );
        ui.checkbox(
            &mut self.settings.tone_log,
            format!(
                "log tone scale for the lit scenes ({} decades)",
                flatland_pictures::colormap::LOG_DECADES
            ),
        );
        let lit = ui
            .checkbox(&mut self.settings.lit, "lit scene (solve B while learning)")
            .on_hover_text(
                "solve the radiosity with the kernel learned so far, on the learner's thread, \
                 at most every 0.5 s and ≤ 10 % of its time",
            );
        if lit.changed() {
            self.worker.send(Command::Lit(self.settings.lit));
        }
        let network = self.settings.learner.preset().is_some();
        if ui
            .add_enabled(network, egui::Button::new("Restore preset"))
            .on_hover_text("the network's preset parameters (target cells, seed kept)")
            .clicked()
        {
            self.settings.restore_preset();
        }
    }

    /// The moving light: the wander, exact or learned transport, the transport's blocks and
    /// its learned M₂ in the kernel plot.
    fn moving_light_controls(&mut self, ui: &mut egui::Ui) {
        ui.checkbox(
            &mut self.settings.wander,
            "the light wanders (grab it to stop)",
        )
        .on_hover_text(
            "the relit scene's first light walks through the rooms by itself; drag a light, \
                 click the floor to add one, right-click one to delete it",
        );
        if ui
            .checkbox(
                &mut self.settings.transport,
                "learned transport (else exact)",
            )
            .on_hover_text(
                "on: B = B₀ + K B₀ exact, plus M₂ B₀ from the learned transport of the later \
                 bounces (docs/ALGORITHM.md §9), built in the background while the exact \
                 re-solve answers; off: the exact re-solve (GMRES, warm-started) every move",
            )
            .changed()
        {
            self.lamps.handle.use_transport(self.settings.transport);
        }
        // One row: the export buttons below must stay on a 1500-point-high window.
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.settings.show_blocks, "its blocks")
                .on_hover_text(
                    "the learned transport's blocks over the kernel plot, coloured by rank: \
                     each block of M₂ joins a cluster of senders (rows, s) to the receivers \
                     its light reaches (columns, t); drawn as the build makes them",
                );
            ui.checkbox(&mut self.settings.show_m2, "its M₂ for ζ")
                .on_hover_text(
                    "the kernel plot shows M₂ = K² (I − K)^-1, the later bounces the \
                     transport learned, as a density in s (log scale), in place of the exact \
                     ζ once the transport is built",
                );
        });
    }

    /// Save the view as a PNG and the run as a model file, into a folder.
    fn export_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Export");
        ui.horizontal(|ui| {
            if ui
                .button("Save view")
                .on_hover_text("the window as a PNG, named after scene, learner and step")
                .clicked()
            {
                self.export_png(ui.ctx());
            }
            if ui
                .button("Save model")
                .on_hover_text(
                    "the running fit as the model file `flatland eval --model` reads (the \
                     learner's network now, whatever moment is shown)",
                )
                .clicked()
            {
                self.export_model();
            }
        });
        ui.horizontal(|ui| {
            let label = ui.label("into");
            let mut dir = self.export.dir.display().to_string();
            if ui
                .add(egui::TextEdit::singleline(&mut dir).desired_width(200.0))
                .labelled_by(label.id)
                .changed()
            {
                self.export.dir = PathBuf::from(dir);
            }
        });
    }
}

/// The network's rates and counts, one row each.
fn network_rates(ui: &mut egui::Ui, n: &mut sgcs::Params) {
    egui::Grid::new("net-grid")
        .num_columns(3)
        .striped(true)
        .show(ui, |ui| {
            schema_row(ui, n, "eps_b", "ε_b", 1e-6..=1.0, 1e-4);
            schema_row(ui, n, "eps_n", "ε_n", 0.0..=1.0, 1e-5);
            schema_row(ui, n, "eta", "η", 1e-6..=1.999, 1e-3);
            schema_row(ui, n, "alpha", "α", 0.0..=0.999, 1e-3);
            schema_row(ui, n, "lambda", "λ", 1.0..=100_000.0, 1.0);
            schema_row(ui, n, "activation_cutoff", "cutoff", 0.0..=0.5, 1e-9);
        });
}

/// How the network's output is made and learned, and how it grows.
fn network_rules(ui: &mut egui::Ui, n: &mut sgcs::Params) {
    choice(
        ui,
        "output",
        "how the cells' outputs combine",
        &mut n.output_mode,
        &[
            (OutputMode::Sum, "Σ v·M", "the paper's radial-basis sum"),
            (
                OutputMode::Normalized,
                "Σ v·M / Σ M",
                "normalised: a face with one cell anywhere has that cell's value (the \
                 default)",
            ),
        ],
    );
    choice(
        ui,
        "output rule",
        "how the output weights follow the error",
        &mut n.output_rule,
        &[
            (
                OutputRule::Normalized,
                "NLMS",
                "the delta rule with its step shortened where cells overlap: cannot \
                 diverge (the paper's preset)",
            ),
            (
                OutputRule::Plain,
                "delta",
                "the paper's printed rule; diverges where many cells overlap",
            ),
            (
                OutputRule::Local,
                "local",
                "only the winner learns, towards the target itself: exact where the target \
                 is constant on a face (the default)",
            ),
        ],
    );
    growth_rules(ui, n);
}

/// Where a new cell goes, what it starts with, and what decides where to grow.
fn growth_rules(ui: &mut egui::Ui, n: &mut sgcs::Params) {
    choice(
        ui,
        "insertion",
        "where a new cell goes",
        &mut n.insertion,
        &[
            (
                Insertion::Midpoint,
                "midpoint",
                "the midpoint of the worst cell's longest edge (the paper)",
            ),
            (
                Insertion::WorstSample,
                "worst sample",
                "the worst cell's worst recent sample, where the error is (the default)",
            ),
        ],
    );
    choice(
        ui,
        "new cell's v",
        "the output weight of a new cell",
        &mut n.insert_rule,
        &[
            (
                InsertRule::PreserveOutput,
                "preserve",
                "the output at the new centre is unchanged (the paper's preset)",
            ),
            (
                InsertRule::VolumeWeighted,
                "volume",
                "the neighbours' weights, weighted by the volume each loses",
            ),
            (
                InsertRule::SampleTarget,
                "its sample's",
                "the target of the sample it is put at (the default)",
            ),
        ],
    );
    choice(
        ui,
        "resource",
        "what a cell's resource τ measures (growth, critical cells)",
        &mut n.resource,
        &[
            (
                Resource::MeanTimesVolume,
                "mean × |F|",
                "mean squared error times the Voronoi volume (the paper)",
            ),
            (
                Resource::ErrorSum,
                "error sum",
                "decayed sum of the weighted squared errors (the default)",
            ),
        ],
    );
}

/// One value among a few, as selectable labels with hover texts, after its name.
fn choice<T: PartialEq + Copy>(
    ui: &mut egui::Ui,
    name: &str,
    meaning: &str,
    value: &mut T,
    options: &[(T, &str, &str)],
) {
    ui.horizontal_wrapped(|ui| {
        ui.label(name).on_hover_text(meaning);
        for &(option, text, hover) in options {
            // Not `labelled_by`: each option is found by its own text.
            ui.selectable_value(value, option, text)
                .on_hover_text(hover);
        }
    });
}

/// A parameter of the schema in a 3-column grid: label (hover: the schema's help) | value |
/// the schema's range. The value is kept inside the range (and inside `shown`, a practical
/// window for dragging), so the learner never sees an invalid value.
fn schema_row<S: Schema>(
    ui: &mut egui::Ui,
    params: &mut S,
    name: &str,
    label: &str,
    shown: std::ops::RangeInclusive<f64>,
    speed: f64,
) {
    let Some(spec) = S::spec(name) else {
        return;
    };
    let (lo, hi) = valid_window(spec.range, shown);
    let Some(mut value) = params.get(name) else {
        return;
    };
    let meaning = spec.help;
    let label = ui.label(label).on_hover_text(meaning);
    let mut drag = DragValue::new(&mut value).range(lo..=hi).speed(speed);
    drag = if spec.range.integer {
        drag.fixed_decimals(0)
    } else {
        drag.max_decimals(9)
    };
    if ui
        .add(drag)
        .labelled_by(label.id)
        .on_hover_text(meaning)
        .changed()
    {
        let value = if spec.range.integer {
            value.round()
        } else {
            value
        };
        if spec.range.contains(value) {
            params.set(name, value);
        }
    }
    ui.label(RichText::new(spec.range.to_string()).small().weak());
    ui.end_row();
}

/// The closed window a drag value may take: the valid range (open ends moved one step in)
/// within `shown`.
fn valid_window(range: Range, shown: std::ops::RangeInclusive<f64>) -> (f64, f64) {
    let lo = match range.lo {
        Bound::Closed(v) => v,
        Bound::Open(v) => v.next_up(),
        Bound::None => f64::MIN,
    };
    let hi = match range.hi {
        Bound::Closed(v) => v,
        Bound::Open(v) if range.integer => v - 1.0,
        Bound::Open(v) => v.next_down(),
        Bound::None => f64::MAX,
    };
    (lo.max(*shown.start()), hi.min(*shown.end()))
}

/// A labelled, range-limited number in a 3-column grid: name (hover: meaning) | value | range.
fn row<T: egui::emath::Numeric>(
    ui: &mut egui::Ui,
    name: &str,
    meaning: &str,
    value: &mut T,
    range: std::ops::RangeInclusive<T>,
    valid: &str,
    speed: f64,
) {
    let label = ui.label(name).on_hover_text(meaning);
    ui.add(
        DragValue::new(value)
            .range(range)
            .speed(speed)
            .max_decimals(9),
    )
    .labelled_by(label.id)
    .on_hover_text(meaning);
    ui.label(RichText::new(valid).small().weak());
    ui.end_row();
}

/// What each learner does, for its hover text.
fn learner_about(learner: Learner) -> &'static str {
    match learner {
        Learner::Light => {
            "the default, what `flatland solve` runs: rounds of solving the scene with what is \
             learned, then probing the exact view of the points between whose neighbours' \
             views the most uncertain light flows (ALGORITHM.md §4a). The network's \
             parameters below do not apply to it"
        }
        Learner::Visibility => {
            "learns only the visibility V, where geometry cannot decide it, in cells that never \
             straddle a shadow boundary (ALGORITHM.md §4)"
        }
        Learner::Paper => {
            "the paper's network: learns ζ everywhere from γ(s, t), with least-squares refit \
             (ALGORITHM.md §3)"
        }
    }
}
