//! The learning curves under the plots: the held-out error of ζ and of the solved `B − E`
//! against steps and rays, cells and samples, and `B(s)` of the learned and exact kernels.

use egui::{Color32, Stroke};
use egui_plot::{Legend, Line, LineStyle, Plot, PlotPoints, Polygon};
use flatland_solve::Mesh;
use kernel_fit::HistoryPoint;

use super::EMITTER;
use crate::lit::LitPoint;
use crate::worker::Lit;

/// `B(s)` along the surfaces: the learned solution as steps (one per element), the exact one
/// on the finer mesh as a line, emitters shaded. The axis stops above the brightest
/// non-emitter; emitters leave the plot.
fn b_curves(ui: &mut egui::Ui, lit: &Lit, height: f32) {
    let setup = &lit.setup;
    let (mesh, b) = (&setup.mesh(), &lit.solve.b);
    let fine = setup.reference().mesh();
    let exact = &setup.reference().solution().radiosity;
    let lit_max = |mesh: &Mesh, b: &[f64]| {
        (0..mesh.len())
            .filter(|&i| mesh.edge_of(i).emission == 0.0)
            .map(|i| b[i])
            .filter(|v| v.is_finite())
            .fold(0.0_f64, f64::max)
    };
    let mut y_max = 1.25 * lit_max(mesh, b).max(lit_max(fine, exact));
    if y_max <= 0.0 || !y_max.is_finite() {
        y_max = 1.0;
    }
    let clip = |v: f64| if v.is_finite() { v.min(y_max) } else { y_max };
    let exact_points: PlotPoints<'static> = fine
        .elements()
        .iter()
        .zip(exact)
        .map(|(e, &v)| [e.s_mid, clip(v)])
        .collect();
    let learned_points: PlotPoints<'static> = mesh
        .elements()
        .iter()
        .zip(b)
        .flat_map(|(e, &v)| [[e.s[0], clip(v)], [e.s[1], clip(v)]])
        .collect();
    let emitters: Vec<[f64; 2]> = mesh
        .edges()
        .iter()
        .filter(|e| e.emission > 0.0)
        .map(|e| e.s)
        .collect();
    Plot::new("b-of-s")
        .height(height)
        .legend(Legend::default())
        .allow_scroll(false)
        .allow_zoom(false)
        .allow_drag(false)
        .allow_double_click_reset(false)
        .show(ui, |p| {
            p.set_plot_bounds_x(0.0..=1.0);
            p.set_plot_bounds_y(0.0..=y_max);
            for (k, [s0, s1]) in emitters.into_iter().enumerate() {
                let name = if k == 0 { "emitter" } else { "" };
                p.polygon(
                    Polygon::new(name, vec![[s0, 0.0], [s1, 0.0], [s1, y_max], [s0, y_max]])
                        .fill_color(EMITTER.gamma_multiply(0.25))
                        .stroke(Stroke::NONE),
                );
            }
            p.line(
                Line::new(format!("exact ({} el.)", fine.len()), exact_points)
                    .color(Color32::from_gray(200))
                    .width(1.5),
            );
            p.line(
                Line::new(format!("learned ({} el.)", mesh.len()), learned_points)
                    .color(Color32::from_rgb(249, 140, 10))
                    .width(2.0),
            );
        });
}

/// A plot of `height` with a legend and y from 0, fixed in place (no scroll, zoom or drag):
/// the curves follow the run, not the pointer. Its x axis counts (steps, rays, rounds) in
/// [`count_label`]s, so a long run's "2000000" does not run into the next plot.
fn fixed_plot(id: &str, height: f32) -> Plot<'_> {
    Plot::new(id)
        .height(height)
        .x_axis_formatter(|mark, _| count_label(mark.value, mark.step_size))
        .include_y(0.0)
        .legend(Legend::default())
        .allow_scroll(false)
        .allow_zoom(false)
        .allow_drag(false)
}

/// A count on an axis whose marks are `step` apart, short: `950`, `12k`, `2.5M`; with as
/// many decimals (up to 3) as the step needs, so neighbouring marks never read the same.
fn count_label(v: f64, step: f64) -> String {
    let (scale, unit) = match v.abs() {
        a if a >= 1e9 => (1e9, "G"),
        a if a >= 1e6 => (1e6, "M"),
        a if a >= 1e4 => (1e3, "k"),
        _ => (1.0, ""),
    };
    let step = (step / scale).abs();
    let decimals = (0..3)
        .find(|&d| {
            let shifted = step * 10f64.powi(d);
            (shifted - shifted.round()).abs() < 1e-6 * shifted.max(1.0)
        })
        .unwrap_or(3) as usize;
    format!("{:.*}{unit}", decimals, v / scale)
}

/// A learning curve. Never aggregated into a band: egui_plot fills the span of points that share
/// a pixel column, which turned a vertical drop (errors falling while the rays stay the same)
/// into a filled wedge.
fn curve(name: &str, points: PlotPoints<'static>) -> Line<'static> {
    Line::new(name, points).allow_band(false)
}

/// The learning curves: held-out error of ζ (and, with the lit scene, of the solved `B − E`)
/// against steps and against rays; cells and samples; and `B(s)` when the lit scene exists.
pub fn curves(ui: &mut egui::Ui, history: &[HistoryPoint], lit: Option<&Lit>) {
    let lit_history = lit.map_or(&[][..], |l| &l.history[..]);
    let h = (ui.available_height() - 22.0).max(60.0);
    let series = |f: &dyn Fn(&HistoryPoint) -> [f64; 2]| -> PlotPoints<'static> {
        history.iter().map(f).collect()
    };
    let lit_series = |f: &dyn Fn(&LitPoint) -> [f64; 2]| -> PlotPoints<'static> {
        lit_history.iter().map(f).collect()
    };
    let columns = if lit.is_some() { 4 } else { 3 };
    // The light-driven learner's points are rounds, with its own estimate of the error.
    let rounds = lit_history.iter().any(|h| h.estimated.is_some());
    let estimated = |x: &dyn Fn(&LitPoint) -> f64| -> Option<Line<'static>> {
        let points: PlotPoints<'static> = lit_history
            .iter()
            .filter_map(|h| h.estimated.map(|e| [x(h), e]))
            .collect();
        (!points.points().is_empty())
            .then(|| curve("estimated B − E", points).style(LineStyle::dashed_loose()))
    };
    // One error plot against `x`: ζ held out, and with the lit scene its solved and estimated
    // B − E.
    let error_plot = |ui: &mut egui::Ui,
                      id: &str,
                      x: &dyn Fn(&HistoryPoint) -> f64,
                      lit_x: &dyn Fn(&LitPoint) -> f64| {
        fixed_plot(id, h).show(ui, |p| {
            p.line(curve(
                "ζ held out",
                series(&|pt| [x(pt), pt.rel_l2_heldout]),
            ));
            if !lit_history.is_empty() {
                p.line(curve(
                    "solved B − E",
                    lit_series(&|pt| [lit_x(pt), pt.rel_l2_reflected]),
                ));
            }
            if let Some(line) = estimated(lit_x) {
                p.line(line);
            }
        });
    };
    ui.columns(columns, |cols| {
        cols[0].label(if rounds {
            "rel. L2 vs rounds"
        } else {
            "rel. L2 vs steps"
        });
        error_plot(&mut cols[0], "err-steps", &|pt| pt.steps as f64, &|pt| {
            pt.steps as f64
        });
        // The light-driven learner casts no ray (its probes sweep whole views): its cost is
        // its probes, so its errors are plotted against them.
        let (label, cost): (_, &dyn Fn(&LitPoint) -> f64) = if rounds {
            ("rel. L2 vs probes", &|pt| pt.cells as f64)
        } else {
            ("rel. L2 vs rays cast", &|pt| pt.rays as f64)
        };
        cols[1].label(label);
        error_plot(&mut cols[1], "err-rays", &|pt| pt.rays as f64, cost);
        if let Some(lit) = lit {
            cols[3].label("B(s): learned vs exact");
            b_curves(&mut cols[3], lit, h);
        }
        counts(&mut cols[2], history, lit_history, rounds, h);
    });
}

/// Cells and samples against steps; for the light-driven learner (`rounds`), its probes
/// against rounds.
fn counts(
    ui: &mut egui::Ui,
    history: &[HistoryPoint],
    lit_history: &[LitPoint],
    rounds: bool,
    height: f32,
) {
    ui.label(if rounds {
        "probes vs rounds"
    } else {
        "cells and samples vs steps"
    });
    let series = |f: &dyn Fn(&HistoryPoint) -> [f64; 2]| -> PlotPoints<'static> {
        history.iter().map(f).collect()
    };
    fixed_plot("counts", height).show(ui, |p| {
        if rounds {
            let probes: PlotPoints<'static> = lit_history
                .iter()
                .map(|h| [h.steps as f64, h.cells as f64])
                .collect();
            p.line(curve("probes", probes).width(2.5));
            return;
        }
        p.line(curve("cells", series(&|h| [h.steps as f64, h.cells as f64])).width(2.5));
        p.line(
            curve(
                "samples / 20",
                series(&|h| [h.steps as f64, h.samples as f64 / 20.0]),
            )
            .style(LineStyle::dashed_dense()),
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_on_an_axis_are_short_and_tell_neighbouring_marks_apart() {
        let label = |v: f64, step: f64| count_label(v, step);
        assert_eq!(label(0.0, 500.0), "0");
        assert_eq!(label(950.0, 50.0), "950");
        assert_eq!(label(2500.0, 500.0), "2500");
        assert_eq!(label(12_000.0, 2000.0), "12k");
        assert_eq!(label(250_000.0, 50_000.0), "250k");
        assert_eq!(label(2e6, 1e6), "2M");
        assert_eq!(label(1.5e6, 5e5), "1.5M");
        assert_eq!(label(1.25e6, 2.5e5), "1.25M");
        assert_eq!(label(3e9, 1e9), "3G");
        assert_eq!(label(-2e6, 1e6), "-2M");
        // Rounds, zoomed in: fractions of a step.
        assert_eq!(label(1.5, 0.5), "1.5");
        assert_eq!(label(1.05, 0.05), "1.05");
        assert_eq!(
            label(1.0, 1.0 / 3.0),
            "1.000",
            "a step no decimal count fits: 3"
        );
    }
}
