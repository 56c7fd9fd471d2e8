//! What a fit holds between steps, and its saved form: the checkpoint file, the fields it
//! writes, read back as they were written.

use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::source::Source;
use super::{HistoryPoint, StopReason};
use crate::model::Sample;
use crate::visibility::Sampler;
use crate::{FitParams, Head, LearnedKernel};

/// Per-cell statistics of the samples a cell won, for the (s, t) re-projection (paper Fig. 3c).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub(crate) struct CellStats {
    pub(crate) sum_s: f64,
    pub(crate) sum_t: f64,
    pub(crate) wins: u64,
}

/// Everything of a fit that a checkpoint saves; the kernel and the reference are rebuilt from
/// the scene the model embeds.
#[derive(Clone)]
pub(crate) struct FitState {
    /// The parameters as given (what files hold); the fit keeps them checked beside.
    pub(crate) params: FitParams,
    pub(crate) model: LearnedKernel,
    /// Where new samples come from.
    pub(crate) source: Source,
    pub(crate) samples: Vec<Sample>,
    /// `set_starts[j]` is the first sample of set j; sets are contiguous in `samples`.
    pub(crate) set_starts: Vec<usize>,
    pub(crate) cell_stats: Vec<CellStats>,
    pub(crate) rays: u64,
    pub(crate) steps_at_last_growth: u64,
    /// No resampling before this step (after a scan fell short, wait one growth period).
    pub(crate) resample_not_before: u64,
    pub(crate) train_rng: ChaCha8Rng,
    pub(crate) resample_rng: ChaCha8Rng,
    pub(crate) history: Vec<HistoryPoint>,
    pub(crate) stop: Option<StopReason>,
    pub(crate) wall_s: f64,
    /// Of `wall_s`: time spent resampling and refitting.
    pub(crate) resample_s: f64,
    pub(crate) refit_s: f64,
}

/// The state as a checkpoint writes it (borrowed): its fields in their order, the source as
/// the visibility learner's sampler.
#[derive(Serialize)]
pub(super) struct SavedState<'a> {
    params: &'a FitParams,
    model: &'a LearnedKernel,
    samples: &'a [Sample],
    set_starts: &'a [usize],
    cell_stats: &'a [CellStats],
    rays: u64,
    steps_at_last_growth: u64,
    resample_not_before: u64,
    train_rng: &'a ChaCha8Rng,
    resample_rng: &'a ChaCha8Rng,
    sampler: Option<&'a Sampler>,
    history: &'a [HistoryPoint],
    stop: Option<StopReason>,
    wall_s: f64,
    resample_s: f64,
    refit_s: f64,
}

/// The `format` field of checkpoint files.
pub const CHECKPOINT_FORMAT: &str = "flatland-checkpoint";
/// The checkpoint version this build reads and writes.
pub const CHECKPOINT_VERSION: u32 = 1;

/// A checkpoint file: a header that identifies it, then the state (borrowed when written).
#[derive(Serialize, Deserialize)]
pub(crate) struct Checkpoint<S> {
    pub(crate) format: String,
    pub(crate) version: u32,
    pub(crate) scene_fingerprint: String,
    pub(crate) reference_res: usize,
    pub(crate) reference_heldout: usize,
    pub(crate) state: S,
}

/// The state as a checkpoint holds it, before it is checked ([`super::checks::checkpoint`]) and
/// its source rebuilt from the parameters' head.
#[derive(Deserialize)]
pub(crate) struct LoadedState {
    pub(crate) params: FitParams,
    pub(crate) model: LearnedKernel,
    pub(crate) samples: Vec<Sample>,
    pub(crate) set_starts: Vec<usize>,
    pub(crate) cell_stats: Vec<CellStats>,
    pub(crate) rays: u64,
    pub(crate) steps_at_last_growth: u64,
    pub(crate) resample_not_before: u64,
    pub(crate) train_rng: ChaCha8Rng,
    pub(crate) resample_rng: ChaCha8Rng,
    /// The visibility learner's sampler (absent for the others, and when nothing varies).
    #[serde(default)]
    pub(crate) sampler: Option<Sampler>,
    pub(crate) history: Vec<HistoryPoint>,
    pub(crate) stop: Option<StopReason>,
    pub(crate) wall_s: f64,
    #[serde(default)]
    pub(crate) resample_s: f64,
    #[serde(default)]
    pub(crate) refit_s: f64,
}

impl FitState {
    /// The saved form, borrowing everything.
    pub(super) fn saved(&self) -> SavedState<'_> {
        SavedState {
            params: &self.params,
            model: &self.model,
            samples: &self.samples,
            set_starts: &self.set_starts,
            cell_stats: &self.cell_stats,
            rays: self.rays,
            steps_at_last_growth: self.steps_at_last_growth,
            resample_not_before: self.resample_not_before,
            train_rng: &self.train_rng,
            resample_rng: &self.resample_rng,
            sampler: self.source.sampler(),
            history: &self.history,
            stop: self.stop,
            wall_s: self.wall_s,
            resample_s: self.resample_s,
            refit_s: self.refit_s,
        }
    }
}

impl LoadedState {
    /// The state, its source rebuilt from `head` and the saved sampler; the error names what
    /// does not belong to that head.
    pub(super) fn into_state(self, head: &Head) -> Result<FitState, String> {
        let source = Source::resumed(head, self.sampler)?;
        Ok(FitState {
            params: self.params,
            model: self.model,
            source,
            samples: self.samples,
            set_starts: self.set_starts,
            cell_stats: self.cell_stats,
            rays: self.rays,
            steps_at_last_growth: self.steps_at_last_growth,
            resample_not_before: self.resample_not_before,
            train_rng: self.train_rng,
            resample_rng: self.resample_rng,
            history: self.history,
            stop: self.stop,
            wall_s: self.wall_s,
            resample_s: self.resample_s,
            refit_s: self.refit_s,
        })
    }
}
