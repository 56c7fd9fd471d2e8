//! One row of the timed bench: a method at one setting and seed, what it cost and how close
//! its lit scene came.

use flatland_solve::{Errors, SolveErrors};

use super::Method;

/// The knob a row was run at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// The light-driven learner's tolerance on its estimated error of `B − E`.
    Tolerance(f64),
    /// Basis functions asked for.
    Budget(usize),
    /// Elements of an exact solve.
    Elements(usize),
    /// Photons traced.
    Photons(u64),
}

impl Setting {
    /// What the knob is: `tolerance`, `budget`, `elements` or `photons`.
    pub fn kind(self) -> &'static str {
        match self {
            Setting::Tolerance(_) => "tolerance",
            Setting::Budget(_) => "budget",
            Setting::Elements(_) => "elements",
            Setting::Photons(_) => "photons",
        }
    }

    /// Its value as the CSV writes it.
    pub fn value(self) -> String {
        match self {
            Setting::Tolerance(t) => t.to_string(),
            Setting::Budget(n) | Setting::Elements(n) => n.to_string(),
            Setting::Photons(n) => n.to_string(),
        }
    }
}

/// One method at one setting and seed.
#[derive(Clone, Debug, PartialEq)]
pub struct TimedRow {
    /// The method.
    pub method: Method,
    /// What it was run at.
    pub setting: Setting,
    /// The seed (1 for a method without one).
    pub seed: u64,
    /// Basis functions of the representation (cells, links, blocks; elements for `exact`;
    /// none for `tracer`).
    pub basis_functions: Option<usize>,
    /// Seconds to build the representation (learning, linking; the exact operator's
    /// assembly), errors excluded.
    pub build_s: f64,
    /// Seconds to solve the radiosity with it (the operator on the solve's mesh and the linear
    /// solve; the whole trace for `tracer`).
    pub solve_s: f64,
    /// `build_s + solve_s`: the time to a lit scene.
    pub total_s: f64,
    /// Bytes the method holds (the representation, the exact operator, the tracer's tallies).
    pub bytes: usize,
    /// Rays cast (exact kernel evaluations or photon hits).
    pub rays: u64,
    /// Errors of the representation's ζ̃ against the ζ reference (relative L2 on its grid and
    /// at its held-out points, relative L1), where a kernel is represented, the run measures ζ
    /// and the error is defined (ζ is not 0 at every held-out point).
    pub zeta: Option<Errors>,
    /// Errors of the solved B against the exact reference.
    pub solve: Option<SolveErrors>,
    /// The light-driven learner's own estimate of its error of `B − E`.
    pub estimated_error: Option<f64>,
    /// Why the row is not what was asked for, or why it failed (empty when it is).
    pub note: String,
    /// Whether the method failed at this setting (the note says why).
    pub failed: bool,
}

impl TimedRow {
    /// A row of `method` at `setting` that has cost and measured nothing yet.
    pub fn new(method: Method, setting: Setting, seed: u64) -> TimedRow {
        TimedRow {
            method,
            setting,
            seed,
            basis_functions: None,
            build_s: 0.0,
            solve_s: 0.0,
            total_s: 0.0,
            bytes: 0,
            rays: 0,
            zeta: None,
            solve: None,
            estimated_error: None,
            note: String::new(),
            failed: false,
        }
    }

    /// The row of a method that failed at `setting`.
    pub fn failed(method: Method, setting: Setting, seed: u64, why: &str) -> TimedRow {
        TimedRow {
            note: format!("failed: {why}"),
            failed: true,
            ..TimedRow::new(method, setting, seed)
        }
    }

    /// The relative L2 error of ζ̃ at the held-out points, where it was measured.
    pub fn zeta_error(&self) -> Option<f64> {
        self.zeta.map(|e| e.heldout)
    }

    /// The relative L2 error of the solved `B − E`, when it was solved.
    pub fn reflected_error(&self) -> Option<f64> {
        self.solve.map(|e| e.rel_l2_reflected)
    }

    /// Adds `more` to the note (`; ` between notes).
    pub fn add_note(&mut self, more: &str) {
        if !self.note.is_empty() {
            self.note.push_str("; ");
        }
        self.note.push_str(more);
    }
}
