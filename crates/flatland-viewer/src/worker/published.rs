//! What the learner publishes, as plain data the UI and the timeline keep: the scene's world,
//! the network at a moment, the learned ζ̃ on the display grid, the lit scene.

use std::sync::Arc;
use std::time::Duration;

use flatland_geom::{Kernel, Scene};
use flatland_light::LightStop;
use flatland_solve::Reference;
use kernel_fit::{FitParams, FitSummary, HistoryPoint, LearnedKernel, StopReason};

use crate::lit::{LitPoint, LitSetup, LitSolve};
use crate::prefix::Prefix;

/// Resolution of the reference grid (the errors' grid, and the colour scale's).
pub const REFERENCE_RES: usize = 256;
/// Resolution of the learned and error panels.
pub const APPROX_RES: usize = 128;

/// A scene and everything derived from it that the UI shows. Replaced, never mutated.
#[derive(Debug)]
pub struct World {
    /// Increases with every new scene.
    pub id: u64,
    /// The scene as the user sees and edits it (not subdivided).
    pub scene: Scene,
    /// The exact kernel (of the subdivided scene: the same function of `(s, t)`).
    pub kernel: Arc<Kernel>,
    /// The exact ζ on the reference grid and at held-out points.
    pub reference: Arc<Reference>,
    /// The exact ζ on the `APPROX_RES` display grid, for the error panel.
    pub exact_small: Vec<f64>,
    /// Whether relative errors are defined on the grid and at the held-out points: against a ζ
    /// that is 0 everywhere (nothing emits) they are 0/0 and shown as "undefined".
    pub defined: [bool; 2],
}

/// A training sample as the overlay draws it: its `(s, t)` and the index of the set that drew it.
pub type SamplePoint = ([f32; 2], u32);

/// One cell as the overlay draws it.
#[derive(Clone, Debug, PartialEq)]
pub struct CellMark {
    /// Mean `(s, t)` of the samples it won (paper Fig. 3c); before it has won one, the `(s, t)`
    /// of the sample nearest to it in the input space; `None` without samples.
    pub st: Option<[f32; 2]>,
    /// δ_c, in the unit-box input frame.
    pub width: f32,
    /// Whether it is critical (`τ_c > ω · mean τ`).
    pub critical: bool,
    /// For a probe of the light-driven learner: the stretches of `s` its point sees (its
    /// column of the kernel where `V = 1`), shared by every status that shows it; empty for
    /// a network cell.
    pub seen: std::sync::Arc<[[f32; 2]]>,
}

/// The learner at one moment: what the overlay and the counts show.
#[derive(Debug)]
pub struct Growth {
    /// What the learner's progress is counted in: training steps of a network, rounds of the
    /// light-driven learner ([`Progress`] says which). Every moment, learned grid and lit
    /// scene is tagged with it.
    pub steps: u64,
    /// The cells, by id (a new cell gets the next id; none is ever removed): a network's
    /// cells, or the light-driven learner's probes.
    pub cells: Vec<CellMark>,
    /// The network's edges that join two cells of one face of the visibility structure (for
    /// a network without faces: of one pair of surface edges), as cell ids. An edge across
    /// faces joins cells that never answer the same ray; drawn, those edges hide the kernel.
    /// Empty for the light-driven learner.
    pub face_edges: Vec<[u32; 2]>,
    /// Time spent learning since the fit started, pauses excluded: the timeline's clock.
    pub run_time: Duration,
    /// Steps or rounds, and what comes with each.
    pub progress: Progress,
}

/// What a learner's progress is made of: a network's steps, or the light-driven learner's
/// rounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// A network trained step by step ([`Growth::steps`] counts its steps).
    Steps {
        /// Rays cast for training so far.
        rays: u64,
        /// Sample sets so far (S₀ is set 0).
        sets: usize,
    },
    /// The light-driven learner, round by round ([`Growth::steps`] counts its rounds). Its
    /// probes sweep whole views: it casts no ray.
    Rounds {
        /// Probes with this index or more were placed by the newest round (the overlay rings
        /// them).
        newest_from: usize,
        /// The estimated relative L2 error of the solved `B − E` after the newest round.
        estimated_error: Option<f64>,
        /// Why it stopped, once it has (and every probe is shown).
        stopped: Option<LightStop>,
    },
}

impl Progress {
    /// Rays cast so far (none by the light-driven learner).
    #[must_use]
    pub fn rays(self) -> u64 {
        match self {
            Progress::Steps { rays, .. } => rays,
            Progress::Rounds { .. } => 0,
        }
    }
}

/// The learner's state as published at one moment.
#[derive(Clone, Debug)]
pub struct Status {
    /// The network.
    pub growth: Arc<Growth>,
    /// Every training sample's `(s, t)` and set, in the order they were drawn.
    pub samples: Prefix<SamplePoint>,
    /// The learning curve so far.
    pub history: Prefix<HistoryPoint>,
    /// The [`World`] it belongs to.
    pub world: u64,
    /// Whether it is training continuously.
    pub running: bool,
    /// Why it stopped, if it did.
    pub stopped: Option<StopReason>,
    /// Training steps per second over the last second.
    pub steps_per_s: f64,
    /// Final errors of the last finished fit (after the refit, if enabled).
    pub summary: Option<FitSummary>,
    /// Commands handled before this status was made.
    pub handled: u64,
    /// The running fit's parameters.
    pub params: FitParams,
    /// Faces of the visibility structure that hold a cell (visibility learners only).
    pub occupied_faces: Option<usize>,
}

/// The exact ζ at the kernel plot's resolution on screen (not the reference's): what the
/// kernel plot shows, one value per pixel.
#[derive(Debug)]
pub struct KernelGrid {
    /// The [`World`] it belongs to.
    pub world: u64,
    /// Its resolution.
    pub res: usize,
    /// ζ on the `res × res` grid, row-major, row ↔ s.
    pub values: Vec<f64>,
}

/// The learned ζ̃ on the display grid: what the learned and error panels show.
#[derive(Debug)]
pub struct LearnedGrid {
    /// The [`World`] it belongs to.
    pub world: u64,
    /// Training steps when it was computed.
    pub steps: u64,
    /// ζ̃ on the `APPROX_RES` grid, row-major, row ↔ s.
    pub values: Vec<f64>,
}

/// The learned ζ̃ on the display grid and the model it came from (kept only while it is the
/// newest: the timeline keeps the grid alone).
#[derive(Debug)]
pub struct Approx {
    /// The grid.
    pub grid: Arc<LearnedGrid>,
    /// The model, for the learned value under the pointer (`None` for the light-driven
    /// learner, whose grid is read instead).
    pub model: Option<LearnedKernel>,
}

/// The lit scene as last published.
#[derive(Clone, Debug)]
pub enum LitState {
    /// Nothing to show yet; what is being done.
    Pending(&'static str),
    /// The lit view is switched off.
    Off,
    /// The setup or a solve failed; why.
    Failed(String),
    /// A solve with the learned kernel.
    Ready(Arc<Lit>),
}

/// The scene lit by the learned kernel.
#[derive(Debug)]
pub struct Lit {
    /// The mesh and the exact B (its `world` is the id of the reference it belongs to).
    pub setup: Arc<LitSetup>,
    /// Training steps of the model solved.
    pub steps: u64,
    /// Its cells.
    pub cells: usize,
    /// B and its errors.
    pub solve: LitSolve,
    /// The error of every solve of this fit so far.
    pub history: Vec<LitPoint>,
}
