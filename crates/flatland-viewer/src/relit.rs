//! The scene relit under moving point lights, on a thread of its own: the UI hands it the
//! newest light positions ([`RelitHandle::move_lights`]) and draws the newest B it published
//! ([`RelitHandle::take`]); the thread relights only the newest positions, dropping any that
//! were overtaken while it worked, so a slow move never queues up behind the pointer.
//!
//! What relights is a [`Relight`]: the exact re-solve ([`ExactRelight`],
//! `flatland_solve::Relighter`: the direct light, the first bounce and the later bounces by a
//! warm-started GMRES), or [`MovingLight`], the viewer's, which answers with the exact
//! re-solve until the learned transport of the later bounces ([`transport`]) is built on a
//! thread of its own, then with the transport (or the exact one, as the user chooses). While
//! it is idle and a build is under way the thread looks every [`POLL`] for the build's end, to
//! switch at once; a move looks first too. Per scene the thread also walks the free space
//! ([`flatland_geom::walk`]) once, for the light that wanders by itself on first launch.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use flatland_geom::{DVec2, Kernel, PointLight, WalkParams, walk};
use flatland_solve::{Mesh, RelightParams, Relighter, SolveError, Stop};
use flatland_transport::TransportError;

use crate::background::Priority;

mod one_moving;
pub mod transport;

pub use transport::{
    BlockLog, M2_RES, M2Grid, MovingLight, TransportPhase, TransportStatus, m2_grid,
};

/// How often the idle thread looks whether a transport's build ended.
pub const POLL: Duration = Duration::from_millis(50);

/// Positions of the wandering light's walk (it runs back and forth along them).
pub const WALK_POSITIONS: usize = 400;
/// The walk's seed: the same wander on every machine.
pub const WALK_SEED: u64 = 33;
/// Moves the median time per move is taken over.
pub const TIMED_MOVES: usize = 32;

/// What answered a move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// The exact re-solve.
    Exact,
    /// The exact direct light and first bounce, the learned transport's later bounces.
    Transport,
}

/// One relit move: B per element and what it cost.
#[derive(Clone, Copy, Debug)]
pub struct Moved<'a> {
    /// B per element of the relighter's mesh.
    pub radiosity: &'a [f64],
    /// The relative residual of `(I − K) B = B₀` the exact re-solve reached (its own error
    /// estimate); `None` for the transport, whose estimate is its own
    /// ([`TransportStatus`]).
    pub residual: Option<f64>,
    /// What answered.
    pub answer: Answer,
}

/// What relights one scene per move of its lights: the exact re-solve, or one whose later
/// bounces come from a learned transport.
pub trait Relight: Send {
    /// The elements B is given on.
    fn mesh(&self) -> &Mesh;
    /// B under `lights` (the scene's emitting edges stay on). Errors name a refused light.
    fn relight(&mut self, lights: &[PointLight], stop: &Stop) -> Result<Moved<'_>, TransportError>;
    /// Moves go through the learned transport (`true`; built the first time, the exact
    /// re-solve answering until then) or the exact re-solve. Only an exact relighter
    /// ignores it.
    fn use_transport(&mut self, _on: bool) -> Result<(), TransportError> {
        Ok(())
    }
    /// Takes a build's end: `true` when what answers the moves changed with it (the last
    /// lights are to be relit).
    fn poll(&mut self) -> bool {
        false
    }
    /// Whether a build is under way that [`Relight::poll`] should be asked about.
    fn pending(&self) -> bool {
        false
    }
    /// The learned transport's build and figures, once one was asked for.
    fn transport(&self) -> Option<TransportStatus> {
        None
    }
}

/// Makes the relighter of a scene on the thread (may take a while: `stop` is polled).
pub type MakeRelight =
    fn(kernel: &Arc<Kernel>, stop: &Stop) -> Result<Box<dyn Relight>, TransportError>;

/// The exact re-solve ([`Relighter`]) on the scene's default mesh.
pub struct ExactRelight(Relighter);

impl ExactRelight {
    /// The exact relighter of `kernel`'s scene on [`Mesh::default_elements`] elements.
    pub fn make(kernel: &Arc<Kernel>, stop: &Stop) -> Result<Box<dyn Relight>, TransportError> {
        let mesh = Mesh::new(kernel, Mesh::default_elements(kernel.scene()))?;
        let relighter = Relighter::new(kernel, &mesh, RelightParams::default(), stop)?;
        Ok(Box::new(ExactRelight(relighter)))
    }
}

impl Relight for ExactRelight {
    fn mesh(&self) -> &Mesh {
        self.0.mesh()
    }

    fn relight(&mut self, lights: &[PointLight], stop: &Stop) -> Result<Moved<'_>, TransportError> {
        let relit = self.0.relight(lights, stop)?;
        Ok(Moved {
            radiosity: relit.radiosity,
            residual: Some(relit.cost.residual),
            answer: Answer::Exact,
        })
    }
}

/// One published B: the lights it is lit by, and what the move took.
#[derive(Clone, Debug)]
pub struct RelitFrame {
    /// The scene (the app's `World` id) it belongs to.
    pub world: u64,
    /// The elements.
    pub mesh: Arc<Mesh>,
    /// The lights it was lit by.
    pub lights: Vec<PointLight>,
    /// B per element.
    pub b: Vec<f64>,
    /// The relative residual the exact re-solve reached (`None`: the transport answered).
    pub residual: Option<f64>,
    /// What answered this move.
    pub answer: Answer,
    /// The learned transport's build and figures, once one was asked for.
    pub transport: Option<TransportStatus>,
    /// Milliseconds this move took.
    pub move_ms: f64,
    /// The median over the last [`TIMED_MOVES`] moves.
    pub median_ms: f64,
    /// Moves relit so far on this scene, and positions dropped because newer ones came first.
    pub moves: u64,
    /// Positions overtaken before they were relit.
    pub dropped: u64,
}

/// What the thread has for the UI.
#[derive(Clone, Debug, Default)]
pub enum RelitState {
    /// Nothing asked yet.
    #[default]
    Idle,
    /// Building the relighter of the scene (the exact operator).
    Building,
    /// The newest B.
    Ready(Arc<RelitFrame>),
    /// The scene could not be relit, or a move was refused: why.
    Failed(String),
}

/// What the thread publishes, each the newest.
#[derive(Debug, Default)]
pub struct RelitMail {
    /// The newest state, if it changed.
    pub state: Option<RelitState>,
    /// The free-space walk of the scene (the wandering light's path), once per scene.
    pub walk: Option<(u64, Arc<Vec<DVec2>>)>,
    /// A scene's relighter is built: its world and the seconds it took.
    pub built: Option<(u64, f64)>,
    fresh: bool,
}

/// What the UI asked for: the newest of each.
#[derive(Default)]
struct Inbox {
    /// A scene to relight from now on, with its world id.
    scene: Option<(u64, Arc<Kernel>)>,
    /// The newest light positions not yet relit.
    lights: Option<Vec<PointLight>>,
    /// Positions replaced before they were taken.
    overtaken: u64,
    /// Through the learned transport or not, when the user changed it.
    transport: Option<bool>,
    quit: bool,
}

#[derive(Default)]
struct Shared {
    inbox: Mutex<Inbox>,
    asked: Condvar,
    outbox: Mutex<RelitMail>,
    posted: Condvar,
    /// A new scene or quit: interrupts a build under way.
    interrupt: AtomicBool,
}

/// The UI's end of the relighting thread. Dropping it stops the thread.
pub struct RelitHandle {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl RelitHandle {
    /// Starts the thread at `priority`; `make` builds each scene's relighter, `repaint` is
    /// called after each publication.
    pub fn spawn(
        priority: Priority,
        make: MakeRelight,
        repaint: impl Fn() + Send + 'static,
    ) -> RelitHandle {
        let shared = Arc::new(Shared::default());
        let end = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("flatland-relight".into())
            .spawn(move || {
                priority.apply_to_this_thread();
                RelitThread::new(end, make, Box::new(repaint)).run();
            })
            .expect("spawning the relighting thread");
        RelitHandle {
            shared,
            thread: Some(thread),
        }
    }

    /// Relight `kernel`'s scene (world `world`) from now on: its relighter is built (a build
    /// under way for an older scene is interrupted) and its walk made.
    pub fn set_scene(&self, world: u64, kernel: Arc<Kernel>) {
        let mut inbox = lock(&self.shared.inbox);
        inbox.scene = Some((world, kernel));
        inbox.lights = None;
        self.shared.interrupt.store(true, Ordering::Release);
        self.shared.asked.notify_one();
    }

    /// Moves through the learned transport (built first, the exact re-solve answering
    /// meanwhile) or through the exact re-solve, from now on and for the scenes after.
    pub fn use_transport(&self, on: bool) {
        lock(&self.shared.inbox).transport = Some(on);
        self.shared.asked.notify_one();
    }

    /// The lights' newest positions: relit as soon as the thread is free, unless newer ones
    /// come first.
    pub fn move_lights(&self, lights: Vec<PointLight>) {
        let mut inbox = lock(&self.shared.inbox);
        if inbox.lights.replace(lights).is_some() {
            inbox.overtaken += 1;
        }
        self.shared.asked.notify_one();
    }

    /// What was published since the last call, without waiting (`None`: the thread holds the
    /// lock right now).
    pub fn take(&self) -> Option<RelitMail> {
        let mut guard = self.shared.outbox.try_lock().ok()?;
        if !guard.fresh {
            return None;
        }
        Some(std::mem::take(&mut *guard))
    }

    /// Blocks until something was published that the UI has not taken, or `timeout` passes
    /// (for tests, which wait on conditions; the UI never waits).
    pub fn wait(&self, timeout: Duration) -> bool {
        let guard = lock(&self.shared.outbox);
        self.shared
            .posted
            .wait_timeout_while(guard, timeout, |m| !m.fresh)
            .map(|(m, _)| m.fresh)
            .unwrap_or(false)
    }
}

impl Drop for RelitHandle {
    fn drop(&mut self) {
        lock(&self.shared.inbox).quit = true;
        self.shared.interrupt.store(true, Ordering::Release);
        self.shared.asked.notify_one();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// A mutex's guard, also when a panicking thread poisoned it (the data are plain values).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The thread: the current scene's relighter and its timings.
struct RelitThread {
    shared: Arc<Shared>,
    make: MakeRelight,
    repaint: Box<dyn Fn() + Send>,
    current: Option<Current>,
    /// Whether moves go through the learned transport.
    transport: bool,
}

/// The scene being relit.
struct Current {
    world: u64,
    relight: Box<dyn Relight>,
    mesh: Arc<Mesh>,
    times: VecDeque<f64>,
    moves: u64,
    dropped_before: u64,
    /// The lights last relit, and the positions overtaken then.
    last: Option<(Vec<PointLight>, u64)>,
    /// What answered the last move.
    answered: Option<Answer>,
}

/// What the thread is asked next.
enum Job {
    Scene(u64, Arc<Kernel>),
    Lights(Vec<PointLight>, u64),
    Transport(bool),
    /// Nothing asked within [`POLL`] while a build is under way.
    Poll,
    Quit,
}

impl RelitThread {
    fn new(shared: Arc<Shared>, make: MakeRelight, repaint: Box<dyn Fn() + Send>) -> Self {
        RelitThread {
            shared,
            make,
            repaint,
            current: None,
            transport: false,
        }
    }

    fn run(mut self) {
        loop {
            match self.next_job() {
                Job::Quit => return,
                Job::Scene(world, kernel) => self.build(world, &kernel),
                Job::Lights(lights, overtaken) => self.relight(&lights, overtaken),
                Job::Transport(on) => self.choose(on),
                Job::Poll => self.poll(),
            }
        }
    }

    /// Moves through the transport or not; the last lights relit by the new choice.
    fn choose(&mut self, on: bool) {
        self.transport = on;
        let Some(c) = self.current.as_mut() else {
            return;
        };
        if let Err(e) = c.relight.use_transport(on) {
            self.publish(|m| m.state = Some(RelitState::Failed(e.to_string())));
            return;
        }
        self.relight_last();
    }

    /// A build's end: the last lights relit when it changed what answers them.
    fn poll(&mut self) {
        if self.current.as_mut().is_some_and(|c| c.relight.poll()) {
            self.relight_last();
        } else {
            // The blocks grew: the UI draws them.
            (self.repaint)();
        }
    }

    fn relight_last(&mut self) {
        if let Some((lights, overtaken)) = self.current.as_ref().and_then(|c| c.last.clone()) {
            self.relight(&lights, overtaken);
        }
    }

    /// Waits for the next job: a new scene first, then the newest lights.
    fn next_job(&self) -> Job {
        let mut inbox = lock(&self.shared.inbox);
        loop {
            if inbox.quit {
                return Job::Quit;
            }
            if let Some((world, kernel)) = inbox.scene.take() {
                self.shared.interrupt.store(false, Ordering::Release);
                return Job::Scene(world, kernel);
            }
            if let Some(on) = inbox.transport.take() {
                return Job::Transport(on);
            }
            if let Some(lights) = inbox.lights.take() {
                return Job::Lights(lights, inbox.overtaken);
            }
            if self.current.as_ref().is_some_and(|c| c.relight.pending()) {
                let (guard, waited) = self
                    .shared
                    .asked
                    .wait_timeout(inbox, POLL)
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                inbox = guard;
                if waited.timed_out() {
                    return Job::Poll;
                }
                continue;
            }
            inbox = self
                .shared
                .asked
                .wait(inbox)
                .unwrap_or_else(std::sync::PoisonError::into_inner);
        }
    }

    fn publish(&self, fill: impl FnOnce(&mut RelitMail)) {
        let mut mail = lock(&self.shared.outbox);
        fill(&mut mail);
        mail.fresh = true;
        self.shared.posted.notify_all();
        drop(mail);
        (self.repaint)();
    }

    /// Builds the relighter and the walk of a new scene (interrupted by a newer one).
    fn build(&mut self, world: u64, kernel: &Arc<Kernel>) {
        self.current = None;
        self.publish(|m| m.state = Some(RelitState::Building));
        // `Stop` is `'static`: the flag is reached through the shared state, not borrowed.
        let shared = Arc::clone(&self.shared);
        let stop = move || shared.interrupt.load(Ordering::Acquire);
        let started = Instant::now();
        let made = (self.make)(kernel, &stop)
            .and_then(|mut r| r.use_transport(self.transport).map(|()| r));
        let built_s = started.elapsed().as_secs_f64();
        let relight = match made {
            Ok(r) => r,
            Err(TransportError::Interrupted | TransportError::Solve(SolveError::Interrupted)) => {
                return;
            }
            Err(e) => {
                self.publish(|m| m.state = Some(RelitState::Failed(e.to_string())));
                return;
            }
        };
        let walked = walk(kernel, &WalkParams::new(WALK_POSITIONS, WALK_SEED));
        let dropped_before = lock(&self.shared.inbox).overtaken;
        self.current = Some(Current {
            world,
            mesh: Arc::new(relight.mesh().clone()),
            relight,
            times: VecDeque::new(),
            moves: 0,
            dropped_before,
            last: None,
            answered: None,
        });
        self.publish(|m| {
            m.built = Some((world, built_s));
            match walked {
                Ok(w) => m.walk = Some((world, Arc::new(w.positions))),
                Err(e) => m.state = Some(RelitState::Failed(format!("no walk: {e}"))),
            }
        });
    }

    /// Relights the current scene under `lights` and publishes B, or why not.
    fn relight(&mut self, lights: &[PointLight], overtaken: u64) {
        let Some(c) = self.current.as_mut() else {
            return;
        };
        c.last = Some((lights.to_vec(), overtaken));
        // A build that ended is taken here too: a light moved every frame keeps the thread
        // from ever idling [`POLL`] long, and the move would go on by the exact re-solve.
        if c.relight.pending() {
            c.relight.poll();
        }
        let started = Instant::now();
        let state = match c.relight.relight(lights, &flatland_solve::never) {
            Ok(moved) => {
                let move_ms = 1e3 * started.elapsed().as_secs_f64();
                let (residual, answer) = (moved.residual, moved.answer);
                let b = moved.radiosity.to_vec();
                if c.answered != Some(answer) {
                    // The median is of the moves of what answers now.
                    c.times.clear();
                    c.answered = Some(answer);
                }
                if c.times.len() == TIMED_MOVES {
                    c.times.pop_front();
                }
                c.times.push_back(move_ms);
                c.moves += 1;
                RelitState::Ready(Arc::new(RelitFrame {
                    world: c.world,
                    mesh: Arc::clone(&c.mesh),
                    lights: lights.to_vec(),
                    b,
                    residual,
                    answer,
                    transport: c.relight.transport(),
                    move_ms,
                    median_ms: median(&c.times),
                    moves: c.moves,
                    dropped: overtaken - c.dropped_before,
                }))
            }
            Err(e) => RelitState::Failed(format!("light not moved: {e}")),
        };
        self.publish(|m| m.state = Some(state));
    }
}

/// The median of `values` (0 when empty).
fn median(values: &VecDeque<f64>) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wait_for(handle: &RelitHandle, mut cond: impl FnMut(&RelitMail) -> bool) -> RelitMail {
        loop {
            assert!(handle.wait(Duration::from_secs(120)), "nothing published");
            if let Some(mail) = handle.take()
                && cond(&mail)
            {
                return mail;
            }
        }
    }

    #[test]
    fn the_newest_lights_are_relit_and_b_follows_them() {
        let scene = flatland_geom::bundled::scene("floorplan").unwrap();
        let kernel = Arc::new(Kernel::new(scene));
        let handle = RelitHandle::spawn(Priority::Normal, ExactRelight::make, || {});
        handle.set_scene(7, Arc::clone(&kernel));
        let mail = wait_for(&handle, |m| {
            m.walk.is_some() || matches!(m.state, Some(RelitState::Failed(_)))
        });
        let (world, walk) = mail.walk.expect("a walk");
        assert_eq!(world, 7);
        assert_eq!(walk.len(), WALK_POSITIONS);
        let frame_at = |at: DVec2| {
            handle.move_lights(vec![PointLight::new(at, 5.0)]);
            let mail = wait_for(
                &handle,
                |m| matches!(&m.state, Some(RelitState::Ready(f)) if f.lights[0].at == at),
            );
            match mail.state {
                Some(RelitState::Ready(f)) => f,
                _ => unreachable!(),
            }
        };
        let first = frame_at(walk[0]);
        let later = frame_at(walk[WALK_POSITIONS / 2]);
        assert_eq!(first.world, 7);
        assert_eq!(first.b.len(), first.mesh.len());
        assert!(first.residual.is_some_and(|r| r <= 1e-6) && first.median_ms > 0.0);
        assert_eq!(first.answer, Answer::Exact);
        assert_ne!(first.b, later.b, "B follows the light");
        // A light on a wall is refused, and says which.
        let wall = kernel.scene().edges()[0];
        handle.move_lights(vec![PointLight::new((wall.a + wall.b) / 2.0, 5.0)]);
        let mail = wait_for(&handle, |m| matches!(m.state, Some(RelitState::Failed(_))));
        let Some(RelitState::Failed(why)) = mail.state else {
            unreachable!()
        };
        assert!(why.starts_with("light not moved"), "{why}");
    }

    #[test]
    fn the_median_is_the_middle_move() {
        let v: VecDeque<f64> = [5.0, 1.0, 3.0].into_iter().collect();
        assert_eq!(median(&v), 3.0);
        assert_eq!(median(&VecDeque::new()), 0.0);
    }
}
