//! The training driver: sample sets, θ-driven resampling, growth, stopping rules, progress.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

use flatland_geom::{Kernel, Scene};
use flatland_solve::{
    Errors, InputFrame, Mesh, Reference, Representation, SolveError, SolveParams, Stop,
    TransferOperator,
};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sgcs::Network;

use crate::seeds;
use crate::visibility::{FaceId, FaceKey, Faces, Labeller, Sampler};
use crate::{FitError, FitParams, Gating, Resampling, Target};

mod checkpoint;
pub(crate) mod checks;
mod refit;
mod resample;
mod samples;

use crate::model::learned::{Geometry, unit_scale};
pub use crate::model::learned::{INPUT_DIM, LearnedKernel};
pub(crate) use checkpoint::Checkpoint;
use samples::*;

/// Why a fit stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The target cell count was reached and trained for one growth period.
    TargetCells,
    /// The held-out error reached the target.
    TargetError,
    /// The ray budget is spent.
    RayBudget,
    /// The step budget is spent.
    StepBudget,
    /// The caller's progress callback asked to stop.
    Interrupted,
    /// [`Target::Visibility`] on a scene where the geometry decides every visibility: the
    /// model is exact without learning anything.
    Exact,
    /// Growth at the worst sample ([`sgcs::Insertion::WorstSample`]) found no error left: every
    /// sample is predicted exactly and a θ scan found no place worth a ray. More cells would
    /// change nothing.
    Converged,
}

/// One training sample: where it is, what the network sees, the target, and its set.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub(crate) struct Sample {
    pub(crate) st: [f64; 2],
    pub(crate) xi: [f64; 4],
    /// What the network learns for this sample (ζ, k when the emission is factored out, or V).
    pub(crate) target: f64,
    /// Importance weight of the sample's error (1 unless [`FitParams::weighted`]).
    #[serde(default = "unit_scale")]
    pub(crate) weight: f64,
}

/// Per-cell statistics of the samples a cell won, for the (s, t) re-projection (paper Fig. 3c).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
struct CellStats {
    sum_s: f64,
    sum_t: f64,
    wins: u64,
}

/// A point of the learning curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryPoint {
    /// Training steps so far.
    pub steps: u64,
    /// Rays cast so far.
    pub rays: u64,
    /// Cells.
    pub cells: usize,
    /// Training samples.
    pub samples: usize,
    /// Held-out relative L2 error (on the first ≤ 1024 held-out points).
    pub rel_l2_heldout: f64,
}

/// One cell as a viewer or a figure needs it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellSnapshot {
    /// Mean (s, t) of the samples the cell won; `None` until it has won one.
    pub st: Option<[f64; 2]>,
    /// δ_c, in the unit-box input frame.
    pub width: f64,
    /// Whether the cell is critical (`τ_c > ω · mean τ`).
    pub critical: bool,
    /// τ_c.
    pub resource: f64,
    /// The output weight v_c.
    pub output: f64,
}

/// A cheap copy of the fit's state for progress displays.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Snapshot {
    /// Training steps so far.
    pub steps: u64,
    /// Rays cast for training so far.
    pub rays: u64,
    /// The cells, indexed by cell id.
    pub cells: Vec<CellSnapshot>,
    /// The network's edges, as cell ids.
    pub edges: Vec<[u32; 2]>,
    /// Every training sample's (s, t) and the index of the set that produced it.
    pub samples: Vec<([f32; 2], u32)>,
    /// Number of sample sets (S₀ is set 0).
    pub sets: usize,
    /// The learning curve so far.
    pub history: Vec<HistoryPoint>,
}

/// The figures a finished fit reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitSummary {
    /// Cells in the network.
    pub cells: usize,
    /// Training samples (= rays cast for training).
    pub samples: usize,
    /// Sample sets.
    pub sets: usize,
    /// Rays cast for training.
    pub rays: u64,
    /// Training steps.
    pub steps: u64,
    /// Errors of the final model.
    pub errors: Errors,
    /// Errors before the least-squares refit, when it ran.
    pub errors_before_refit: Option<Errors>,
    /// Wall time of the training and the refit (reference construction excluded), seconds.
    pub wall_s: f64,
    /// Of `wall_s`: the network's training steps and the driver around them, seconds.
    #[serde(default)]
    pub train_s: f64,
    /// Of `wall_s`: θ-resampling (drawing and scanning candidates, casting the rays), seconds.
    #[serde(default)]
    pub resample_s: f64,
    /// Of `wall_s`: the least-squares refit (0 without one), seconds.
    #[serde(default)]
    pub refit_s: f64,
    /// Building the reference the errors are measured against (not in `wall_s`), seconds.
    #[serde(default)]
    pub reference_s: f64,
    /// Measuring the final errors against the reference (not in `wall_s`), seconds.
    #[serde(default)]
    pub errors_s: f64,
    /// Why it stopped.
    pub stop: StopReason,
}

/// Growth periods (λ steps) without an insertion, each with a θ scan, after which a fit that
/// grows at its worst samples has converged (see [`StopReason::Converged`]).
const STALL_PERIODS: u64 = 20;

/// Every this-many-th training sample is held back to choose the refit's ridge weight.
const VALIDATION_STRIDE: usize = 2;
/// Ridge candidates: `params.ridge × 10^k` for k in 0..RIDGE_DECADES.
const RIDGE_DECADES: i32 = 7;

/// What [`Fit::refit`] chose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefitChoice {
    /// The ridge weight refitted with, or `None` when the learned weights validated better.
    pub ridge: Option<f64>,
    /// Relative L2 of the winner on the held-back training samples.
    pub validation_error: f64,
}

/// Held-out points used for the learning curve (the final errors use all of them).
const HISTORY_HELDOUT: usize = 1024;

/// A running fit of one scene's kernel. See the crate docs for the algorithm. A clone shares
/// the kernel and the reference and continues exactly as the original would.
#[derive(Clone)]
pub struct Fit {
    kernel: Arc<Kernel>,
    reference: Arc<Reference>,
    state: FitState,
    /// The face of each sample's ray (visibility models; derived from the samples, not saved).
    sample_faces: Vec<Option<FaceId>>,
}

/// Everything of a fit that a checkpoint saves; the kernel and the reference are rebuilt from
/// the scene the model embeds.
#[derive(Clone, Serialize, Deserialize)]
struct FitState {
    params: FitParams,
    model: LearnedKernel,
    samples: Vec<Sample>,
    /// `set_starts[j]` is the first sample of set j; sets are contiguous in `samples`.
    set_starts: Vec<usize>,
    cell_stats: Vec<CellStats>,
    rays: u64,
    steps_at_last_growth: u64,
    /// No resampling before this step (after a scan fell short, wait one growth period).
    resample_not_before: u64,
    train_rng: ChaCha8Rng,
    resample_rng: ChaCha8Rng,
    /// [`Target::Visibility`]: where samples and θ candidates are drawn.
    #[serde(default)]
    sampler: Option<Sampler>,
    history: Vec<HistoryPoint>,
    stop: Option<StopReason>,
    wall_s: f64,
    /// Of `wall_s`: time spent resampling and refitting.
    #[serde(default)]
    resample_s: f64,
    #[serde(default)]
    refit_s: f64,
}

impl Fit {
    /// Starts a fit: validates the parameters, draws S₀ (|S₀| rays) and builds the first simplex
    /// from three of its samples. `reference` is what errors are measured against; build it with
    /// [`Reference::new`] on the same kernel (its seed stream never meets the training streams).
    pub fn new(
        kernel: Arc<Kernel>,
        reference: Arc<Reference>,
        params: FitParams,
    ) -> Result<Fit, FitError> {
        params.validate()?;
        let scene = kernel.scene().clone();
        let frame = InputFrame::of(&scene);
        let mut initial_rng = seeds::stream(params.seed, seeds::FIT_INITIAL);
        let visibility = params.target == Target::Visibility;
        let sampler = if visibility {
            Sampler::new(&kernel, params.importance, &mut initial_rng)
        } else {
            None
        };
        let (mut samples, output_scale) = match (visibility, &sampler) {
            (true, Some(sampler)) => {
                let draws = draw_points(sampler, &kernel, params.initial_samples, &mut initial_rng);
                (visibility_samples(&kernel, frame, &params, &draws), 1.0)
            }
            // Visibility is known everywhere: nothing to learn (see `StopReason::Exact`).
            (true, None) => (Vec::new(), 1.0),
            (false, _) => {
                let points: Vec<[f64; 2]> = (0..params.initial_samples)
                    .map(|_| [initial_rng.random::<f64>(), initial_rng.random::<f64>()])
                    .collect();
                let samples = make_samples(&kernel, &scene, frame, params.target, 1.0, &points);
                let scale = rms_scale(samples.iter().map(|s| s.target));
                (samples, scale)
            }
        };
        for sample in &mut samples {
            sample.target /= output_scale;
        }
        let mut net_params = params.network;
        net_params.max_cells = params.target_cells;
        let simplex: Vec<Vec<f64>> = if samples.is_empty() {
            vec![
                vec![0.0; INPUT_DIM],
                vec![1.0, 0.0, 0.0, 0.0],
                vec![0.0, 1.0, 0.0, 0.0],
            ]
        } else {
            pick_simplex(&samples, &mut initial_rng)
        };
        let mut network = Network::new(net_params, INPUT_DIM, 1, &simplex)?;
        if net_params.insert_rule == sgcs::InsertRule::SampleTarget {
            // Cells inserted at a sample start from its target; so do the first three.
            for (c, xi) in simplex.iter().enumerate() {
                let sample = samples.iter().find(|s| s.xi[..] == xi[..]);
                if let Some(sample) = sample {
                    network.set_output(c, &[sample.target])?;
                }
            }
        }
        let rays = rays_of(&kernel, &samples);
        let model = LearnedKernel::assemble(
            scene,
            frame,
            network,
            emission_factor(&kernel, params.target),
            output_scale,
            params.target,
            params.gating,
            visibility.then(|| Arc::clone(&kernel)),
        );
        let stop = (visibility && sampler.is_none()).then_some(StopReason::Exact);
        let set_starts = if samples.is_empty() {
            Vec::new()
        } else {
            vec![0]
        };
        let mut fit = Fit {
            kernel,
            reference,
            sample_faces: Vec::new(),
            state: FitState {
                cell_stats: vec![CellStats::default(); model.network.len()],
                model,
                samples,
                set_starts,
                rays,
                steps_at_last_growth: 0,
                resample_not_before: 0,
                train_rng: seeds::stream(params.seed, seeds::FIT_TRAIN),
                resample_rng: seeds::stream(params.seed, seeds::FIT_RESAMPLE),
                sampler,
                history: Vec::new(),
                stop,
                wall_s: 0.0,
                resample_s: 0.0,
                refit_s: 0.0,
                params,
            },
        };
        fit.index_sample_faces();
        Ok(fit)
    }

    /// Numbers the faces of the samples not yet numbered (see [`LearnedKernel::intern_faces`]).
    fn index_sample_faces(&mut self) {
        let from = self.sample_faces.len();
        let faces = self.state.model.intern_faces(&self.state.samples[from..]);
        self.sample_faces.extend(faces);
    }

    /// The parameters.
    pub fn params(&self) -> &FitParams {
        &self.state.params
    }
    /// The learned kernel so far.
    pub fn model(&self) -> &LearnedKernel {
        &self.state.model
    }
    /// The network so far.
    pub fn network(&self) -> &Network {
        &self.state.model.network
    }
    /// The exact kernel being learned.
    pub fn kernel(&self) -> &Arc<Kernel> {
        &self.kernel
    }
    /// The reference errors are measured against.
    pub fn reference(&self) -> &Arc<Reference> {
        &self.reference
    }
    /// Rays cast for training so far.
    pub fn rays(&self) -> u64 {
        self.state.rays
    }
    /// Training samples so far.
    pub fn sample_count(&self) -> usize {
        self.state.samples.len()
    }
    /// Sample sets so far.
    pub fn set_count(&self) -> usize {
        self.state.set_starts.len()
    }
    /// Training steps so far.
    pub fn steps(&self) -> u64 {
        self.state.model.network.steps()
    }
    /// Why the fit stopped, once it has.
    pub fn stopped(&self) -> Option<StopReason> {
        self.state.stop
    }
    /// The learning curve so far.
    pub fn history(&self) -> &[HistoryPoint] {
        &self.state.history
    }

    /// One training step: resample if `|A| / |S| > ψ`, draw a set uniformly and a sample from
    /// it, adapt the network, record who won. Returns the stop reason once a rule fires.
    pub fn step(&mut self) -> Option<StopReason> {
        if self.state.stop.is_some() {
            return self.state.stop;
        }
        let steps = self.steps();
        let cells = self.state.model.network.len();
        let p = &self.state.params;
        // Growth at the worst sample waits while every sample is predicted exactly; then only a
        // θ scan can show where the model is still wrong, whatever |A| / |S|.
        let lambda = u64::from(p.network.lambda);
        let stalled = p.network.insertion == sgcs::Insertion::WorstSample
            && cells < p.target_cells
            && steps >= self.state.steps_at_last_growth + 2 * lambda
            && steps.is_multiple_of(lambda);
        if stalled && steps >= self.state.steps_at_last_growth + STALL_PERIODS * lambda {
            // Every scan since the last growth found only samples predicted exactly.
            self.state.stop = Some(StopReason::Converged);
            return self.state.stop;
        }
        if (stalled || cells as f64 > p.psi * self.state.samples.len() as f64)
            && steps >= self.state.resample_not_before
            && self.state.rays < p.ray_budget
        {
            let before = self.state.samples.len();
            self.resample();
            if stalled && self.state.samples.len() == before {
                self.state.stop = Some(StopReason::Converged);
                return self.state.stop;
            }
        }
        let set = self
            .state
            .train_rng
            .random_range(0..self.state.set_starts.len());
        let start = self.state.set_starts[set];
        let end = self
            .state
            .set_starts
            .get(set + 1)
            .copied()
            .unwrap_or(self.state.samples.len());
        let index = self.state.train_rng.random_range(start..end);
        let sample = self.state.samples[index];
        let outcome = self.train_on(&sample, self.sample_faces[index]);
        if let Some(new) = outcome.inserted {
            debug_assert_eq!(new, self.state.cell_stats.len());
            self.state.cell_stats.push(CellStats::default());
            self.state.steps_at_last_growth = self.steps();
        }
        let stats = &mut self.state.cell_stats[outcome.bmu];
        stats.sum_s += sample.st[0];
        stats.sum_t += sample.st[1];
        stats.wins += 1;

        let steps = self.steps();
        if self.state.params.eval_every > 0 && steps.is_multiple_of(self.state.params.eval_every) {
            self.record_history();
        }
        self.state.stop = self.stop_reason();
        self.state.stop
    }

    /// One network step on `sample` (whose ray is in `face`): gated by that face for a
    /// visibility model (whose cell faces then follow the cells that moved), plain otherwise.
    fn train_on(&mut self, sample: &Sample, face: Option<FaceId>) -> sgcs::StepOutcome {
        let LearnedKernel {
            network,
            geometry,
            gating,
            ..
        } = &mut self.state.model;
        let gate = match (geometry.as_ref(), face) {
            (Some(g), Some(face)) if *gating != Gating::Off => Some(g.faces.gate_of(face, *gating)),
            _ => None,
        };
        let (xi, target, weight) = (&sample.xi, [sample.target], sample.weight);
        let outcome = match &gate {
            Some(gate) => network.try_step_gated(xi, &target, weight, gate),
            None => network.try_step_gated(xi, &target, weight, &sgcs::Open),
        }
        .expect("training samples are finite and bounded");
        self.state.model.relabel_moved();
        outcome
    }

    fn stop_reason(&self) -> Option<StopReason> {
        let p = &self.state.params;
        let steps = self.steps();
        let lambda = u64::from(p.network.lambda);
        if self.state.model.network.len() >= p.target_cells
            && steps - self.state.steps_at_last_growth >= lambda
        {
            return Some(StopReason::TargetCells);
        }
        if p.target_error > 0.0
            && self
                .state
                .history
                .last()
                .is_some_and(|h| h.steps == steps && h.rel_l2_heldout <= p.target_error)
        {
            return Some(StopReason::TargetError);
        }
        if self.state.rays >= p.ray_budget {
            return Some(StopReason::RayBudget);
        }
        if steps >= p.max_steps {
            return Some(StopReason::StepBudget);
        }
        None
    }

    /// Trains until a stopping rule fires, calling `progress` every `every` steps (and once at
    /// the end); the callback stops the fit by returning `ControlFlow::Break`
    /// ([`StopReason::Interrupted`]). The state is then exactly what a checkpoint saves.
    pub fn train(
        &mut self,
        every: u64,
        mut progress: impl FnMut(&Fit) -> ControlFlow<()>,
    ) -> StopReason {
        let started = Instant::now();
        let every = every.max(1);
        let reason = loop {
            if let Some(reason) = self.step() {
                break reason;
            }
            if self.steps().is_multiple_of(every) && progress(self).is_break() {
                self.state.stop = Some(StopReason::Interrupted);
                break StopReason::Interrupted;
            }
        };
        self.state.wall_s += started.elapsed().as_secs_f64();
        let _ = progress(self);
        reason
    }

    /// [`train`](Fit::train), then [`finish`](Fit::finish): the whole fit.
    pub fn run(
        &mut self,
        every: u64,
        progress: impl FnMut(&Fit) -> ControlFlow<()>,
    ) -> Result<FitSummary, FitError> {
        self.train(every, progress);
        self.finish()
    }

    /// Refits (if enabled) and measures the final errors. Idempotent apart from the refit.
    pub fn finish(&mut self) -> Result<FitSummary, FitError> {
        self.finish_with(|_| ControlFlow::Continue(()))
    }

    /// [`finish`](Fit::finish), telling `progress` how the refit goes; the callback can stop
    /// the refit ([`FitError::Interrupted`], the learned weights stay as they were).
    pub fn finish_with(
        &mut self,
        progress: impl FnMut(sgcs::RefitProgress) -> ControlFlow<()>,
    ) -> Result<FitSummary, FitError> {
        let mut errors_before_refit = None;
        let mut errors_s = 0.0;
        if self.state.params.refit && self.state.params.target != Target::Visibility {
            let started = Instant::now();
            errors_before_refit = Some(self.reference.errors(&self.state.model));
            errors_s += started.elapsed().as_secs_f64();
            self.refit_with_progress(progress)?;
        }
        let started = Instant::now();
        let errors = self.reference.errors(&self.state.model);
        errors_s += started.elapsed().as_secs_f64();
        let s = &self.state;
        Ok(FitSummary {
            cells: s.model.network.len(),
            samples: s.samples.len(),
            sets: s.set_starts.len(),
            rays: s.rays,
            steps: self.steps(),
            errors,
            errors_before_refit,
            wall_s: s.wall_s,
            train_s: (s.wall_s - s.resample_s - s.refit_s).max(0.0),
            resample_s: s.resample_s,
            refit_s: s.refit_s,
            reference_s: self.reference.build_s(),
            errors_s,
            stop: s.stop.unwrap_or(StopReason::Interrupted),
        })
    }

    fn record_history(&mut self) {
        let (points, values) = self.reference.heldout();
        let n = points.len().min(HISTORY_HELDOUT);
        let predicted: Vec<f64> = points[..n]
            .par_iter()
            .map(|&[s, t]| self.state.model.zeta(s, t))
            .collect();
        self.state.history.push(HistoryPoint {
            steps: self.steps(),
            rays: self.state.rays,
            cells: self.state.model.network.len(),
            samples: self.state.samples.len(),
            rel_l2_heldout: flatland_solve::relative_l2(&predicted, &values[..n]),
        });
    }

    /// The re-projected (s, t) of every cell (paper Fig. 3c); `None` for a cell that never won.
    pub fn cell_st(&self) -> Vec<Option<[f64; 2]>> {
        self.state
            .cell_stats
            .iter()
            .map(|c| (c.wins > 0).then(|| [c.sum_s / c.wins as f64, c.sum_t / c.wins as f64]))
            .collect()
    }

    /// A cheap copy of the state for a progress display or the viewer.
    pub fn snapshot(&self) -> Snapshot {
        let net = &self.state.model.network;
        let critical = net.critical_cells(self.state.params.omega);
        let st = self.cell_st();
        let cells = (0..net.len())
            .map(|c| CellSnapshot {
                st: st[c],
                width: net.width(c),
                critical: critical[c],
                resource: net.resource(c),
                output: net.output(c)[0],
            })
            .collect();
        let mut samples = Vec::with_capacity(self.state.samples.len());
        for (set, &start) in self.state.set_starts.iter().enumerate() {
            let end = self
                .state
                .set_starts
                .get(set + 1)
                .copied()
                .unwrap_or(self.state.samples.len());
            samples.extend(
                self.state.samples[start..end]
                    .iter()
                    .map(|s| ([s.st[0] as f32, s.st[1] as f32], set as u32)),
            );
        }
        Snapshot {
            steps: self.steps(),
            rays: self.state.rays,
            cells,
            edges: net
                .edges()
                .into_iter()
                .map(|(a, b)| [a as u32, b as u32])
                .collect(),
            samples,
            sets: self.state.set_starts.len(),
            history: self.state.history.clone(),
        }
    }

    /// Continues learning on a changed scene (the representation stays adaptive: a changed scene is learned on, not from scratch).
    ///
    /// The network keeps its cells, weights and counters and the input frame stays put (so the
    /// cells keep their meaning); the old samples describe the old scene and are dropped, and a
    /// new S₀ of `max(|S₀|, |A|/ψ)` uniform samples is drawn from the new kernel.
    pub fn set_kernel(&mut self, kernel: Arc<Kernel>, reference: Arc<Reference>) {
        let scene = kernel.scene().clone();
        let p = self.state.params;
        let n = (p.initial_samples)
            .max((self.state.model.network.len() as f64 / p.psi).ceil() as usize);
        let frame = self.state.model.frame;
        self.state.stop = None;
        self.state.samples = if p.target == Target::Visibility {
            let rng = &mut self.state.resample_rng;
            self.state.sampler = Sampler::new(&kernel, p.importance, rng);
            match &self.state.sampler {
                Some(sampler) => {
                    visibility_samples(&kernel, frame, &p, &draw_points(sampler, &kernel, n, rng))
                }
                None => {
                    self.state.stop = Some(StopReason::Exact);
                    Vec::new()
                }
            }
        } else {
            let points: Vec<[f64; 2]> = (0..n)
                .map(|_| {
                    [
                        self.state.resample_rng.random::<f64>(),
                        self.state.resample_rng.random::<f64>(),
                    ]
                })
                .collect();
            make_samples(
                &kernel,
                &scene,
                frame,
                p.target,
                self.state.model.output_scale,
                &points,
            )
        };
        self.state.rays += rays_of(&kernel, &self.state.samples);
        self.state.set_starts = if self.state.samples.is_empty() {
            Vec::new()
        } else {
            vec![0]
        };
        self.state.cell_stats = vec![CellStats::default(); self.state.model.network.len()];
        self.state.model.scene = scene;
        self.state.model.emission_factor = emission_factor(&kernel, p.target);
        if p.target == Target::Visibility {
            // The cells keep their places and values; their faces are those of the new scene.
            self.state.model.geometry = Some(Geometry {
                kernel: Arc::clone(&kernel),
                labeller: Labeller::new(&kernel, frame),
                faces: Faces::default(),
            });
            let all: Vec<usize> = (0..self.state.model.network.len()).collect();
            self.state.model.relabel(&all);
        }
        self.kernel = kernel;
        self.reference = reference;
        self.state.steps_at_last_growth = self.steps();
        self.sample_faces.clear();
        self.index_sample_faces();
    }

    /// Changes the parameters of a running fit (the viewer's controls). What the network
    /// learns (`target`, `gating`) is fixed for a fit: changing it needs a new [`Fit`].
    pub fn set_params(&mut self, params: FitParams) -> Result<(), FitError> {
        params.validate()?;
        let old = &self.state.params;
        if (params.target, params.gating) != (old.target, old.gating) {
            return Err(FitError::InvalidParameter {
                name: "target",
                value: format!("{:?} with gating {:?}", params.target, params.gating),
                valid: "the fit's own target and gating (start a new fit to change them)",
            });
        }
        let mut net_params = params.network;
        net_params.max_cells = params.target_cells;
        self.state.model.network.set_params(net_params)?;
        self.state.params = params;
        self.state.stop = None;
        Ok(())
    }
}

/// A fit is its model: every method asks the [`LearnedKernel`] it trains.
impl Representation for Fit {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        self.state.model.zeta(s, t)
    }
    fn basis_functions(&self) -> Option<usize> {
        self.state.model.basis_functions()
    }
    fn memory_bytes(&self) -> usize {
        self.state.model.memory_bytes()
    }
    fn scene_fingerprint(&self) -> Option<u64> {
        self.state.model.scene_fingerprint()
    }
    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        self.state.model.operator(mesh, params, stop)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Preset;
    use flatland_solve::{density_ratio, discontinuity_mask};

    const FIG3: &str = flatland_geom::bundled::SCENES[0].2;
    const MAZE: &str = flatland_geom::bundled::SCENES[2].2;
    const BOX: &str = flatland_geom::bundled::SCENES[1].2;

    fn fig3() -> Arc<Kernel> {
        Arc::new(Kernel::new(Scene::from_ron_str(FIG3).unwrap()))
    }

    fn maze() -> Arc<Kernel> {
        Arc::new(Kernel::new(Scene::from_ron_str(MAZE).unwrap()))
    }

    fn fit_with(kernel: &Arc<Kernel>, params: FitParams) -> Fit {
        let reference = Arc::new(Reference::new(kernel, 64, 2048, crate::REFERENCE_SEED));
        Fit::new(Arc::clone(kernel), reference, params).unwrap()
    }

    fn paper(cells: usize) -> FitParams {
        preset(Preset::Paper, cells)
    }

    fn preset(preset: Preset, cells: usize) -> FitParams {
        FitParams {
            target_cells: cells,
            eval_every: 0,
            ..preset.params()
        }
    }

    fn run(fit: &mut Fit) -> FitSummary {
        fit.run(1000, |_| ControlFlow::Continue(())).unwrap()
    }

    #[test]
    fn same_seed_same_fit() {
        let kernel = maze();
        for p in Preset::ALL {
            let a = run(&mut fit_with(&kernel, preset(p, 40)));
            let b = run(&mut fit_with(&kernel, preset(p, 40)));
            assert_eq!((a.errors, a.rays, a.steps), (b.errors, b.rays, b.steps));
            let c = run(&mut fit_with(
                &kernel,
                FitParams {
                    seed: 2,
                    ..preset(p, 40)
                },
            ));
            assert_ne!(
                a.errors, c.errors,
                "{p:?}: another seed must give another fit"
            );
        }
    }

    #[test]
    fn resume_continues_to_the_same_result() {
        for (p, kernel, cells) in [(Preset::Paper, fig3(), 60), (Preset::Default, maze(), 120)] {
            let mut full = fit_with(&kernel, preset(p, cells));
            let uninterrupted = run(&mut full);

            let mut first = fit_with(&kernel, preset(p, cells));
            let reason = first.train(500, |f| {
                if f.steps() >= 7_000 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
            assert_eq!(reason, StopReason::Interrupted);
            let dir = std::env::temp_dir().join(format!(
                "flatland-resume-{}-{}",
                std::process::id(),
                p.name()
            ));
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("fit.ckpt.json");
            first.save_checkpoint(&path).unwrap();
            let mut resumed = Fit::resume(&path, flatland_geom::KernelParams::default()).unwrap();
            assert_eq!(resumed.steps(), first.steps());
            let summary = run(&mut resumed);
            std::fs::remove_dir_all(&dir).unwrap();
            assert_eq!(
                (summary.rays, summary.steps, summary.cells, summary.samples),
                (
                    uninterrupted.rays,
                    uninterrupted.steps,
                    uninterrupted.cells,
                    uninterrupted.samples
                ),
                "{p:?}"
            );
            // serde_json's float_roundtrip makes the checkpoint exact: the same fit to the last
            // bit (a visibility model rebuilds its cells' faces from their positions).
            assert_eq!(summary.errors, uninterrupted.errors, "{p:?}");
        }
    }

    /// The default learner on the paper's scene: every face of the blocker's shadows is found,
    /// the learned kernel is then exact, and the fit stops by itself.
    #[test]
    fn default_learner_converges_to_the_exact_kernel_on_fig3() {
        let kernel = fig3();
        let mut fit = fit_with(&kernel, preset(Preset::Default, 400));
        let summary = run(&mut fit);
        assert_eq!(summary.stop, StopReason::Converged, "{summary:?}");
        assert!(summary.cells < 400, "{summary:?}");
        assert!(
            summary.errors.grid < 1e-9 && summary.errors.heldout < 1e-9,
            "{summary:?}"
        );
        // Exactly the kernel, also between grid points and on pairs learned or known.
        let mut r = crate::seeds::stream(99, 0);
        for _ in 0..2000 {
            let (s, t) = (r.random::<f64>(), r.random::<f64>());
            assert_eq!(fit.model().zeta(s, t), kernel.zeta(s, t), "({s}, {t})");
        }
    }

    /// Cells stay filed under the face their centre is in after every step, and the learned
    /// kernel beats hierarchical radiosity by far at the same budget (R4).
    #[test]
    fn default_learner_keeps_cells_in_their_faces_and_beats_hr_on_maze() {
        let kernel = maze();
        let mut fit = fit_with(&kernel, preset(Preset::Default, 150));
        while fit.step().is_none() {
            if fit.steps().is_multiple_of(97) || fit.steps().is_multiple_of(300) {
                fit.model().check_invariants().unwrap();
            }
        }
        fit.model().check_invariants().unwrap();
        let learned = fit.finish().unwrap().errors;
        let hr = flatland_baselines::run_hr_at_budget(
            &kernel,
            150,
            1,
            &flatland_baselines::HrParams::default(),
        )
        .unwrap();
        let hr = fit.reference().errors(&hr.approx);
        // Measured 0.05 vs 0.5: demand half of HR's error.
        assert!(
            learned.grid < 0.5 * hr.grid && learned.heldout < 0.5 * hr.heldout,
            "learned {learned:?}, HR {hr:?}"
        );
    }

    /// A closed room without occluders: geometry decides every visibility, nothing is learned
    /// and the kernel is exact.
    #[test]
    fn a_scene_without_shadows_needs_no_learning() {
        let kernel = Arc::new(Kernel::new(Scene::from_ron_str(BOX).unwrap()));
        let mut fit = fit_with(&kernel, preset(Preset::Default, 50));
        let summary = run(&mut fit);
        assert_eq!(summary.stop, StopReason::Exact);
        assert_eq!((summary.rays, summary.samples), (0, 0));
        assert_eq!((summary.errors.grid, summary.errors.heldout), (0.0, 0.0));
    }

    /// A visibility model saved and loaded predicts exactly the same (its faces are rebuilt).
    #[test]
    fn visibility_models_round_trip_through_model_files() {
        let kernel = maze();
        let mut fit = fit_with(&kernel, preset(Preset::Default, 60));
        let summary = run(&mut fit);
        let dir = std::env::temp_dir().join(format!("flatland-vismodel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("model.json");
        let file = crate::ModelFile::new(fit.model().clone(), *fit.params(), Some(summary));
        file.save(&path).unwrap();
        let loaded = crate::ModelFile::load(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        loaded.model.check_invariants().unwrap();
        let mut r = crate::seeds::stream(5, 0);
        for _ in 0..3000 {
            let (s, t) = (r.random::<f64>(), r.random::<f64>());
            assert_eq!(
                loaded.model.zeta(s, t).to_bits(),
                fit.model().zeta(s, t).to_bits()
            );
        }
    }

    #[test]
    fn checkpoints_of_another_kind_or_version_are_refused() {
        let dir = std::env::temp_dir().join(format!("flatland-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cases = [
            (
                r#"{"format":"flatland-checkpoint","version":99}"#,
                "version",
            ),
            (
                r#"{"format":"something-else","version":1}"#,
                "not a flatland checkpoint",
            ),
            ("{ truncated", "line 1"),
            (
                r#"{"format":"flatland-checkpoint","version":1,"params":{}}"#,
                "malformed",
            ),
        ];
        for (i, (text, expected)) in cases.iter().enumerate() {
            let path = dir.join(format!("{i}.json"));
            std::fs::write(&path, text).unwrap();
            let err = Fit::resume(&path, flatland_geom::KernelParams::default())
                .err()
                .expect("must be refused")
                .to_string();
            assert!(
                err.contains(expected) && err.contains(&format!("{i}.json")),
                "{err}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn rays_samples_and_stopping_rules() {
        let kernel = fig3();
        let mut fit = fit_with(&kernel, paper(100));
        let summary = run(&mut fit);
        assert_eq!(summary.stop, StopReason::TargetCells);
        assert_eq!(summary.cells, 100);
        // A sample costs a ray only where geometry cannot decide visibility (on fig3: the
        // pairs the blocker shadows); R5: ψ = 0.05 keeps ≈ 20 samples per cell.
        assert!(
            summary.rays > 0 && summary.rays < summary.samples as u64,
            "{summary:?}"
        );
        let per_cell = summary.samples as f64 / summary.cells as f64;
        assert!(
            (15.0..=25.0).contains(&per_cell),
            "{per_cell} samples per cell"
        );

        let budget = run(&mut fit_with(
            &kernel,
            FitParams {
                ray_budget: 400,
                ..paper(100)
            },
        ));
        assert_eq!(budget.stop, StopReason::RayBudget);
        assert!(budget.rays <= 400, "{}", budget.rays);
        let steps = run(&mut fit_with(
            &kernel,
            FitParams {
                max_steps: 1234,
                ..paper(100)
            },
        ));
        assert_eq!((steps.stop, steps.steps), (StopReason::StepBudget, 1234));
        let target = run(&mut fit_with(
            &kernel,
            FitParams {
                target_error: 0.9,
                eval_every: 500,
                ..paper(100)
            },
        ));
        assert_eq!(target.stop, StopReason::TargetError);
    }

    #[test]
    fn r1_cells_concentrate_near_discontinuities() {
        let kernel = fig3();
        let mut fit = fit_with(&kernel, paper(200));
        run(&mut fit);
        // Jumps of ζ larger than a tenth of its 99th percentile, on a 128² grid, ±2 cells.
        let res = 128;
        let grid = kernel.grid(res, true);
        let mut sorted = grid.clone();
        sorted.sort_by(f64::total_cmp);
        let mask = discontinuity_mask(&grid, res, 0.1 * sorted[sorted.len() * 99 / 100], 2);
        let cells: Vec<[f64; 2]> = fit.cell_st().into_iter().flatten().collect();
        let ratio = density_ratio(&mask, res, &cells).unwrap();
        // Measured ≈ 9 on fig3 at 200 cells (≈ 4 with uniform resampling): demand 3.
        assert!(
            ratio > 3.0,
            "cells per unit area near / away from discontinuities: {ratio}"
        );
    }

    #[test]
    fn r2_subdivision_gives_the_same_error_and_cells() {
        let kernel = fig3();
        let fine = Arc::new(Kernel::new(kernel.scene().subdivide(1000).unwrap()));
        for p in Preset::ALL {
            let coarse = run(&mut fit_with(&kernel, preset(p, 80)));
            let subdivided = run(&mut fit_with(&fine, preset(p, 80)));
            assert_eq!(coarse.cells, subdivided.cells, "{p:?}");
            for (a, b) in [
                (coarse.errors.grid, subdivided.errors.grid),
                (coarse.errors.heldout, subdivided.errors.heldout),
            ] {
                assert!(
                    (a - b).abs() <= 0.1 * a.max(1e-6),
                    "{p:?}: ×1 error {a} vs ×1000 error {b}"
                );
            }
        }
    }

    #[test]
    fn theta_resampling_beats_uniform_at_the_same_ray_budget_on_fig3() {
        let kernel = fig3();
        let (mut theta, mut uniform) = ((0.0, 0), (0.0, 0));
        for seed in 1..=3 {
            let t = run(&mut fit_with(&kernel, FitParams { seed, ..paper(200) }));
            let u = run(&mut fit_with(
                &kernel,
                FitParams {
                    seed,
                    resampling: Resampling::Uniform,
                    ..paper(200)
                },
            ));
            theta = (theta.0 + t.errors.heldout, theta.1 + t.rays);
            uniform = (uniform.0 + u.errors.heldout, uniform.1 + u.rays);
        }
        // Both stop at 200 cells with ≈ 20 samples per cell; θ's short scans may top a set up
        // later, so allow it 2 % more rays.
        assert!(
            theta.1 as f64 <= 1.02 * uniform.1 as f64,
            "{theta:?} vs {uniform:?} rays"
        );
        // Measured: summed held-out errors 1.29 vs 1.58 over seeds 1-3; demand a 10 % margin.
        assert!(
            theta.0 < 0.9 * uniform.0,
            "θ {theta:?} vs uniform {uniform:?}"
        );
    }

    #[test]
    fn a_moved_blocker_is_learned_from_the_current_state() {
        let kernel = fig3();
        for p in Preset::ALL {
            let mut fit = fit_with(&kernel, preset(p, 80));
            run(&mut fit);
            let scene = kernel.scene();
            let blocker = scene
                .edges()
                .iter()
                .position(|e| e.role == flatland_geom::Role::Blocker)
                .unwrap();
            let mut moved = scene.edges()[blocker];
            moved.a.x += 0.8;
            moved.b.x += 0.8;
            let new_kernel = Arc::new(Kernel::new(scene.with_edge(blocker, moved).unwrap()));
            let reference = Arc::new(Reference::new(&new_kernel, 64, 2048, 1));
            let cells_before = fit.network().len();
            fit.set_kernel(Arc::clone(&new_kernel), Arc::clone(&reference));
            let stale = reference.errors(fit.model());
            fit.set_params(preset(p, 100)).unwrap();
            let after = run(&mut fit);
            assert!(after.cells >= cells_before && after.cells <= 100, "{p:?}");
            assert!(
                after.errors.heldout < stale.heldout,
                "{p:?}: {stale:?} -> {:?}",
                after.errors
            );
        }
    }

    #[test]
    fn emission_scale_does_not_change_the_learning() {
        let scene = fig3().scene().clone();
        let scaled = |factor: f64| {
            let edges = scene.edges().iter().map(|e| flatland_geom::Edge {
                emission: e.emission * factor,
                ..*e
            });
            Arc::new(Kernel::new(Scene::new(edges.collect()).unwrap()))
        };
        for p in Preset::ALL {
            let base = run(&mut fit_with(&scaled(1.0), preset(p, 40)));
            for factor in [1e-200, 1e-12, 1e12, 1e200] {
                let other = run(&mut fit_with(&scaled(factor), preset(p, 40)));
                for (a, b) in [
                    (base.errors.grid, other.errors.grid),
                    (base.errors.heldout, other.errors.heldout),
                ] {
                    // Equal up to rounding (the targets are divided by a different scale).
                    assert!(
                        (a - b).abs() <= 1e-4 * a.max(1e-9),
                        "{p:?}: emission ×{factor:e}: {b} vs {a}"
                    );
                }
            }
        }
    }
}
