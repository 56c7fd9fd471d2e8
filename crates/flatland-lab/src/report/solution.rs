//! What `flatland solve --out` writes, as bytes (the caller writes them): the solution as CSV
//! (one row per element, or B as a function at points inside every element), the lit plan as
//! SVG, or the lit scene beside B(s) against the exact solution as PNG; and what it prints
//! (a table, or one JSON object).

use std::borrow::Cow;

use flatland_methods::{Account, Lit};
use flatland_pictures::PictureError;
use flatland_solve::{
    FinalGather, LitScene, SolveError, Stop, line_along, radiosity_csv, samples_csv,
};

use crate::memory::peak_bytes;

/// One lighting of a lit scene, and what names it.
pub struct Solution<'a> {
    /// The lit scene (its mesh, the exact solve and reference, B as a function).
    pub lit: &'a LitScene,
    /// The lighting with the kernel asked for.
    pub lighting: &'a Lit,
    /// Whether that kernel is the exact one (whose element value is the mean of its function).
    pub exact: bool,
    /// The scene's name, for titles.
    pub label: &'a str,
    /// The kernel's name, for titles.
    pub kernel: &'a str,
}

impl Solution<'_> {
    /// One value per element: the exact kernel's the mean of its function over the element,
    /// another kernel's its element value.
    #[must_use]
    pub fn element_values(&self) -> &[f64] {
        match self.lit.function() {
            Some(function) if self.exact => &function.element_means,
            _ => &self.lighting.comparison.solution.radiosity,
        }
    }

    /// `edge,s,x,y,b`: `samples` rows per element of B as a function (the final gather of the
    /// solved B at evenly spaced points), or one row per element ([`Self::element_values`]).
    pub fn csv(&self, samples: Option<usize>, stop: &Stop) -> Result<String, SolveError> {
        let Some(n) = samples else {
            return Ok(radiosity_csv(self.lit.mesh(), self.element_values()));
        };
        let gather = match self.lit.function() {
            Some(function) => Cow::Borrowed(&function.gather),
            None => Cow::Owned(FinalGather::new(self.lit.kernel(), self.lit.mesh())?),
        };
        let b = &self.lighting.comparison.solution.radiosity;
        Ok(samples_csv(&gather.samples(b, n, stop)?))
    }

    /// B along every element as the pictures draw it: the exact kernel's by its final gather
    /// (at the start, middle and end of each element: three views per element), another
    /// kernel's as the line through its element midpoints.
    pub fn along(&self, stop: &Stop) -> Result<Vec<[f64; 3]>, SolveError> {
        let b = &self.lighting.comparison.solution.radiosity;
        match self.lit.function() {
            Some(function) if self.exact => function.gather.along(b, stop),
            _ => Ok(line_along(self.lit.mesh(), b)),
        }
    }

    /// The lit plan as SVG (`flatland_pictures::plan`), each element drawn by `along`
    /// ([`Self::along`]).
    #[must_use]
    pub fn svg(&self, along: &[[f64; 3]]) -> String {
        let title = format!("{} lit by the {} kernel", self.label, self.kernel);
        let (scene, mesh) = (self.lit.kernel().scene(), self.lit.mesh());
        let values = self.element_values();
        let plan = flatland_pictures::plan::lit_plan(scene, mesh, values, along, &title);
        plan.svg().to_owned()
    }

    /// The lit scene beside B(s) against the exact solution, as PNG, each element drawn by
    /// `along` ([`Self::along`]).
    pub fn png(&self, along: &[[f64; 3]]) -> Result<Vec<u8>, PictureError> {
        let c = &self.lighting.comparison;
        flatland_pictures::lit::lit_scene_png(&flatland_pictures::lit::Picture {
            scene: self.lit.kernel().scene(),
            label: self.label,
            kernel: self.kernel,
            mesh: self.lit.mesh(),
            b: &c.solution.radiosity,
            along,
            reference: self.lit.reference(),
            rel_l2_reflected: c.errors.rel_l2_reflected,
        })
    }

    /// `flatland solve --json`'s object; `note` only when the method built a count other than asked (or
    /// traced), the learner's keys only for the light-driven learner.
    pub fn json(&self) -> serde_json::Value {
        let (scene, kernel, lit, l) = (self.label, self.kernel, self.lit, self.lighting);
        let c = &l.comparison;
        let mut json = serde_json::json!({
            "scene": scene,
            "kernel": kernel,
            "elements": lit.mesh().len(),
            "basis_functions": l.basis,
            "kernel_bytes": l.bytes,
            "rel_l2_b": c.errors.rel_l2_b,
            "rel_l2_reflected": c.errors.rel_l2_reflected,
            "iterations": c.solution.iterations,
            "residual": c.solution.residual,
            "wall_s": c.solution.wall_s(),
            "peak_memory_bytes": peak_bytes(),
            "build_s": l.build_s,
            "reference_elements": lit.reference().mesh().len(),
            "discretization_error_estimate": lit.estimate().map(|e| e.estimate),
            "error_estimate": lit.estimate().map(|e| e.estimate),
            "error_estimate_covers": lit.estimate().map(|e| e.covers()),
        });
        if let Some(f) = lit.function() {
            json["refinement_rounds"] = f.rounds.len().into();
        }
        if let Some(note) = &l.note {
            json["note"] = note.as_str().into();
        }
        if let Account::Light(a) = &l.account {
            json["estimated_rel_l2_reflected"] = a.estimated_error.unwrap_or(f64::INFINITY).into();
            json["learner_error_estimate"] = a.estimate.map(|e| e.estimate()).into();
            json["learner_error_estimate_covers"] = a.estimate.map(|e| e.covers()).into();
            json["rounds"] = a.rounds.into();
            json["probes"] = a.probes.into();
            json["stopped"] = a.stopped.name().into();
        }
        json
    }

    /// `flatland solve`'s table, printed.
    pub fn print(&self) {
        let (scene, kernel, lit, l) = (self.label, self.kernel, self.lit, self.lighting);
        let (c, s) = (&l.comparison, &l.comparison.solution);
        let mut rows = vec![(
            "basis functions",
            l.basis.map_or("exact (none)".into(), |n| n.to_string()),
        )];
        rows.extend(l.note.clone().map(|note| ("note", note)));
        let (n, reference) = (lit.mesh().len(), lit.reference().mesh().len());
        rows.push(("elements", format!("{n} (exact reference: {reference})")));
        if let Some(e) = lit.estimate() {
            let estimate = e.estimate;
            let covers = "of B − E as a function along the surfaces, between the collocation \
                          points too";
            let finer = e.finer_elements;
            let text = format!("≈ {estimate:.1e} ({covers}; from a solve on {finer} elements)");
            rows.push(("discretization error", text));
            if let Some(f) = lit.function() {
                let counts: Vec<String> = f.rounds.iter().map(|r| r.elements.to_string()).collect();
                rows.push(("mesh refined", format!("{} elements", counts.join(" → "))));
            }
        }
        rows.push(("rel. L2 of B", format!("{:.5}", c.errors.rel_l2_b)));
        let reflected = c.errors.rel_l2_reflected;
        rows.push((
            "rel. L2 of B − E",
            format!("{reflected:.5}   (the reflected part)"),
        ));
        if let Account::Light(a) = &l.account {
            let estimate = a.estimated_error.unwrap_or(f64::INFINITY);
            let (rounds, probes, why) = (a.rounds, a.probes, a.stopped.name());
            let text = format!(
                "{estimate:.5}   (against the exact kernel on these elements; {rounds} rounds, \
                 {probes} probes, stopped: {why})"
            );
            rows.push(("  estimated by the learner", text));
            if let Some(e) = a.estimate.filter(|e| e.discretization.is_some()) {
                let text = format!(
                    "{:.5}   (its values read by the exact final gather, as --samples \
                     writes them: the learner's plus the mesh's; the error above reads them as \
                     a line through the midpoints)",
                    e.estimate()
                );
                rows.push(("  with the mesh's error", text));
            }
        }
        let (iterations, residual) = (s.iterations, s.residual);
        rows.push((
            "iterations",
            format!("{iterations} (residual {residual:.1e})"),
        ));
        let (wall, assembly, solve) = (s.wall_s(), s.assembly_s, s.solve_s);
        let text = format!("{wall:.3} s (operator {assembly:.3} s, linear solve {solve:.3} s)");
        rows.push(("wall time", text));
        rows.push(("building the kernel", format!("{:.3} s", l.build_s)));
        rows.push((
            "kernel's memory",
            format!("{} (the representation)", kernel_bytes_text(l.bytes)),
        ));
        if let Some(peak) = peak_bytes() {
            let mb = peak as f64 / 1e6;
            rows.push(("peak memory", format!("{mb:.0} MB (the whole command)")));
        }
        println!("solve of {scene} with the {kernel} kernel");
        for (key, value) in rows {
            println!("  {key:<26} {value}");
        }
    }
}

/// A representation's bytes in units that show them: a network of a few hundred cells is tens
/// of kilobytes, which "0.0 MB" hid.
fn kernel_bytes_text(bytes: usize) -> String {
    let bytes = bytes as f64;
    if bytes < 1e5 {
        format!("{:.1} KB", bytes / 1e3)
    } else {
        format!("{:.1} MB", bytes / 1e6)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_kernels_show_their_kilobytes() {
        assert_eq!(kernel_bytes_text(0), "0.0 KB");
        assert_eq!(kernel_bytes_text(31_200), "31.2 KB");
        assert_eq!(kernel_bytes_text(2_500_000), "2.5 MB");
    }
}
