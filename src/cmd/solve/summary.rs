//! What `flatland solve` reports: the table, or one JSON object.

use flatland_light::LightStop;
use flatland_methods::Account;
use flatland_solve::{Comparison, LitScene};

use super::BuiltInfo;

/// What `flatland solve` reports.
pub(super) struct Summary<'a> {
    scene: &'a str,
    kernel: &'a str,
    lit: &'a LitScene,
    c: &'a Comparison,
    built: &'a BuiltInfo,
}

impl<'a> Summary<'a> {
    pub fn new(
        scene: &'a str,
        kernel: &'a str,
        lit: &'a LitScene,
        c: &'a Comparison,
        built: &'a BuiltInfo,
    ) -> Summary<'a> {
        Summary {
            scene,
            kernel,
            lit,
            c,
            built,
        }
    }

    /// The `--json` object; `note` is there only when the method built a count other than
    /// asked (or traced).
    pub fn json(&self) -> serde_json::Value {
        let (c, b) = (self.c, self.built);
        let mut json = serde_json::json!({
            "scene": self.scene,
            "kernel": self.kernel,
            "elements": self.lit.mesh().len(),
            "basis_functions": b.basis,
            "kernel_bytes": b.bytes,
            "rel_l2_b": c.errors.rel_l2_b,
            "rel_l2_reflected": c.errors.rel_l2_reflected,
            "iterations": c.solution.iterations,
            "residual": c.solution.residual,
            "wall_s": c.solution.wall_s(),
            "peak_memory_bytes": flatland_lab::memory::peak_bytes(),
            "build_s": b.build_s,
            "reference_elements": self.lit.reference().mesh().len(),
            "discretization_error_estimate": self.lit.estimate().map(|e| e.estimate),
        });
        if let Some(note) = &b.note {
            json["note"] = note.as_str().into();
        }
        if let Account::Light(l) = &b.account {
            json["estimated_rel_l2_reflected"] = l.estimated_error.unwrap_or(f64::INFINITY).into();
            json["rounds"] = l.rounds.into();
            json["probes"] = l.probes.into();
            json["stopped"] = stop_name(l.stopped).into();
        }
        json
    }

    /// The human-readable summary.
    pub fn print(&self) {
        let (c, b) = (self.c, self.built);
        let row = |k: &str, v: String| println!("  {k:<26} {v}");
        println!("solve of {} with the {} kernel", self.scene, self.kernel);
        let basis = b.basis.map_or("exact (none)".to_owned(), |n| n.to_string());
        row("basis functions", basis);
        if let Some(note) = &b.note {
            row("note", note.clone());
        }
        let reference = self.lit.reference().mesh().len();
        let elements = self.lit.mesh().len();
        row(
            "elements",
            format!("{elements} (exact reference: {reference})"),
        );
        if let Some(e) = self.lit.estimate() {
            let (estimate, finer) = (e.estimate, e.finer_elements);
            let text =
                format!("≈ {estimate:.1e} (estimated from a solve on 2N = {finer} elements)");
            row("discretization error", text);
        }
        row("rel. L2 of B", format!("{:.5}", c.errors.rel_l2_b));
        let reflected = c.errors.rel_l2_reflected;
        row(
            "rel. L2 of B − E",
            format!("{reflected:.5}   (the reflected part)"),
        );
        if let Account::Light(l) = &b.account {
            let estimate = l.estimated_error.unwrap_or(f64::INFINITY);
            let (rounds, probes, why) = (l.rounds, l.probes, stop_name(l.stopped));
            let text = format!(
                "{estimate:.5}   (against the exact kernel on these elements; {rounds} rounds, \
                 {probes} probes, stopped: {why})"
            );
            row("  estimated by the learner", text);
        }
        let (iterations, residual) = (c.solution.iterations, c.solution.residual);
        row(
            "iterations",
            format!("{iterations} (residual {residual:.1e})"),
        );
        let s = &c.solution;
        let (wall, assembly, solve) = (s.wall_s(), s.assembly_s, s.solve_s);
        let text = format!("{wall:.3} s (operator {assembly:.3} s, linear solve {solve:.3} s)");
        row("wall time", text);
        row("building the kernel", format!("{:.3} s", b.build_s));
        let mb = b.bytes as f64 / 1e6;
        row(
            "kernel's memory",
            format!("{mb:.1} MB (the representation)"),
        );
        if let Some(peak) = flatland_lab::memory::peak_bytes() {
            let mb = peak as f64 / 1e6;
            row("peak memory", format!("{mb:.0} MB (the whole command)"));
        }
    }
}

/// How `--json` and the table name why the light-driven learner stopped.
fn stop_name(stop: LightStop) -> &'static str {
    match stop {
        LightStop::Tolerance => "tolerance",
        LightStop::Exact => "exact",
        LightStop::Cells => "cells",
        LightStop::Time => "time",
    }
}
