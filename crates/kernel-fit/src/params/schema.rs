//! The schema of the fit's numeric parameters (names, symbols, ranges, help) and the table of
//! docs/ALGORITHM.md §8 generated from it.

use sgcs::schema::{Bound, Range, Schema, Spec};

use crate::{FitParams, limits};

/// The fit's own numeric parameters (the network's follow them in [`FitParams::specs`]).
fn own_specs() -> Vec<Spec> {
    let mut specs = growth_specs();
    specs.extend(stop_specs());
    specs
}

/// A spec of the table.
fn spec(name: &'static str, symbol: &'static str, range: Range, help: &'static str) -> Spec {
    Spec {
        name,
        symbol,
        range,
        help,
    }
}

/// How the network grows and its samples are drawn.
fn growth_specs() -> Vec<Spec> {
    use Bound::{Closed, None as Unbounded, Open};
    let real = Range::real;
    let whole = |lo: f64, hi: Option<u64>| Range::integer(lo, hi.map(|h| h as f64));
    vec![
        spec(
            "omega",
            "ω",
            real(Closed(0.0), Unbounded),
            "a cell is critical when τ_c > ω · mean τ",
        ),
        spec(
            "phi",
            "φ",
            real(Open(0.0), Unbounded),
            "ξ is inside a (sub-)network when its summed activation exceeds φ",
        ),
        spec(
            "psi",
            "ψ",
            real(Open(0.0), Closed(1.0)),
            "a new sample set is drawn when cells / samples > ψ",
        ),
        spec(
            "initial_samples",
            "|S₀|",
            whole(3.0, Some(limits::MAX_SET_SIZE as u64)),
            "uniform random samples before training",
        ),
        spec(
            "min_set_size",
            "",
            whole(1.0, Some(limits::MAX_SET_SIZE as u64)),
            "smallest resampled set",
        ),
        spec(
            "scan_factor",
            "",
            whole(1.0, None),
            "the θ scan looks at most this × set size candidates",
        ),
    ]
}

/// When the fit stops, its refit, and what it measures on the way.
fn stop_specs() -> Vec<Spec> {
    use Bound::{Closed, None as Unbounded, Open};
    let real = Range::real;
    let whole = |lo: f64, hi: Option<u64>| Range::integer(lo, hi.map(|h| h as f64));
    vec![
        spec(
            "target_cells",
            "N",
            whole(3.0, Some(limits::MAX_CELLS as u64)),
            "stop at this many cells (the network's max_cells)",
        ),
        spec(
            "max_steps",
            "",
            whole(1.0, Some(limits::MAX_COUNT)),
            "stop after this many training steps",
        ),
        spec(
            "ray_budget",
            "",
            whole(1.0, None),
            "stop after this many training rays",
        ),
        spec(
            "target_error",
            "",
            real(Closed(0.0), Unbounded),
            "stop when the held-out relative L2 reaches this (0: never)",
        ),
        spec(
            "ridge",
            "",
            real(Open(0.0), Closed(1e100)),
            "smallest ridge weight the least-squares refit tries (× 10⁰ … 10⁶)",
        ),
        spec(
            "heldout",
            "",
            whole(
                *limits::HELDOUT.start() as f64,
                Some(*limits::HELDOUT.end() as u64),
            ),
            "held-out points of the error measured during the fit",
        ),
        spec(
            "eval_every",
            "",
            whole(0.0, None),
            "steps between two held-out measurements in the history (0: never)",
        ),
        spec(
            "importance",
            "",
            real(Closed(0.0), Open(1.0)),
            "visibility learner: share of samples drawn by importance",
        ),
    ]
}

impl Schema for FitParams {
    /// The network's parameters (except `max_cells`, which is `target_cells`), then the fit's.
    fn specs() -> Vec<Spec> {
        let mut specs: Vec<Spec> = sgcs::Params::specs()
            .into_iter()
            .filter(|s| s.name != "max_cells")
            .collect();
        specs.extend(own_specs());
        specs
    }

    fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "omega" => self.omega,
            "phi" => self.phi,
            "psi" => self.psi,
            "initial_samples" => self.initial_samples as f64,
            "min_set_size" => self.min_set_size as f64,
            "scan_factor" => self.scan_factor as f64,
            "target_cells" => self.target_cells as f64,
            "max_steps" => self.max_steps as f64,
            "ray_budget" => self.ray_budget as f64,
            "target_error" => self.target_error,
            "ridge" => self.ridge,
            "heldout" => self.heldout as f64,
            "eval_every" => self.eval_every as f64,
            "importance" => self.importance,
            "max_cells" => return None,
            _ => return self.network.get(name),
        })
    }

    fn set(&mut self, name: &str, value: f64) -> bool {
        match name {
            "omega" => self.omega = value,
            "phi" => self.phi = value,
            "psi" => self.psi = value,
            "initial_samples" => self.initial_samples = value as usize,
            "min_set_size" => self.min_set_size = value as usize,
            "scan_factor" => self.scan_factor = value as usize,
            "target_cells" => self.target_cells = value as usize,
            "max_steps" => self.max_steps = value as u64,
            "ray_budget" => self.ray_budget = value as u64,
            "target_error" => self.target_error = value,
            "ridge" => self.ridge = value,
            "heldout" => self.heldout = value as usize,
            "eval_every" => self.eval_every = value as u64,
            "importance" => self.importance = value,
            "max_cells" => return false,
            _ => return self.network.set(name, value),
        }
        true
    }
}

/// The Markdown table of every numeric parameter (name, symbol, range, the paper's and the
/// visibility network's value, meaning): the table of docs/ALGORITHM.md §8, which a test keeps
/// equal to this.
pub fn parameter_table() -> String {
    sgcs::schema::markdown_table(&[
        ("paper", &FitParams::paper()),
        ("visibility network", &FitParams::default()),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    const BEGIN: &str = "<!-- parameters: kernel_fit::parameter_table() -->\n";
    const END: &str = "<!-- end of parameters -->";

    #[test]
    fn the_documented_parameter_table_is_the_schema() {
        let doc = include_str!("../../../../docs/ALGORITHM.md");
        let table = doc
            .split_once(BEGIN)
            .and_then(|(_, rest)| rest.split_once(END))
            .map(|(table, _)| table)
            .expect("docs/ALGORITHM.md §8 holds the generated table between its markers");
        assert_eq!(
            table,
            parameter_table(),
            "docs/ALGORITHM.md §8 is out of date; replace its table with:\n{}",
            parameter_table()
        );
    }

    #[test]
    fn every_value_just_outside_a_range_is_refused_by_name() {
        for spec in FitParams::specs() {
            for bad in spec.range.outside() {
                let mut params = FitParams::default();
                assert!(params.set(spec.name, bad), "{}", spec.name);
                let msg = params.validate().unwrap_err().to_string();
                assert!(
                    msg.contains(spec.name) && msg.contains("must be in"),
                    "{msg}"
                );
            }
        }
        let mut params = FitParams::default();
        assert!(sgcs::schema::set_checked(&mut params, "eta = 0.5").is_ok());
        assert_eq!(params.network.eta, 0.5);
        let err = sgcs::schema::set_checked(&mut params, "eta=2").unwrap_err();
        assert!(err.contains("(0, 2)"), "{err}");
        let err = sgcs::schema::set_checked(&mut params, "max_cells=10").unwrap_err();
        assert!(err.contains("target_cells"), "the list of names: {err}");
    }
}
