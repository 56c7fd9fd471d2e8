//! A walk through free space: where a lamp carried through a scene's rooms and doors goes.
//!
//! The walker starts from a free point — the scene's first light when it stands clear, else the
//! most open of a seeded sample of points inside the scene (no probe ray from it meets the back
//! of a surface: it is in a room, not behind a wall or inside furniture) — and moves in steps
//! of a fraction of the local free space, turning smoothly: each step it looks around with
//! [`PROBES`] rays, wanders a little, leans towards the open directions (a door shows as a long
//! ray) and turns at most [`MAX_TURN`] towards them. A step is taken only if its path meets no
//! edge ([`Kernel::path_is_clear`]) and its end is at least the margin from every edge
//! ([`Kernel::nearest_edge_within`]), so the walk never crosses a wall and never puts a light
//! on one; a step that fails is halved, and a walker that is cornered turns to the most open
//! direction at once. Everything is drawn from one seeded stream: the same scene and
//! parameters give the same walk on every machine.

use std::f64::consts::{PI, TAU};

use glam::DVec2;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{GeomError, Kernel, Role};

/// Rays a walker looks around with at each step (evenly spread, the first straight ahead).
pub const PROBES: usize = 16;

/// Most a walker turns in one step, in radians: it turns smoothly unless cornered.
pub const MAX_TURN: f64 = 0.5;

/// Points sampled across the scene's bounds to find a free start.
pub const START_SAMPLES: usize = 4096;

/// Most positions a walk may have.
pub const MAX_POSITIONS: usize = 1_000_000;

/// Halvings of a step that meets an edge or comes too near one before the walker turns.
const HALVINGS: usize = 12;

/// The spread of the walker's wandering per step (radians, normal-ish).
const WANDER: f64 = 0.35;

/// What to walk: how many positions, from which seed, how far from the edges and how fast.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkParams {
    /// Positions, the start included. Valid: `1..=MAX_POSITIONS`.
    pub positions: usize,
    /// The seed of every random choice.
    pub seed: u64,
    /// The least distance from every edge, in scene units; `None`: a twentieth of the median
    /// length of the scene's whole edges ([`WalkParams::margin_for`]). Valid: finite, > 0.
    pub margin: Option<f64>,
    /// A step is this fraction of the local free space (the mean distance the probe rays
    /// travel, at most the way ahead). Valid: `(0, 1)`.
    pub step: f64,
}

impl WalkParams {
    /// `positions` from `seed`, the default margin and a step of a quarter of the free space.
    #[must_use]
    pub fn new(positions: usize, seed: u64) -> WalkParams {
        WalkParams {
            positions,
            seed,
            margin: None,
            step: 0.25,
        }
    }

    /// Checks every field; errors name it and its valid range.
    pub fn check(&self) -> Result<(), GeomError> {
        if !(1..=MAX_POSITIONS).contains(&self.positions) {
            return Err(GeomError::Param {
                name: "positions",
                range: "[1, 1000000]",
                value: self.positions as f64,
            });
        }
        if let Some(m) = self.margin.filter(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(GeomError::Param {
                name: "margin",
                range: "(0, inf), finite",
                value: m,
            });
        }
        if !(self.step > 0.0 && self.step < 1.0) {
            return Err(GeomError::Param {
                name: "step",
                range: "(0, 1)",
                value: self.step,
            });
        }
        Ok(())
    }

    /// The margin the walk keeps in `kernel`'s scene: the one given, or a twentieth of the
    /// median length of its whole edges (a door of the generated plans is 0.9 wide, their
    /// median edge about 1: the walker passes doors with room to spare).
    #[must_use]
    pub fn margin_for(&self, kernel: &Kernel) -> f64 {
        self.margin
            .unwrap_or_else(|| kernel.median_edge_length() / 20.0)
    }
}

/// A walk: its positions and the margin it kept.
#[derive(Clone, Debug, PartialEq)]
pub struct Walk {
    /// Where the walker was, the start first.
    pub positions: Vec<DVec2>,
    /// The least distance it kept from every edge.
    pub margin: f64,
}

/// Walks `params.positions` positions through `kernel`'s free space (see the module docs).
/// Errors: parameters out of range, or no free point at least the margin from every edge
/// inside the scene.
pub fn walk(kernel: &Kernel, params: &WalkParams) -> Result<Walk, GeomError> {
    params.check()?;
    let margin = params.margin_for(kernel);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let walker = Walker::new(kernel, margin);
    let start = walker.start(&mut rng)?;
    let mut positions = Vec::with_capacity(params.positions);
    positions.push(start);
    let mut at = start;
    let mut heading = rng.random_range(0.0..TAU);
    while positions.len() < params.positions {
        (at, heading) = walker.step(at, heading, params.step, &mut rng);
        positions.push(at);
    }
    Ok(Walk { positions, margin })
}

/// Whether `p` is in a room: no ray of [`PROBES`] evenly spread from it meets the back of a
/// surface (one that leaves the scene is fine: an open scene is one room). A point behind a
/// wall, inside a solid object or outside a closed building sees a back.
#[must_use]
pub fn in_a_room(kernel: &Kernel, p: DVec2) -> bool {
    (0..PROBES).all(|k| {
        let direction = DVec2::from_angle(TAU * k as f64 / PROBES as f64);
        kernel.first_hit(p, direction, None).is_none_or(|hit| {
            let edge = kernel.scene().edge(hit.edge);
            edge.role != Role::Surface || (edge.b - edge.a).perp_dot(p - edge.a) > 0.0
        })
    })
}

/// What every step asks of the scene.
struct Walker<'k> {
    kernel: &'k Kernel,
    margin: f64,
    /// The scene's bounds, shrunk by the margin: a walk in an open scene stays over it.
    lo: DVec2,
    hi: DVec2,
    /// How far a probe ray that leaves the scene counts: the bounds' diagonal.
    reach: f64,
}

impl<'k> Walker<'k> {
    fn new(kernel: &'k Kernel, margin: f64) -> Walker<'k> {
        let (lo, hi) = kernel.scene().bounds();
        Walker {
            kernel,
            margin,
            lo: lo + DVec2::splat(margin),
            hi: hi - DVec2::splat(margin),
            reach: lo.distance(hi),
        }
    }

    /// The scene's first light if it stands free, else the most open free point of a seeded
    /// sample of the bounds.
    fn start(&self, rng: &mut ChaCha8Rng) -> Result<DVec2, GeomError> {
        if let Some(light) = self.kernel.scene().lights().first()
            && self.free(light.at)
            && self.in_a_room(light.at)
        {
            return Ok(light.at);
        }
        let mut best: Option<(f64, DVec2)> = None;
        if self.lo.x < self.hi.x && self.lo.y < self.hi.y {
            for _ in 0..START_SAMPLES {
                let p = DVec2::new(
                    rng.random_range(self.lo.x..self.hi.x),
                    rng.random_range(self.lo.y..self.hi.y),
                );
                if !self.free(p) || !self.in_a_room(p) {
                    continue;
                }
                let openness = self.nearest(p);
                if best.is_none_or(|(o, _)| openness > o) {
                    best = Some((openness, p));
                }
            }
        }
        best.map(|(_, p)| p).ok_or(GeomError::NoFreeSpace {
            margin: self.margin,
            tries: START_SAMPLES,
        })
    }

    /// Whether `p` is over the (shrunk) bounds and at least the margin from every edge.
    fn free(&self, p: DVec2) -> bool {
        p.cmpge(self.lo).all()
            && p.cmple(self.hi).all()
            && self.kernel.nearest_edge_within(p, self.margin).is_none()
    }

    fn in_a_room(&self, p: DVec2) -> bool {
        in_a_room(self.kernel, p)
    }

    /// How far `p` is from the nearest edge (up to the bounds' diagonal).
    fn nearest(&self, p: DVec2) -> f64 {
        self.kernel
            .nearest_edge_within(p, self.reach)
            .unwrap_or(self.reach)
    }

    /// How far a ray from `p` along `angle` travels before it meets an edge or leaves the
    /// (shrunk) bounds.
    fn free_along(&self, p: DVec2, angle: f64) -> f64 {
        let d = DVec2::from_angle(angle);
        let hit = self
            .kernel
            .first_hit(p, d, None)
            .map_or(self.reach, |h| h.distance);
        // The distance to the bounds' border along d.
        let exit = [
            (d.x, p.x, self.lo.x, self.hi.x),
            (d.y, p.y, self.lo.y, self.hi.y),
        ]
        .into_iter()
        .filter(|&(di, ..)| di != 0.0)
        .map(|(di, pi, lo, hi)| {
            if di > 0.0 {
                (hi - pi) / di
            } else {
                (lo - pi) / di
            }
        })
        .fold(self.reach, f64::min);
        hit.min(exit.max(0.0))
    }

    /// One step from `at` heading `heading`: the new position and heading.
    fn step(&self, at: DVec2, heading: f64, fraction: f64, rng: &mut ChaCha8Rng) -> (DVec2, f64) {
        let angles: Vec<f64> = (0..PROBES)
            .map(|k| heading + TAU * k as f64 / PROBES as f64)
            .collect();
        let free: Vec<f64> = angles.iter().map(|&a| self.free_along(at, a)).collect();
        let room = free.iter().sum::<f64>() / PROBES as f64;
        // Wander a little, then lean towards the open directions near the wandered heading.
        let wandered = heading + WANDER * (rng.random::<f64>() + rng.random::<f64>() - 1.0) * 2.0;
        let score = |k: usize| {
            let ahead = 0.5 + 0.5 * (angles[k] - wandered).cos();
            free[k].sqrt() * ahead * ahead
        };
        let best = (0..PROBES)
            .max_by(|&i, &j| score(i).total_cmp(&score(j)))
            .expect("PROBES > 0");
        let turn = wrap(angles[best] - heading).clamp(-MAX_TURN, MAX_TURN);
        let smooth = heading + turn;
        if let Some(next) = self.advance(at, smooth, fraction * room) {
            return (next, wrap(smooth));
        }
        // Cornered: turn to the most open direction at once.
        let open = (0..PROBES)
            .max_by(|&i, &j| free[i].total_cmp(&free[j]))
            .expect("PROBES > 0");
        match self.advance(at, angles[open], fraction * room) {
            Some(next) => (next, wrap(angles[open])),
            None => (at, wrap(angles[open])),
        }
    }

    /// The point `length` from `at` along `angle` (at most a fraction of the way ahead),
    /// halved until its path is clear and its end free; `None` if no halving is.
    fn advance(&self, at: DVec2, angle: f64, length: f64) -> Option<DVec2> {
        let ahead = self.free_along(at, angle) - self.margin;
        let mut length = length.min(0.5 * ahead);
        if length <= 0.0 {
            return None;
        }
        let d = DVec2::from_angle(angle);
        for _ in 0..HALVINGS {
            let next = at + d * length;
            if self.free(next) && self.kernel.path_is_clear(at, next) {
                return Some(next);
            }
            length *= 0.5;
        }
        None
    }
}

/// `angle` in `(−π, π]`.
fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(TAU);
    if a > PI { a - TAU } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visibility::open_segment_hits;
    use crate::{Edge, PointLight, Scene};

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn distance_to_edges(scene: &Scene, p: DVec2) -> f64 {
        scene
            .edges()
            .iter()
            .map(|e| crate::kernel::point_segment_distance(p, e.a, e.b))
            .fold(f64::INFINITY, f64::min)
    }

    /// Every step checked against every edge: no crossing, the margin kept.
    fn assert_free(kernel: &Kernel, walk: &Walk) {
        let scene = kernel.scene();
        for (k, p) in walk.positions.iter().enumerate() {
            let d = distance_to_edges(scene, *p);
            assert!(d >= walk.margin, "position {k} at {p}: {d} from an edge");
        }
        for (k, pair) in walk.positions.windows(2).enumerate() {
            let crossed = scene
                .edges()
                .iter()
                .position(|e| open_segment_hits(pair[0], pair[1], e.a, e.b));
            assert_eq!(crossed, None, "step {k}: {} → {}", pair[0], pair[1]);
        }
    }

    #[test]
    fn a_walk_in_a_room_with_a_blocker_keeps_its_margin_and_is_seeded() {
        let mut edges = Edge::polygon(&[v(0.0, 0.0), v(4.0, 0.0), v(4.0, 3.0), v(0.0, 3.0)], 0.5);
        edges.push(Edge::blocker(v(1.0, 1.5), v(3.0, 1.5)));
        let kernel = Kernel::new(Scene::new(edges).unwrap());
        let params = WalkParams {
            margin: Some(0.1),
            ..WalkParams::new(400, 7)
        };
        let walk = walk(&kernel, &params).unwrap();
        assert_eq!(walk.positions.len(), 400);
        assert_free(&kernel, &walk);
        // It moves: most steps go somewhere, and it gets round the blocker to both sides.
        let moved = walk.positions.windows(2).filter(|w| w[0] != w[1]).count();
        assert!(moved > 390, "{moved} of 399 steps moved");
        assert!(
            walk.positions.iter().any(|p| p.y < 1.4) && walk.positions.iter().any(|p| p.y > 1.6)
        );
        assert_eq!(super::walk(&kernel, &params).unwrap(), walk, "seeded");
        let other = super::walk(&kernel, &WalkParams { seed: 8, ..params }).unwrap();
        assert_ne!(other.positions, walk.positions);
    }

    #[test]
    fn a_walk_through_a_generated_plan_passes_doors_and_starts_at_its_first_lamp() {
        let scene = crate::generate::floor_plan_lit(600, 11).unwrap();
        let first = scene.lights()[0].at;
        let kernel = Kernel::new(scene);
        let walk = walk(&kernel, &WalkParams::new(600, 3)).unwrap();
        assert_eq!(walk.positions[0], first);
        assert_free(&kernel, &walk);
        // Rooms are at most 6 × 5.5: a walk that goes farther than that left its room.
        let farthest = walk
            .positions
            .iter()
            .map(|p| p.distance(first))
            .fold(0.0, f64::max);
        assert!(farthest > 8.0, "stayed within {farthest} of the start");
    }

    #[test]
    fn a_start_is_found_in_a_room_not_behind_its_walls_and_a_light_on_no_free_point_is_skipped() {
        // A room whose walls are boxes: points inside the walls' thickness see their backs.
        let room = Edge::polygon(&[v(0.0, 0.0), v(3.0, 0.0), v(3.0, 2.0), v(0.0, 2.0)], 0.5);
        let outer = Edge::polygon(
            &[v(-1.0, -1.0), v(-1.0, 3.0), v(4.0, 3.0), v(4.0, -1.0)],
            0.5,
        );
        let edges: Vec<Edge> = room.into_iter().chain(outer).collect();
        // A light too near a wall for the margin: not a start.
        let scene = Scene::new(edges)
            .unwrap()
            .with_lights(vec![PointLight::new(v(0.01, 1.0), 1.0)])
            .unwrap();
        let kernel = Kernel::new(scene);
        let params = WalkParams {
            margin: Some(0.05),
            ..WalkParams::new(50, 1)
        };
        let walk = walk(&kernel, &params).unwrap();
        let start = walk.positions[0];
        assert!(
            start.x > 0.05 && start.x < 2.95 && start.y > 0.05 && start.y < 1.95,
            "{start}"
        );
        assert_free(&kernel, &walk);
        assert!(
            walk.positions
                .iter()
                .all(|p| p.x > 0.0 && p.x < 3.0 && p.y > 0.0 && p.y < 2.0)
        );
    }

    #[test]
    fn no_free_space_and_bad_parameters_are_refused_by_name() {
        let narrow = Edge::polygon(&[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 0.01), v(0.0, 0.01)], 0.5);
        let kernel = Kernel::new(Scene::new(narrow).unwrap());
        let params = WalkParams {
            margin: Some(0.1),
            ..WalkParams::new(10, 1)
        };
        let err = walk(&kernel, &params).unwrap_err().to_string();
        assert!(
            err.contains("no free point") && err.contains("0.1"),
            "{err}"
        );
        assert!(!err.contains('\n'), "{err}");
        for (bad, name) in [
            (WalkParams::new(0, 1), "positions"),
            (
                WalkParams {
                    margin: Some(-1.0),
                    ..WalkParams::new(5, 1)
                },
                "margin",
            ),
            (
                WalkParams {
                    step: 1.0,
                    ..WalkParams::new(5, 1)
                },
                "step",
            ),
        ] {
            let err = walk(&kernel, &bad).unwrap_err().to_string();
            assert!(err.starts_with(name), "{err}");
        }
    }
}
