//! What `flatland solve` reports: the table, or one JSON object.

use flatland_lab::memory::peak_bytes;
use flatland_methods::{Account, Lit};
use flatland_solve::{Estimate, LitScene};

/// The `--json` object; `note` only when the method built a count other than asked (or
/// traced), the learner's keys only for the light-driven learner.
pub fn json(scene: &str, kernel: &str, lit: &LitScene, l: &Lit) -> serde_json::Value {
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
        "discretization_error_estimate": lit.estimate().map(|e| e.estimate()),
        "error_estimate": lit.estimate().map(|e| e.estimate()),
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
        json["rounds"] = a.rounds.into();
        json["probes"] = a.probes.into();
        json["stopped"] = a.stopped.name().into();
    }
    json
}

/// The human-readable table.
pub fn print(scene: &str, kernel: &str, lit: &LitScene, l: &Lit) {
    let (c, s) = (&l.comparison, &l.comparison.solution);
    let mut rows = vec![(
        "basis functions",
        l.basis.map_or("exact (none)".into(), |n| n.to_string()),
    )];
    rows.extend(l.note.clone().map(|note| ("note", note)));
    let (n, reference) = (lit.mesh().len(), lit.reference().mesh().len());
    rows.push(("elements", format!("{n} (exact reference: {reference})")));
    if let Some(e) = lit.estimate() {
        let estimate = e.estimate();
        let covers = match e {
            Estimate::Function(_) => {
                "of B − E as a function along the surfaces, between the \
                                      collocation points too"
            }
            Estimate::Collocation(_) => "of B − E at the collocation points only",
        };
        let finer = e.finer_elements();
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
    let mb = l.bytes as f64 / 1e6;
    rows.push((
        "kernel's memory",
        format!("{mb:.1} MB (the representation)"),
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
