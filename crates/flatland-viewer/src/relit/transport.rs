//! The moving light through the learned transport: [`MovingLight`] answers moves with the
//! exact re-solve until the transport (`flatland_transport::TransportRelighter`: the exact
//! direct light and first bounce, the transport's later bounces) is built, then with the
//! transport. The transport is built on a thread of its own, at the lowest priority, from the
//! exact relighter's operator, so the light never freezes while it builds; its blocks are
//! published as they are made ([`BlockLog`]) for the kernel plot. It answers as soon as its
//! blocks are made: its error estimate ([`Validation`]) and the grid of its `M₂(s, t)` for the
//! plot ([`M2Grid`]) are made after, by the same thread, and shown when they are ready.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::sync::{Arc, Mutex, OnceLock};

use flatland_geom::{Kernel, PointLight};
use flatland_solve::{Mesh, RelightParams, Relighter, Stop};
use flatland_transport::{
    BlockFootprint, Columns, ErrorEstimate, Transport, TransportError, TransportParams,
    TransportRelighter,
};

use super::one_moving::OneMoving;
use super::{Answer, Moved, Relight, lock};
use crate::background::Priority;

/// The blocks of a transport as its build makes them, in the order they were made.
#[derive(Debug, Default)]
pub struct BlockLog(Mutex<Vec<BlockFootprint>>);

impl BlockLog {
    /// How many blocks are made.
    #[must_use]
    pub fn len(&self) -> usize {
        lock(&self.0).len()
    }

    /// Whether none is made yet.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The blocks made so far.
    #[must_use]
    pub fn blocks(&self) -> Vec<BlockFootprint> {
        lock(&self.0).clone()
    }

    fn push(&self, block: BlockFootprint) {
        lock(&self.0).push(block);
    }
}

/// Cells per side of the learned `M₂(s, t)`'s grid ([`m2_grid`]).
pub const M2_RES: usize = 256;

/// The learned kernel of the later bounces on an `M2_RES × M2_RES` grid of `(s, t)` (row-major,
/// row ↔ `s`, the sender, column ↔ `t`, the receiver, as every plot's grid): each cell the mean
/// over it of the density `m(s, t) = M₂[receiver, sender] / Δs_sender`. An entry's mass goes
/// to the cells its pair of elements covers (the cell it falls in when smaller than a cell).
#[must_use]
pub fn m2_grid(transport: &Transport, mesh: &Mesh) -> Vec<f64> {
    let res = M2_RES;
    let mut grid = vec![0.0; res * res];
    let elements = mesh.elements();
    let cells = |s: [f64; 2]| {
        let lo = ((s[0] * res as f64) as usize).min(res - 1);
        let hi = ((s[1] * res as f64).ceil() as usize).clamp(lo + 1, res);
        lo..hi
    };
    let cell_area = 1.0 / (res * res) as f64;
    transport.entries(|receiver, sender, value| {
        let (t, s) = (elements[receiver as usize].s, elements[sender as usize].s);
        let (rows, columns) = (cells(s), cells(t));
        // The mass M₂ Δt (density × area) spread over the cells it covers.
        let spread = rows.len() * columns.len();
        let add = value * (t[1] - t[0]) / (cell_area * spread as f64);
        for row in rows {
            for cell in &mut grid[row * res + columns.start..row * res + columns.end] {
                *cell += add;
            }
        }
    });
    grid
}

/// The learned `M₂(s, t)` on its grid ([`m2_grid`]), filled by the build's thread after the
/// transport already answers moves: at 10⁴ edges the grid visits tens of millions of entries,
/// seconds at the lowest priority, which the moving light must not wait for.
pub type M2Grid = Arc<OnceLock<Vec<f64>>>;

/// The transport's own error estimate, measured after it answers: an exact solve per
/// validation light (32), work the moving light need not wait for.
pub type Validation = Arc<OnceLock<ErrorEstimate>>;

/// Where the learned transport of the scene is.
#[derive(Clone, Debug)]
pub enum TransportPhase {
    /// Being built; the exact re-solve answers meanwhile.
    Building,
    /// Built: its own error estimate (relative L2 of B on its validation lights) once
    /// measured, its bytes and the seconds its blocks took (the exact operator it reads was
    /// built before).
    Ready {
        /// The estimate, once measured ([`Validation`]).
        estimate: Option<ErrorEstimate>,
        /// Bytes of the transport alone.
        bytes: usize,
        /// Seconds its blocks took.
        build_s: f64,
        /// The learned `M₂(s, t)` ([`m2_grid`]), once made.
        m2: M2Grid,
    },
    /// The build failed: why.
    Failed(String),
}

/// The learned transport's build, for the UI.
#[derive(Clone, Debug)]
pub struct TransportStatus {
    /// Its blocks so far.
    pub blocks: Arc<BlockLog>,
    /// Blocks it will have (one per cluster of elements).
    pub clusters: usize,
    /// Where it is.
    pub phase: TransportPhase,
}

/// The learned transport of one scene: none asked for, being built, built, or failed.
enum Slot {
    Off,
    Building {
        cancel: Arc<AtomicBool>,
        done: Receiver<Result<TransportRelighter, TransportError>>,
        later: (Validation, M2Grid),
    },
    Ready(Box<TransportRelighter>, (Validation, M2Grid)),
    Failed(String),
}

/// The exact re-solve, and the learned transport once it is built and chosen.
pub struct MovingLight {
    exact: Relighter,
    kernel: Arc<Kernel>,
    /// Whether moves should go through the transport (when it is built).
    chosen: bool,
    slot: Slot,
    blocks: Arc<BlockLog>,
    clusters: usize,
    /// The others' light while one light moves, and what answered it.
    moving: OneMoving,
    answered: Answer,
}

impl MovingLight {
    /// The exact relighter of `kernel`'s scene on [`Mesh::default_elements`] elements; the
    /// transport is built when first chosen ([`Relight::use_transport`]).
    pub fn make(kernel: &Arc<Kernel>, stop: &Stop) -> Result<Box<dyn Relight>, TransportError> {
        let mesh = Mesh::new(kernel, Mesh::default_elements(kernel.scene()))?;
        let exact = Relighter::new(kernel, &mesh, RelightParams::default(), stop)?;
        let clusters = Transport::blocks_to_build(&mesh, &TransportParams::default());
        Ok(Box::new(MovingLight {
            exact,
            kernel: Arc::clone(kernel),
            chosen: false,
            slot: Slot::Off,
            blocks: Arc::default(),
            clusters,
            moving: OneMoving::default(),
            answered: Answer::Exact,
        }))
    }

    /// Starts the transport's build on its own thread.
    fn start_build(&mut self) -> Result<(), TransportError> {
        let copy = self.exact.with_params(RelightParams::default())?;
        let kernel = Arc::clone(&self.kernel);
        let blocks = Arc::clone(&self.blocks);
        let cancel = Arc::new(AtomicBool::new(false));
        let cancelled = Arc::clone(&cancel);
        let (send, done) = channel();
        let later = (Validation::default(), M2Grid::default());
        let (validated, filled) = (Arc::clone(&later.0), Arc::clone(&later.1));
        std::thread::Builder::new()
            .name("flatland-transport".into())
            .spawn(move || {
                Priority::Background.apply_to_this_thread();
                let stop = move || cancelled.load(Ordering::Acquire);
                let watch = |block| blocks.push(block);
                let params = TransportParams::default();
                // The operator by columns serves the blocks and then the estimate.
                let (mesh, columns) = (copy.mesh().clone(), Columns::of(copy.rows()));
                let built =
                    Transport::build_unvalidated(&kernel, &mesh, &columns, &params, &stop, &watch);
                let mut transport = match built {
                    Ok(t) => t,
                    Err(e) => {
                        // The receiver is gone when the scene changed meanwhile.
                        let _ = send.send(Err(e));
                        return;
                    }
                };
                // The relighter answers first; the estimate and the grid (for the M₂ plot)
                // are made after, on a copy of its blocks.
                let answering = TransportRelighter::new(&kernel, copy, transport.clone(), &stop);
                if send.send(answering).is_err() || stop() {
                    return;
                }
                if transport.validate(&kernel, &mesh, &columns, &stop).is_ok() {
                    let _ = validated.set(transport.estimated_error());
                }
                drop(columns);
                if !stop() {
                    let _ = filled.set(m2_grid(&transport, &mesh));
                }
            })
            .expect("spawning the transport's thread");
        self.slot = Slot::Building {
            cancel,
            done,
            later,
        };
        Ok(())
    }
}

impl Drop for MovingLight {
    fn drop(&mut self) {
        if let Slot::Building { cancel, .. } = &self.slot {
            cancel.store(true, Ordering::Release);
        }
    }
}

impl Relight for MovingLight {
    fn mesh(&self) -> &Mesh {
        self.exact.mesh()
    }

    fn relight(&mut self, lights: &[PointLight], stop: &Stop) -> Result<Moved<'_>, TransportError> {
        let answer = match (&self.slot, self.chosen) {
            (Slot::Ready(..), true) => Answer::Transport,
            _ => Answer::Exact,
        };
        if answer != self.answered {
            self.moving.forget();
            self.answered = answer;
        }
        let copy = |b: &[f64], out: &mut Vec<f64>| {
            out.clear();
            out.extend_from_slice(b);
        };
        if let Slot::Ready(transport, _) = &mut self.slot
            && answer == Answer::Transport
        {
            let radiosity = self.moving.relight(lights, |lights, out| {
                copy(transport.relight(lights)?, out);
                Ok::<_, TransportError>(())
            })?;
            return Ok(Moved {
                radiosity,
                residual: None,
                answer,
            });
        }
        let (exact, mut residual) = (&mut self.exact, 0.0f64);
        let radiosity = self.moving.relight(lights, |lights, out| {
            let relit = exact.relight(lights, stop)?;
            residual = residual.max(relit.cost.residual);
            copy(relit.radiosity, out);
            Ok::<_, TransportError>(())
        })?;
        Ok(Moved {
            radiosity,
            residual: Some(residual),
            answer,
        })
    }

    fn use_transport(&mut self, on: bool) -> Result<(), TransportError> {
        self.chosen = on;
        if on && matches!(self.slot, Slot::Off) {
            self.start_build()?;
        }
        Ok(())
    }

    fn poll(&mut self) -> bool {
        let Slot::Building { done, later, .. } = &self.slot else {
            return false;
        };
        match done.try_recv() {
            Err(TryRecvError::Empty) => return false,
            Ok(Ok(transport)) => {
                let later = (Arc::clone(&later.0), Arc::clone(&later.1));
                self.slot = Slot::Ready(Box::new(transport), later);
            }
            Ok(Err(e)) => self.slot = Slot::Failed(e.to_string()),
            Err(TryRecvError::Disconnected) => {
                self.slot = Slot::Failed("the transport's thread ended".into());
            }
        }
        self.chosen
    }

    fn pending(&self) -> bool {
        matches!(self.slot, Slot::Building { .. })
    }

    fn transport(&self) -> Option<TransportStatus> {
        let phase = match &self.slot {
            Slot::Off => return None,
            Slot::Building { .. } => TransportPhase::Building,
            Slot::Ready(t, (estimate, m2)) => TransportPhase::Ready {
                estimate: estimate.get().copied(),
                bytes: t.transport().bytes(),
                build_s: t.transport().build_s(),
                m2: Arc::clone(m2),
            },
            Slot::Failed(why) => TransportPhase::Failed(why.clone()),
        };
        Some(TransportStatus {
            blocks: Arc::clone(&self.blocks),
            clusters: self.clusters,
            phase,
        })
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::relit::{ExactRelight, RelitFrame, RelitHandle, RelitMail, RelitState};

    fn wait_for(handle: &RelitHandle, mut cond: impl FnMut(&RelitMail) -> bool) -> RelitMail {
        loop {
            assert!(handle.wait(Duration::from_secs(300)), "nothing published");
            if let Some(mail) = handle.take()
                && cond(&mail)
            {
                return mail;
            }
        }
    }

    fn frame_by(handle: &RelitHandle, answer: Answer) -> Arc<RelitFrame> {
        let mail = wait_for(
            handle,
            |m| matches!(&m.state, Some(RelitState::Ready(f)) if f.answer == answer),
        );
        match mail.state {
            Some(RelitState::Ready(f)) => f,
            _ => unreachable!(),
        }
    }

    /// Relative L2 of `a − b` over the elements, weighted by their lengths.
    fn relative(mesh: &Mesh, a: &[f64], b: &[f64]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (i, e) in mesh.elements().iter().enumerate() {
            num += e.length * (a[i] - b[i]).powi(2);
            den += e.length * b[i] * b[i];
        }
        (num / den).sqrt()
    }

    #[test]
    fn the_transport_through_the_thread_is_the_exact_relight_within_its_estimate() {
        let scene = flatland_geom::bundled::scene("floorplan").unwrap();
        let kernel = Arc::new(Kernel::new(scene));
        let handle = RelitHandle::spawn(Priority::Normal, MovingLight::make, || {});
        handle.use_transport(true);
        handle.set_scene(3, Arc::clone(&kernel));
        let mail = wait_for(&handle, |m| m.walk.is_some());
        let (_, walk) = mail.walk.expect("a walk");
        let lights = vec![PointLight::new(walk[walk.len() / 3], 5.0)];
        handle.move_lights(lights.clone());
        // The exact re-solve answers until the transport is built; then the thread relights
        // the same lights by the transport by itself.
        let frame = frame_by(&handle, Answer::Transport);
        assert_eq!(frame.lights, lights);
        assert!(frame.residual.is_none());
        let status = frame.transport.clone().expect("the transport's status");
        let TransportPhase::Ready { bytes, ref m2, .. } = status.phase else {
            panic!("{:?}", status.phase)
        };
        assert!(bytes > 0);
        // The estimate and then the grid follow the relighter: wait for the grid (no
        // timeout: the build's thread makes both next), then the next move's status holds
        // the estimate.
        let m2 = m2.wait();
        assert_eq!(m2.len(), M2_RES * M2_RES);
        assert!(m2.iter().any(|&v| v > 0.0));
        let lights = vec![PointLight::new(walk[walk.len() / 3], 6.0)];
        handle.move_lights(lights.clone());
        let frame = frame_by(&handle, Answer::Transport);
        assert_eq!(frame.lights, lights);
        let Some(TransportPhase::Ready {
            estimate: Some(estimate),
            ..
        }) = frame.transport.as_ref().map(|t| t.phase.clone())
        else {
            panic!("no estimate after the grid: {:?}", frame.transport)
        };
        assert!(estimate.lights > 0);
        let mut exact = ExactRelight::make(&kernel, &flatland_solve::never).unwrap();
        let solved = exact.relight(&lights, &flatland_solve::never).unwrap();
        let error = relative(&frame.mesh, &frame.b, solved.radiosity);
        // Stated factor: within three times the largest estimated error of B (as the
        // transport's own test of its relighter).
        assert!(error <= 3.0 * estimate.b_max, "{error} vs {estimate:?}");
        // Every cluster's block was published, and every element sends from exactly one.
        let blocks = status.blocks.blocks();
        assert_eq!(blocks.len(), status.clusters);
        let mut sends = vec![0; frame.mesh.len()];
        for block in &blocks {
            for run in &block.senders {
                run.clone().for_each(|e| sends[e as usize] += 1);
            }
        }
        assert!(sends.iter().all(|&n| n == 1));
        // Back to the exact re-solve: the same lights relit by it at once.
        handle.use_transport(false);
        let back = frame_by(&handle, Answer::Exact);
        assert!(relative(&back.mesh, &back.b, solved.radiosity) < 1e-4);
    }

    #[test]
    fn the_m2_grid_keeps_the_mass_of_the_entries() {
        // Σ over the grid of density × cell area is Σ M₂[i, j] Δt_i, however the entries
        // fall on the cells.
        let plan = flatland_geom::generate::floor_plan(120, 4).unwrap();
        let kernel = Kernel::new(plan);
        let mesh = Mesh::new(&kernel, 2 * Mesh::min_elements(kernel.scene())).unwrap();
        let k = flatland_solve::sweep_operator(&kernel, &mesh, &flatland_solve::never).unwrap();
        let params = TransportParams::default();
        let transport =
            Transport::build(&kernel, &mesh, &k, &params, &flatland_solve::never).unwrap();
        let grid = m2_grid(&transport, &mesh);
        let cell = 1.0 / (M2_RES * M2_RES) as f64;
        let mass: f64 = grid.iter().sum::<f64>() * cell;
        let mut exact = 0.0;
        let elements = mesh.elements();
        transport.entries(|i, _, v| {
            exact += v * (elements[i as usize].s[1] - elements[i as usize].s[0])
        });
        assert!(exact > 0.0);
        assert!((mass - exact).abs() <= 1e-9 * exact, "{mass} vs {exact}");
    }

    #[test]
    fn the_block_log_grows_as_blocks_are_pushed() {
        let log = BlockLog::default();
        assert!(log.is_empty());
        let block = BlockFootprint {
            cluster: 2,
            senders: std::iter::once(0..3).collect(),
            receivers: vec![1..2, 5..9],
            rank: 1,
        };
        log.push(block.clone());
        assert_eq!(log.len(), 1);
        assert_eq!(log.blocks(), vec![block]);
    }
}
