//! The learner's thread and the UI's end of it. The thread owns the running learner (the
//! [`flatland_light::LightFit`] or a network's [`kernel_fit::Fit`]); the UI talks to it with [`Command`]s and reads what it publishes from a [`Mailbox`] with
//! `try_lock`, so a frame never waits for training. Each publication also wakes whoever waits
//! for one ([`WorkerHandle::wait`]: tests, which wait on what the learner says instead of
//! sleeping), and every status says how many commands the learner has handled, so the UI knows
//! when it has caught up.
//!
//! The thread itself is in [`learner`], what it publishes in [`published`], which network edges
//! join cells of one face in [`faces`].

mod faces;
mod learner;
mod published;

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Sender};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use flatland_geom::Scene;
use flatland_solve::Representation;
use kernel_fit::{FitParams, LearnedKernel, LiveParams};
use rayon::prelude::*;

use crate::background::Priority;
use crate::learner::Learner;

pub use published::{
    APPROX_RES, Approx, CellMark, Growth, KernelGrid, LearnedGrid, Lit, LitState, Progress,
    REFERENCE_RES, Status, World,
};

/// What the UI asks of the learner.
#[derive(Debug)]
pub enum Command {
    /// Train continuously.
    Play,
    /// Stop training (the fit is kept).
    Pause,
    /// Train exactly this many steps (then pause).
    Step(u64),
    /// Start `learner` afresh on `scene` (subdivided `subdivide` times).
    Reset {
        /// The scene as the user sees it (not subdivided).
        scene: Scene,
        /// Pieces per surface edge.
        subdivide: usize,
        /// The learner to run.
        learner: Learner,
        /// A network's parameters (the light-driven learner has none: its statuses carry
        /// them, as the settings keep them for a network).
        params: FitParams,
    },
    /// New live parameters for the running fit (what else changes needs a new fit: `Reset`).
    Params(LiveParams),
    /// The scene changed (an end point was dragged): keep learning from the current state.
    Edit {
        /// The changed scene (not subdivided).
        scene: Scene,
        /// Pieces per surface edge.
        subdivide: usize,
    },
    /// Cells the network may grow per second of training; `None` grows as fast as it can.
    Pace(Option<f64>),
    /// Solve the lit scene with the learned kernel while it learns (or stop doing so).
    Lit(bool),
    /// The kernel plot is this many pixels wide: publish the exact ζ at that resolution.
    PlotResolution(usize),
    /// Save the running fit as a model file `dir/{stem}-step{steps}.model.json`.
    ExportModel {
        /// The folder.
        dir: PathBuf,
        /// The file name's start (scene and learner).
        stem: String,
    },
    /// Nothing but a status: the UI's way to learn that everything before it was handled.
    Sync,
}

/// What the learner publishes. Each field holds the newest value; the UI takes them.
#[derive(Debug, Default)]
pub struct Mailbox {
    /// A new scene's data.
    pub world: Option<Arc<World>>,
    /// Every status since the UI last took the mail, oldest first (the timeline keeps them all,
    /// however slowly the UI draws).
    pub statuses: Vec<Status>,
    /// The newest approximation.
    pub approx: Option<Arc<Approx>>,
    /// The exact ζ at the kernel plot's resolution.
    pub kernel_grid: Option<Arc<KernelGrid>>,
    /// The newest lit scene.
    pub lit: Option<LitState>,
    /// An error to show (a bad parameter, a failed reset).
    pub error: Option<String>,
    /// Something done to tell the user (a file saved).
    pub note: Option<String>,
    /// Work that keeps the learner busy for a noticeable time (e.g. "computing the reference").
    pub busy: Option<&'static str>,
    /// Something was posted since the UI last took the mail.
    fresh: bool,
}

/// The mailbox and the signal that something was posted to it.
#[derive(Default)]
struct Shared {
    mailbox: Mutex<Mailbox>,
    posted: Condvar,
    /// Commands sent so far: more than the learner has handled means one is waiting.
    sent: AtomicU64,
}

/// The UI's end: a command channel and the mailbox. Dropping it stops the thread.
pub struct WorkerHandle {
    commands: Option<Sender<Command>>,
    sent: u64,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl WorkerHandle {
    /// Starts the thread at `priority` (the threads it starts for the lit scene inherit it).
    /// `repaint` is called after each publication (the UI's repaint request).
    pub fn spawn(priority: Priority, repaint: impl Fn() + Send + 'static) -> WorkerHandle {
        let (tx, rx) = mpsc::channel();
        let shared = Arc::new(Shared::default());
        let learner_end = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("flatland-learner".into())
            .spawn(move || {
                priority.apply_to_this_thread();
                learner::LearnerThread::new(rx, learner_end, Box::new(repaint)).run();
            })
            .expect("spawning the learner thread");
        WorkerHandle {
            commands: Some(tx),
            sent: 0,
            shared,
            thread: Some(thread),
        }
    }

    /// Sends a command (ignored if the thread has ended).
    pub fn send(&mut self, command: Command) {
        if let Some(tx) = &self.commands
            && tx.send(command).is_ok()
        {
            self.sent += 1;
            self.shared.sent.store(self.sent, Ordering::Release);
        }
    }

    /// Commands sent so far (compare with [`Status::handled`]).
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// Takes what was published since the last call, without waiting: `None` when the learner
    /// holds the lock right now (try again next frame).
    pub fn take(&self) -> Option<Mailbox> {
        let mut guard = self.shared.mailbox.try_lock().ok()?;
        let mail = std::mem::take(&mut *guard);
        guard.busy = mail.busy; // a state, not an event: it stays until the learner clears it
        Some(mail)
    }

    /// Blocks until the learner has posted something the UI has not taken yet, or `timeout`
    /// passes; returns whether there is something. For tests and tools that wait on the
    /// learner: the UI itself never waits.
    pub fn wait(&self, timeout: Duration) -> bool {
        let Ok(guard) = self.shared.mailbox.lock() else {
            return false;
        };
        self.shared
            .posted
            .wait_timeout_while(guard, timeout, |m| !m.fresh)
            .map(|(m, _)| m.fresh)
            .unwrap_or(false)
    }
}

impl Drop for WorkerHandle {
    fn drop(&mut self) {
        self.commands = None; // disconnects: the learner's next read ends its loop
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// ζ̃ on the midpoint grid of resolution `res`, row-major, row ↔ s (in parallel).
#[must_use]
pub fn approx_grid(model: &LearnedKernel, res: usize) -> Vec<f64> {
    (0..res * res)
        .into_par_iter()
        .with_min_len(512)
        .map(|k| {
            let (s, t) = flatland_solve::grid_point(res, k);
            model.zeta(s, t)
        })
        .collect()
}
