//! The moving lights: the point lights the relit scene is lit by, where they are, the wander
//! along the free-space walk, and what the user does to them (grab, add, delete). The
//! relighting itself is on its own thread ([`crate::relit`]): each frame the lights' newest
//! positions go there when they changed, and the newest B that came back is drawn.

use std::sync::Arc;
use std::time::Instant;

use flatland_geom::{DVec2, Kernel, PointLight, WalkParams, in_a_room};
use flatland_pictures::colormap::Scale;

use super::ViewerApp;
use crate::relit::{Answer, M2Grid, RelitFrame, RelitHandle, RelitState, TransportPhase};
use crate::views::{BlocksTexture, EdgesTexture, LampsOut};
use crate::worker::World;

/// A light added to a scene without lights of its own is this many times as strong as its
/// strongest emitting edge: as strong as one, its bounce into the next room is lost under the
/// emitters' light there.
pub const LAMP_OVER_EMITTER: f64 = 4.0;

/// Walk positions the wandering light passes per second.
pub const WANDER_SPEED: f64 = 6.0;

/// The lights and the relit scene they make.
pub(super) struct Lamps {
    pub(super) handle: RelitHandle,
    /// The world whose scene the thread relights.
    pub(super) world: Option<Arc<World>>,
    /// The lights as the user sees them.
    pub(super) lights: Vec<PointLight>,
    /// The lights last sent to the thread.
    sent: Vec<PointLight>,
    /// Power of a light added with a click.
    power: f64,
    /// Whether the thread has built this scene's relighter.
    built: bool,
    /// The free-space walk the wandering light follows, and where along it it is (in
    /// positions, running back and forth).
    walk: Option<Arc<Vec<DVec2>>>,
    along: f64,
    last_tick: Option<Instant>,
    /// The newest B, and why there is none when there is not.
    pub(super) frame: Option<Arc<RelitFrame>>,
    pub(super) state: RelitState,
    /// The top of the colour scale, fixed per scene at its first B (so the scale does not jump
    /// as the light moves; the exposure slider moves it).
    pub(super) top: Option<f64>,
    /// The light being dragged, by index.
    pub(super) grabbed: Option<usize>,
    /// Where the lights' marks were drawn in the last frame (for tests and tools).
    pub(super) marks: Vec<egui::Pos2>,
    pub(super) texture: EdgesTexture,
    /// The learned transport's blocks over the kernel plot.
    pub(super) blocks: BlocksTexture,
    /// The learned `M₂(s, t)` shown in the kernel plot: its world, grid, texture and scale.
    pub(super) m2: Option<(u64, M2Grid, egui::TextureHandle, Scale)>,
}

impl Lamps {
    pub(super) fn new(handle: RelitHandle) -> Lamps {
        Lamps {
            handle,
            world: None,
            lights: Vec::new(),
            sent: Vec::new(),
            power: 1.0,
            built: false,
            walk: None,
            along: 0.0,
            last_tick: None,
            frame: None,
            state: RelitState::Idle,
            top: None,
            grabbed: None,
            marks: Vec::new(),
            texture: EdgesTexture::default(),
            blocks: BlocksTexture::default(),
            m2: None,
        }
    }

    /// The id of the world relit (0: none yet).
    fn world_id(&self) -> u64 {
        self.world.as_ref().map_or(0, |w| w.id)
    }
}

/// What answered a move, in words.
pub(super) fn answer_name(answer: Answer) -> &'static str {
    match answer {
        Answer::Exact => "moving light, exact re-solve",
        Answer::Transport => "moving light, learned transport",
    }
}

/// How good a move is: the exact re-solve's residual, or the transport's own error estimate of
/// B (relative L2 on its validation lights).
pub(super) fn relit_quality(frame: &RelitFrame) -> String {
    match (frame.residual, frame.transport.as_ref().map(|t| &t.phase)) {
        (Some(r), _) => format!("residual {r:.0e}"),
        (
            None,
            Some(TransportPhase::Ready {
                estimate: Some(estimate),
                ..
            }),
        ) => format!(
            "est. error of B {:.1} % (max {:.1} %)",
            100.0 * estimate.b_mean,
            100.0 * estimate.b_max
        ),
        (None, Some(TransportPhase::Ready { estimate: None, .. })) => {
            "error of B being estimated".to_owned()
        }
        (None, _) => String::new(),
    }
}

/// Where the learned transport is: its build's progress, or its bytes and build time.
pub(super) fn transport_note(frame: &RelitFrame) -> String {
    let Some(t) = &frame.transport else {
        return String::new();
    };
    match &t.phase {
        TransportPhase::Building => format!(
            "transport building: {} of {} blocks (exact meanwhile)",
            t.blocks.len(),
            t.clusters
        ),
        TransportPhase::Ready {
            estimate,
            bytes,
            build_s,
            ..
        } => format!(
            "transport: {} blocks, {:.1} MB, built in {:.1} s, {}",
            t.clusters,
            *bytes as f64 / 1e6,
            build_s,
            estimate.map_or("its estimate being measured".to_owned(), |e| format!(
                "est. on {} lights",
                e.lights
            ))
        ),
        TransportPhase::Failed(why) => format!("transport failed: {why}"),
    }
}

/// Power of a light in `kernel`'s scene: its first light's, else [`LAMP_OVER_EMITTER`] times
/// that of its strongest emitting edge (`E × length`), else 1.
fn light_power(kernel: &Kernel) -> f64 {
    let scene = kernel.scene();
    if let Some(l) = scene.lights().first() {
        return l.power;
    }
    let strongest = scene
        .edges()
        .iter()
        .map(|e| e.emission * e.length())
        .fold(0.0, f64::max);
    if strongest > 0.0 {
        LAMP_OVER_EMITTER * strongest
    } else {
        1.0
    }
}

/// Where a light may go: inside a room (not behind a wall or inside an object) and off every
/// edge by a hair; why not otherwise.
fn refused(kernel: &Kernel, p: DVec2) -> Option<&'static str> {
    // A fiftieth of the walk's margin: a light may go nearer a wall than the wanderer does.
    let hair = WalkParams::new(1, 0).margin_for(kernel) / 50.0;
    if kernel.nearest_edge_within(p, hair).is_some() {
        Some("on a wall")
    } else if !in_a_room(kernel, p) {
        Some("behind a wall or inside an object")
    } else {
        None
    }
}

/// `at` of the walk `positions` (a position count from its start, back and forth).
fn along_walk(positions: &[DVec2], along: f64) -> DVec2 {
    let last = positions.len().saturating_sub(1);
    if last == 0 {
        return positions.first().copied().unwrap_or_default();
    }
    let period = 2.0 * last as f64;
    let mut x = along.rem_euclid(period);
    if x > last as f64 {
        x = period - x;
    }
    let i = (x.floor() as usize).min(last - 1);
    positions[i].lerp(positions[i + 1], x - i as f64)
}

impl ViewerApp {
    /// Once a frame: takes what the relighting thread published, follows a new scene, moves
    /// the wandering light and sends the lights when they changed.
    pub(super) fn tick_lamps(&mut self, ctx: &egui::Context) {
        self.take_relit();
        if let Some(world) = self
            .world
            .as_ref()
            .filter(|w| w.id != self.lamps.world_id())
        {
            let l = &mut self.lamps;
            l.world = Some(Arc::clone(world));
            l.power = light_power(&world.kernel);
            l.lights = world.scene.lights().to_vec();
            l.sent.clear();
            (l.built, l.walk, l.frame, l.top, l.grabbed) = (false, None, None, None, None);
            l.along = 0.0;
            l.handle.set_scene(world.id, Arc::clone(&world.kernel));
        }
        let now = Instant::now();
        let dt = self
            .lamps
            .last_tick
            .replace(now)
            .map_or(0.0, |t| now.duration_since(t).as_secs_f64().min(0.1));
        let l = &mut self.lamps;
        if self.settings.wander
            && l.grabbed.is_none()
            && let Some(walk) = &l.walk
            && let Some(first) = l.lights.first_mut()
        {
            l.along += dt * WANDER_SPEED;
            first.at = along_walk(walk, l.along);
            ctx.request_repaint();
        }
        if l.built && l.lights != l.sent {
            l.sent.clone_from(&l.lights);
            l.handle.move_lights(l.lights.clone());
        }
    }

    /// Takes the relighting thread's publications.
    fn take_relit(&mut self) {
        let Some(mail) = self.lamps.handle.take() else {
            return;
        };
        let l = &mut self.lamps;
        if mail.built.is_some_and(|(world, _)| world == l.world_id()) {
            l.built = true;
        }
        if let Some((_, walk)) = mail.walk.filter(|(w, _)| *w == l.world_id()) {
            if l.lights.is_empty()
                && let Some(&start) = walk.first()
            {
                l.lights.push(PointLight::new(start, l.power));
            }
            l.walk = Some(walk);
        }
        match mail.state {
            Some(RelitState::Ready(frame)) if frame.world == l.world_id() => {
                if l.top.is_none() {
                    l.top = Some(crate::lit::colour_top(&frame.mesh, &frame.b));
                }
                l.frame = Some(frame);
                l.state = RelitState::Idle;
            }
            Some(RelitState::Failed(why)) => {
                // A refused move: the lights go back to the last lit positions.
                if let Some(f) = &l.frame {
                    l.lights.clone_from(&f.lights);
                    l.sent.clone_from(&f.lights);
                }
                self.message = Some((why.clone(), true));
                l.state = RelitState::Failed(why);
            }
            Some(state @ RelitState::Building) => l.state = state,
            _ => {}
        }
    }

    /// Applies what the user did in the relit view: a grabbed light follows the pointer, a
    /// click adds one, a right click deletes one (any of them stops the wander).
    pub(super) fn apply_lamps(&mut self, out: &LampsOut) {
        let Some(world) = self.lamps.world.clone() else {
            return;
        };
        let kernel = &world.kernel;
        if out.moved.is_some() || out.added.is_some() || out.deleted.is_some() {
            self.settings.wander = false;
        }
        if let Some((i, to)) = out.moved
            && i < self.lamps.lights.len()
        {
            match refused(kernel, to) {
                None => self.lamps.lights[i].at = to,
                Some(why) => {
                    self.message = Some((
                        format!("light {i} stays: ({:.2}, {:.2}) is {why}", to.x, to.y),
                        true,
                    ));
                }
            }
        }
        if let Some(at) = out.added {
            match refused(kernel, at) {
                None => {
                    let power = self.lamps.power;
                    self.lamps.lights.push(PointLight::new(at, power));
                }
                Some(why) => {
                    self.message = Some((
                        format!("no light added: ({:.2}, {:.2}) is {why}", at.x, at.y),
                        true,
                    ));
                }
            }
        }
        if let Some(i) = out.deleted.filter(|&i| i < self.lamps.lights.len()) {
            self.lamps.lights.remove(i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wander_runs_back_and_forth_along_the_walk() {
        let walk = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 2.0),
        ];
        assert_eq!(along_walk(&walk, 0.0), walk[0]);
        assert_eq!(along_walk(&walk, 0.5), DVec2::new(0.5, 0.0));
        assert_eq!(along_walk(&walk, 2.0), walk[2]);
        assert_eq!(along_walk(&walk, 2.5), DVec2::new(1.0, 1.0), "back again");
        assert_eq!(along_walk(&walk, 3.5), DVec2::new(0.5, 0.0));
        assert_eq!(along_walk(&walk, 4.0), walk[0]);
        assert_eq!(along_walk(&walk[..1], 7.0), walk[0]);
    }

    #[test]
    fn a_light_is_kept_in_the_rooms_and_off_the_walls() {
        let kernel = Kernel::new(flatland_geom::bundled::scene("floorplan").unwrap());
        let wall = kernel.scene().edges()[0];
        assert_eq!(refused(&kernel, (wall.a + wall.b) / 2.0), Some("on a wall"));
        let walked = flatland_geom::walk(&kernel, &flatland_geom::WalkParams::new(1, 3)).unwrap();
        assert_eq!(refused(&kernel, walked.positions[0]), None);
        assert!(light_power(&kernel) > 0.0);
    }
}
