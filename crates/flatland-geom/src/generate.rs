//! Realistic scenes from a seed: floor plans and halls, from a few dozen edges to 10⁵.
//!
//! Both are built from solid, one-sided objects, the way a user models a building in Flatland:
//!
//! - **Floor plan** ([`floor_plan`]): a grid of rooms of random widths (3–6) and depths (3–5.5)
//!   inside a closed outer wall. Interior walls are 0.2 thick boxes whose faces point into the
//!   rooms. Every room is reachable: a random spanning tree of the rooms gets a door (0.9 wide)
//!   or, one time in seven, no wall at all (an open plan); one other wall in four gets a door
//!   too. Rooms hold 0–3 pieces of furniture (solid boxes, one in five turned by a random angle)
//!   kept clear of the doors, and floor lamps (small emitting boxes): two, or one per twelve
//!   rooms in larger plans.
//! - **Hall** ([`hall`]): one large room, cluttered with solid boxes (crates, and one in four a
//!   long shelf) at least 0.3 apart, lit by skylights (emitting pieces of the ceiling): one per
//!   15 units of width, at least one.
//!
//! Both also come **lit by point lights** instead ([`generate_lit`], [`floor_plan_lit`],
//! [`hall_lit`]), with no edge emitting: a floor plan gets a lamp in every room (a
//! [`PointLight`] of power 8, kept 0.4 clear of walls, doors and furniture, which are placed
//! around it), a hall one lamp per 10 units of width, 0.5 under the ceiling, over the clear
//! band the boxes leave there, and its skylights are plain ceiling. The walls, doors and
//! furniture are drawn from the same seed stream, so they are not the same as the emitting
//! version's: only what a seed gives is fixed.
//!
//! Nothing overlaps or hides inside another object: where a wall abuts another, the covered
//! part of the face is left out, so every surface can be lit. A scene's edge count is close to
//! the size asked for ([`GenerateParams::edges`], within a fifth for sizes from 100 up), and the
//! same parameters give the same scene on every machine.

use std::f64::consts::TAU;

use glam::DVec2;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{Edge, GeomError, PointLight, Scene};

/// Which kind of scene [`generate`] builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// Rooms, thick walls, doors, furniture and lamps ([`floor_plan`]).
    FloorPlan,
    /// A large room full of boxes under skylights ([`hall`]).
    Hall,
}

/// What to generate: the kind, about how many edges, and the seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GenerateParams {
    /// The kind of scene.
    pub kind: SceneKind,
    /// About this many edges. Valid: [`MIN_EDGES`, `MAX_EDGES`].
    pub edges: usize,
    /// The seed: the same parameters give the same scene.
    pub seed: u64,
}

/// Smallest size [`generate`] accepts: one room with its furniture, or a small hall.
pub const MIN_EDGES: usize = 24;
/// Largest size [`generate`] accepts.
pub const MAX_EDGES: usize = 1_000_000;
// The error message spells the range out; keep it equal to the constants.
const _: () = assert!(MIN_EDGES == 24 && MAX_EDGES == 1_000_000);

impl GenerateParams {
    /// Checks the size; the error names the valid range.
    pub fn check(&self) -> Result<(), GeomError> {
        if (MIN_EDGES..=MAX_EDGES).contains(&self.edges) {
            Ok(())
        } else {
            Err(GeomError::Param {
                name: "edges",
                range: "[24, 1000000]",
                value: self.edges as f64,
            })
        }
    }
}

/// The scene `params` describe, lit by emitting edges (see the module docs).
pub fn generate(params: &GenerateParams) -> Result<Scene, GeomError> {
    build(params, Lamps::Emitting)
}

/// The scene `params` describe, lit by point lights, no edge emitting (see the module docs).
pub fn generate_lit(params: &GenerateParams) -> Result<Scene, GeomError> {
    build(params, Lamps::Points)
}

/// How the generated scene is lit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lamps {
    /// Emitting boxes (floor plans) and skylights (halls).
    Emitting,
    /// Point lights.
    Points,
}

fn build(params: &GenerateParams, lamps: Lamps) -> Result<Scene, GeomError> {
    params.check()?;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let (edges, lights) = match params.kind {
        SceneKind::FloorPlan => floor_plan_edges(params.edges, lamps, &mut rng),
        SceneKind::Hall => hall_edges(params.edges, lamps, &mut rng),
    };
    Scene::new(edges)?.with_lights(lights)
}

/// A floor plan of about `edges` edges (see the module docs).
pub fn floor_plan(edges: usize, seed: u64) -> Result<Scene, GeomError> {
    generate(&GenerateParams {
        kind: SceneKind::FloorPlan,
        edges,
        seed,
    })
}

/// A hall of about `edges` edges (see the module docs).
pub fn hall(edges: usize, seed: u64) -> Result<Scene, GeomError> {
    generate(&GenerateParams {
        kind: SceneKind::Hall,
        edges,
        seed,
    })
}

/// A floor plan of about `edges` edges with a lamp (a point light) in every room and no
/// emitting edge (see the module docs).
pub fn floor_plan_lit(edges: usize, seed: u64) -> Result<Scene, GeomError> {
    generate_lit(&GenerateParams {
        kind: SceneKind::FloorPlan,
        edges,
        seed,
    })
}

/// A hall of about `edges` edges lit by point lights under its ceiling, no emitting edge
/// (see the module docs).
pub fn hall_lit(edges: usize, seed: u64) -> Result<Scene, GeomError> {
    generate_lit(&GenerateParams {
        kind: SceneKind::Hall,
        edges,
        seed,
    })
}

/// A room lamp's power.
const LAMP_POWER: f64 = 8.0;
/// A hall lamp's power.
const HALL_LAMP_POWER: f64 = 15.0;

/// Interior wall thickness.
const WALL: f64 = 0.2;
/// Door width.
const DOOR: f64 = 0.9;
/// Clearance kept free around a door's centre, on both sides of the wall.
const DOOR_CLEARANCE: f64 = 1.0;
/// Edges a room brings on average (walls, doors, furniture, lamps), measured on large plans.
const EDGES_PER_ROOM: f64 = 12.5;
/// Smallest gap between two objects, and between an object and a wall.
const GAP: f64 = 0.3;

/// An axis-aligned or turned box, listed clockwise so its faces point out.
fn solid_box(center: DVec2, half: DVec2, angle: f64, reflectance: f64, emission: f64) -> [Edge; 4] {
    let (s, c) = angle.sin_cos();
    let turn = |p: DVec2| center + DVec2::new(c * p.x - s * p.y, s * p.x + c * p.y);
    let corners = [
        turn(DVec2::new(-half.x, -half.y)),
        turn(DVec2::new(-half.x, half.y)),
        turn(DVec2::new(half.x, half.y)),
        turn(DVec2::new(half.x, -half.y)),
    ];
    std::array::from_fn(|i| {
        Edge::surface(corners[i], corners[(i + 1) % 4], reflectance).with_emission(emission)
    })
}

/// The corners of a box, for overlap tests: its bounding box grown by `margin`.
fn bounds(center: DVec2, half: DVec2, angle: f64, margin: f64) -> (DVec2, DVec2) {
    let (s, c) = angle.sin_cos();
    let reach = DVec2::new(
        c.abs() * half.x + s.abs() * half.y,
        s.abs() * half.x + c.abs() * half.y,
    ) + margin;
    (center - reach, center + reach)
}

fn overlaps(a: (DVec2, DVec2), b: (DVec2, DVec2)) -> bool {
    a.0.x < b.1.x && b.0.x < a.1.x && a.0.y < b.1.y && b.0.y < a.1.y
}

/// One face of an axis-aligned wall: the part of `[lo, hi]` along the line outside the `cuts`,
/// as edges whose front is `normal` (one of ±x, ±y). `at` is the fixed coordinate.
fn wall_face(
    edges: &mut Vec<Edge>,
    at: f64,
    [lo, hi]: [f64; 2],
    mut cuts: Vec<[f64; 2]>,
    normal: DVec2,
    reflectance: f64,
) {
    cuts.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut pieces = Vec::new();
    let mut from = lo;
    for [c0, c1] in cuts {
        if c0 > from {
            pieces.push([from, c0.min(hi)]);
        }
        from = from.max(c1);
    }
    if hi > from {
        pieces.push([from, hi]);
    }
    let horizontal = normal.y != 0.0;
    let point = |u: f64| {
        if horizontal {
            DVec2::new(u, at)
        } else {
            DVec2::new(at, u)
        }
    };
    for [u0, u1] in pieces {
        if u1 - u0 < 1e-9 {
            continue;
        }
        let (p, q) = (point(u0), point(u1));
        // The front is the left of a → b: choose the direction that puts `normal` there.
        let edge = if (q - p).perp().dot(normal) > 0.0 {
            Edge::surface(p, q, reflectance)
        } else {
            Edge::surface(q, p, reflectance)
        };
        edges.push(edge);
    }
}

/// A wall along one grid line between two rooms: present or not, and its doors' centres.
#[derive(Clone, Debug, Default)]
struct Wall {
    present: bool,
    doors: Vec<f64>,
}

/// The grid of rooms: column and row boundaries, and every interior wall.
struct Plan {
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// `horizontal[r][c]`: the wall on line `ys[r]` (r in 1..rows) over column c. Always present.
    horizontal: Vec<Vec<Wall>>,
    /// `vertical[r][c]`: the wall on line `xs[c]` (c in 1..cols) over row r.
    vertical: Vec<Vec<Wall>>,
}

impl Plan {
    fn new(rows: usize, cols: usize, rng: &mut impl Rng) -> Plan {
        let mut boundaries = |n: usize, lo: f64, hi: f64| {
            let mut v = vec![0.0];
            for _ in 0..n {
                let next = v.last().unwrap() + rng.random_range(lo..hi);
                v.push(next);
            }
            v
        };
        let xs = boundaries(cols, 3.0, 6.0);
        let ys = boundaries(rows, 3.0, 5.5);
        let solid = |n: usize, m: usize| {
            vec![
                vec![
                    Wall {
                        present: true,
                        doors: Vec::new()
                    };
                    m
                ];
                n
            ]
        };
        let mut plan = Plan {
            xs,
            ys,
            horizontal: solid(rows, cols),
            vertical: solid(rows, cols),
        };
        plan.connect(rows, cols, rng);
        plan
    }

    /// Doors (or open walls) along a random spanning tree of the rooms, plus extra doors.
    fn connect(&mut self, rows: usize, cols: usize, rng: &mut impl Rng) {
        // Room adjacencies: (room, room, is the wall vertical, r, c).
        let room = |r: usize, c: usize| r * cols + c;
        let mut walls = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                if c + 1 < cols {
                    walls.push((room(r, c), room(r, c + 1), true, r, c + 1));
                }
                if r + 1 < rows {
                    walls.push((room(r, c), room(r + 1, c), false, r + 1, c));
                }
            }
        }
        // Random order, then Kruskal: a wall joining two unconnected parts gets an opening.
        for i in (1..walls.len()).rev() {
            walls.swap(i, rng.random_range(0..=i));
        }
        let mut parent: Vec<usize> = (0..rows * cols).collect();
        fn find(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        for (a, b, vertical, r, c) in walls {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            let tree = ra != rb;
            if tree {
                parent[ra] = rb;
            }
            let open = tree && vertical && rng.random_range(0..7) == 0;
            let door = tree || rng.random_range(0..4) == 0;
            let (lo, hi) = if vertical {
                (self.ys[r], self.ys[r + 1])
            } else {
                (self.xs[c], self.xs[c + 1])
            };
            let wall = if vertical {
                &mut self.vertical[r][c]
            } else {
                &mut self.horizontal[r][c]
            };
            if open {
                wall.present = false;
            } else if door {
                // Keep the door away from the walls that meet this one at its ends.
                let margin = WALL / 2.0 + DOOR / 2.0 + GAP;
                wall.doors.push(rng.random_range(lo + margin..hi - margin));
            }
        }
    }

    /// Every wall face, cut where another wall abuts it.
    fn wall_edges(&self, edges: &mut Vec<Edge>, rng: &mut impl Rng) {
        let (rows, cols) = (self.ys.len() - 1, self.xs.len() - 1);
        let (w, h) = (self.xs[cols], self.ys[rows]);
        let half = WALL / 2.0;
        let mut rho = || rng.random_range(0.45..0.75);
        // Where vertical walls of row r abut a horizontal line (their x extents).
        let abut_x = |r: usize| -> Vec<[f64; 2]> {
            (1..cols)
                .filter(|&c| self.vertical[r][c].present)
                .map(|c| [self.xs[c] - half, self.xs[c] + half])
                .collect()
        };
        let abut_y: Vec<[f64; 2]> = (1..rows)
            .map(|r| [self.ys[r] - half, self.ys[r] + half])
            .collect();
        // The outer wall, facing in.
        wall_face(edges, 0.0, [0.0, w], abut_x(0), DVec2::Y, rho());
        wall_face(edges, h, [0.0, w], abut_x(rows - 1), -DVec2::Y, rho());
        wall_face(edges, 0.0, [0.0, h], abut_y.clone(), DVec2::X, rho());
        wall_face(edges, w, [0.0, h], abut_y, -DVec2::X, rho());
        // Horizontal lines: boxes between doors, faces cut where vertical walls abut.
        for r in 1..rows {
            let y = self.ys[r];
            let doors: Vec<f64> = (0..cols)
                .flat_map(|c| self.horizontal[r][c].doors.iter().copied())
                .collect();
            let (below, above) = (abut_x(r - 1), abut_x(r));
            let rho = rho();
            for [x0, x1] in pieces_between([0.0, w], &doors) {
                let within = |cuts: &[[f64; 2]]| -> Vec<[f64; 2]> {
                    cuts.iter()
                        .copied()
                        .filter(|c| c[0] > x0 && c[1] < x1)
                        .collect()
                };
                wall_face(edges, y - half, [x0, x1], within(&below), -DVec2::Y, rho);
                wall_face(edges, y + half, [x0, x1], within(&above), DVec2::Y, rho);
                if x0 > 0.0 {
                    wall_face(edges, x0, [y - half, y + half], vec![], -DVec2::X, rho);
                }
                if x1 < w {
                    wall_face(edges, x1, [y - half, y + half], vec![], DVec2::X, rho);
                }
            }
        }
        // Vertical walls: from one horizontal line (or the outer wall) to the next.
        for r in 0..rows {
            let y0 = if r == 0 { 0.0 } else { self.ys[r] + half };
            let y1 = if r + 1 == rows {
                h
            } else {
                self.ys[r + 1] - half
            };
            for c in 1..cols {
                let wall = &self.vertical[r][c];
                if !wall.present {
                    continue;
                }
                let x = self.xs[c];
                let rho = rho();
                for [p0, p1] in pieces_between([y0, y1], &wall.doors) {
                    wall_face(edges, x - half, [p0, p1], vec![], -DVec2::X, rho);
                    wall_face(edges, x + half, [p0, p1], vec![], DVec2::X, rho);
                    if p0 > y0 {
                        wall_face(edges, p0, [x - half, x + half], vec![], -DVec2::Y, rho);
                    }
                    if p1 < y1 {
                        wall_face(edges, p1, [x - half, x + half], vec![], DVec2::Y, rho);
                    }
                }
            }
        }
    }

    /// Door centres as points, for keeping furniture clear of them.
    fn door_points(&self) -> Vec<DVec2> {
        let mut points = Vec::new();
        for (r, row) in self.horizontal.iter().enumerate() {
            for wall in row {
                points.extend(wall.doors.iter().map(|&x| DVec2::new(x, self.ys[r])));
            }
        }
        for (r, row) in self.vertical.iter().enumerate() {
            for (c, wall) in row.iter().enumerate() {
                let y = |d: f64| DVec2::new(self.xs[c], d);
                points.extend(wall.doors.iter().map(|&d| y(d)));
                if !wall.present && c > 0 {
                    // An open wall is a wide door: keep its middle clear too.
                    points.push(y((self.ys[r] + self.ys[r + 1]) / 2.0));
                }
            }
        }
        points
    }
}

/// `[lo, hi]` minus a door of width [`DOOR`] at each centre.
fn pieces_between([lo, hi]: [f64; 2], doors: &[f64]) -> Vec<[f64; 2]> {
    let mut doors = doors.to_vec();
    doors.sort_by(f64::total_cmp);
    let mut pieces = Vec::new();
    let mut from = lo;
    for d in doors {
        pieces.push([from, d - DOOR / 2.0]);
        from = d + DOOR / 2.0;
    }
    pieces.push([from, hi]);
    pieces
}

/// Places boxes in the rectangle `[lo, hi]` without overlapping `taken` (grown by [`GAP`]) or
/// coming within [`DOOR_CLEARANCE`] of a door; gives up on a box after a few tries.
struct Placer {
    taken: Vec<(DVec2, DVec2)>,
    doors: Vec<DVec2>,
}

impl Placer {
    fn place(
        &mut self,
        (lo, hi): (DVec2, DVec2),
        half: DVec2,
        angle: f64,
        rng: &mut impl Rng,
    ) -> Option<DVec2> {
        let reach = bounds(DVec2::ZERO, half, angle, GAP).1;
        let (min, max) = (lo + reach, hi - reach);
        if min.x >= max.x || min.y >= max.y {
            return None;
        }
        for _ in 0..20 {
            let center = DVec2::new(
                rng.random_range(min.x..max.x),
                rng.random_range(min.y..max.y),
            );
            let b = bounds(center, half, angle, GAP);
            let near_door = self.doors.iter().any(|&d| {
                let nearest = d.clamp(b.0, b.1);
                nearest.distance(d) < DOOR_CLEARANCE
            });
            if !near_door && !self.taken.iter().any(|&t| overlaps(t, b)) {
                self.taken.push(bounds(center, half, angle, 0.0));
                return Some(center);
            }
        }
        None
    }
}

fn floor_plan_edges(
    target: usize,
    lamps: Lamps,
    rng: &mut ChaCha8Rng,
) -> (Vec<Edge>, Vec<PointLight>) {
    let rooms = (target as f64 / EDGES_PER_ROOM).max(1.0);
    let cols = (rooms * 4.0 / 3.0).sqrt().round().max(1.0) as usize;
    let rows = (rooms / cols as f64).round().max(1.0) as usize;
    let plan = Plan::new(rows, cols, rng);
    let mut edges = Vec::new();
    plan.wall_edges(&mut edges, rng);
    let mut placer = Placer {
        taken: Vec::new(),
        doors: plan.door_points(),
    };
    let half = WALL / 2.0;
    let room_area = |r: usize, c: usize| {
        (
            DVec2::new(plan.xs[c] + half, plan.ys[r] + half),
            DVec2::new(plan.xs[c + 1] - half, plan.ys[r + 1] - half),
        )
    };
    // Lamps first, so every plan has its light wherever the furniture goes.
    let half = DVec2::splat(0.1);
    let mut lights = Vec::new();
    if lamps == Lamps::Points {
        // One per room; its little box is only kept free, so the lamp stands 0.4 from
        // anything (a room too cluttered by doors for it stays dark).
        for r in 0..rows {
            for c in 0..cols {
                if let Some(center) = placer.place(room_area(r, c), half, 0.0, rng) {
                    lights.push(PointLight::new(center, LAMP_POWER));
                }
            }
        }
    }
    let emitting = if lamps == Lamps::Emitting {
        (rows * cols / 12).max(2)
    } else {
        0
    };
    let mut lit = 0;
    while lit < emitting {
        let (r, c) = (rng.random_range(0..rows), rng.random_range(0..cols));
        if let Some(center) = placer.place(room_area(r, c), half, 0.0, rng) {
            edges.extend(solid_box(center, half, 0.0, 0.3, 10.0));
            lit += 1;
        }
    }
    for r in 0..rows {
        for c in 0..cols {
            for _ in 0..rng.random_range(0..=3) {
                let half = DVec2::new(rng.random_range(0.2..0.9), rng.random_range(0.2..0.5));
                let angle = if rng.random_range(0..5) == 0 {
                    rng.random_range(0.0..TAU)
                } else {
                    f64::from(rng.random_range(0..2_u8)) * TAU / 4.0
                };
                let rho = rng.random_range(0.2..0.8);
                if let Some(center) = placer.place(room_area(r, c), half, angle, rng) {
                    edges.extend(solid_box(center, half, angle, rho, 0.0));
                }
            }
        }
    }
    (edges, lights)
}

fn hall_edges(target: usize, lamps: Lamps, rng: &mut ChaCha8Rng) -> (Vec<Edge>, Vec<PointLight>) {
    let boxes = target.saturating_sub(8).max(4) / 4;
    // About 10 units of floor per box, 3 : 2.
    let area = 10.0 * boxes as f64;
    let (w, h) = ((area * 1.5).sqrt().max(8.0), (area / 1.5).sqrt().max(6.0));
    let mut edges = Vec::new();
    let v = DVec2::new;
    // Floor and walls, facing in; the ceiling (from right to left) carries the skylights.
    edges.push(Edge::surface(v(0.0, 0.0), v(w, 0.0), 0.6));
    edges.push(Edge::surface(v(w, 0.0), v(w, h), 0.55));
    let skylights = ((w / 15.0).round() as usize).max(1);
    let mut x = w;
    for i in (0..skylights).rev() {
        let center = w * (i as f64 + 0.5) / skylights as f64;
        let half = rng.random_range(1.0..2.0);
        edges.push(Edge::surface(v(x, h), v(center + half, h), 0.55));
        let skylight = Edge::surface(v(center + half, h), v(center - half, h), 0.2);
        edges.push(match lamps {
            Lamps::Emitting => skylight.with_emission(5.0),
            Lamps::Points => Edge {
                reflectance: 0.55,
                ..skylight
            },
        });
        x = center - half;
    }
    edges.push(Edge::surface(v(x, h), v(0.0, h), 0.55));
    edges.push(Edge::surface(v(0.0, h), v(0.0, 0.0), 0.55));
    // Boxes, placed on a grid of buckets so a large hall is as quick as a small one.
    let mut grid = BucketGrid::new(w, h, 4.0);
    let mut placed = 0;
    let mut tries = 0;
    while placed < boxes && tries < 50 * boxes {
        tries += 1;
        let half = if rng.random_range(0..4) == 0 {
            v(rng.random_range(1.5..3.0), rng.random_range(0.25..0.4))
        } else {
            v(rng.random_range(0.25..0.9), rng.random_range(0.25..0.9))
        };
        let angle = if rng.random_range(0..5) == 0 {
            rng.random_range(0.0..TAU)
        } else {
            f64::from(rng.random_range(0..2_u8)) * TAU / 4.0
        };
        let reach = bounds(DVec2::ZERO, half, angle, 0.0).1;
        let margin = reach + 0.5;
        if margin.x * 2.0 >= w || margin.y * 2.0 >= h - 1.0 {
            continue;
        }
        // Keep a clear band under the ceiling so the skylights light the floor.
        let center = v(
            rng.random_range(margin.x..w - margin.x),
            rng.random_range(margin.y..h - 1.0 - margin.y),
        );
        let b = bounds(center, half, angle, GAP);
        if grid.free(b) {
            grid.insert(bounds(center, half, angle, 0.0));
            edges.extend(solid_box(
                center,
                half,
                angle,
                rng.random_range(0.2..0.8),
                0.0,
            ));
            placed += 1;
        }
    }
    let lights = match lamps {
        Lamps::Emitting => Vec::new(),
        Lamps::Points => hall_lamps(w, h),
    };
    (edges, lights)
}

/// A hall's lamps: one per 10 units of width, in the band under the ceiling that no box
/// reaches (boxes end 1.5 below it).
fn hall_lamps(w: f64, h: f64) -> Vec<PointLight> {
    let count = ((w / 10.0).round() as usize).max(1);
    (0..count)
        .map(|i| {
            let x = w * (i as f64 + 0.5) / count as f64;
            PointLight::new(DVec2::new(x, h - 0.5), HALL_LAMP_POWER)
        })
        .collect()
}

/// Boxes filed by the square buckets they touch, for overlap tests in large halls.
struct BucketGrid {
    size: f64,
    cols: usize,
    rows: usize,
    buckets: Vec<Vec<(DVec2, DVec2)>>,
}

impl BucketGrid {
    fn new(w: f64, h: f64, size: f64) -> BucketGrid {
        let (cols, rows) = (
            (w / size).ceil() as usize + 1,
            (h / size).ceil() as usize + 1,
        );
        BucketGrid {
            size,
            cols,
            rows,
            buckets: vec![Vec::new(); cols * rows],
        }
    }

    fn cells(&self, (lo, hi): (DVec2, DVec2)) -> impl Iterator<Item = usize> + '_ {
        let clamp = |u: f64, n: usize| ((u / self.size).floor().max(0.0) as usize).min(n - 1);
        let (c0, c1) = (clamp(lo.x, self.cols), clamp(hi.x, self.cols));
        let (r0, r1) = (clamp(lo.y, self.rows), clamp(hi.y, self.rows));
        (r0..=r1).flat_map(move |r| (c0..=c1).map(move |c| r * self.cols + c))
    }

    fn free(&self, b: (DVec2, DVec2)) -> bool {
        self.cells(b)
            .all(|i| !self.buckets[i].iter().any(|&t| overlaps(t, b)))
    }

    fn insert(&mut self, b: (DVec2, DVec2)) {
        let cells: Vec<usize> = self.cells(b).collect();
        for i in cells {
            self.buckets[i].push(b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Kernel;

    fn emitters(scene: &Scene) -> usize {
        scene.edges().iter().filter(|e| e.emission > 0.0).count()
    }

    #[test]
    fn sizes_land_near_the_size_asked_for() {
        for kind in [SceneKind::FloorPlan, SceneKind::Hall] {
            for edges in [100, 300, 1000, 10_000] {
                let scene = generate(&GenerateParams {
                    kind,
                    edges,
                    seed: 3,
                })
                .unwrap();
                let n = scene.edges().len() as f64;
                let ratio = n / edges as f64;
                assert!((0.8..=1.2).contains(&ratio), "{kind:?} {edges}: {n} edges");
                assert!(emitters(&scene) >= 1, "{kind:?} {edges}: nothing emits");
            }
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_scene_and_another_seed_another() {
        let a = floor_plan(300, 7).unwrap();
        assert_eq!(a, floor_plan(300, 7).unwrap());
        assert_ne!(a, floor_plan(300, 8).unwrap());
        assert_eq!(hall(300, 7).unwrap(), hall(300, 7).unwrap());
    }

    #[test]
    fn a_size_outside_the_range_is_refused_with_the_range() {
        let err = floor_plan(3, 1).unwrap_err().to_string();
        assert!(err.contains("[24, 1000000]") && err.contains('3'), "{err}");
    }

    /// Every surface is solid and faces free space: no edge crosses another's interior, and no
    /// light leaves the building: every sender's light lands on a surface (`∫ G V dl = 1`) — a
    /// hidden or inside-out face would break one or the other.
    #[test]
    fn edges_never_cross_and_every_sender_sees_a_closed_scene() {
        use crate::visibility::orient;
        for scene in [floor_plan(200, 2).unwrap(), hall(200, 2).unwrap()] {
            let e = scene.edges();
            for i in 0..e.len() {
                for j in i + 1..e.len() {
                    let (p, q) = ((e[i].a, e[i].b), (e[j].a, e[j].b));
                    let proper = orient(p.0, p.1, q.0) * orient(p.0, p.1, q.1) < 0.0
                        && orient(q.0, q.1, p.0) * orient(q.0, q.1, p.1) < 0.0;
                    assert!(!proper, "edges {i} and {j} cross");
                }
            }
            let kernel = Kernel::new(scene.clone());
            let l = scene.total_length();
            for &s in &[0.1234, 0.377, 0.5511, 0.81] {
                // Midpoint rule in t, fine enough for a 1 % check away from corners.
                let n = 200_000;
                let sum: f64 = (0..n)
                    .map(|k| {
                        let t = (k as f64 + 0.5) / n as f64;
                        let sample = kernel.eval(s, t);
                        if sample.visible { sample.geometry } else { 0.0 }
                    })
                    .sum();
                let total = sum * l / n as f64;
                assert!((total - 1.0).abs() < 0.02, "s = {s}: ∫ G V = {total}");
            }
        }
    }

    /// Lit by lamps: no edge emits, every room of a plan has its lamp (but for rooms too
    /// crowded by doors), each lamp at least 0.4 from every edge; a hall's lamps hang in its
    /// clear band. Same seed, same scene.
    #[test]
    fn lit_plans_and_halls_have_lamps_clear_of_everything_and_no_emitter() {
        for kind in [SceneKind::FloorPlan, SceneKind::Hall] {
            for edges in [100, 1000, 10_000] {
                let params = GenerateParams {
                    kind,
                    edges,
                    seed: 4,
                };
                let scene = generate_lit(&params).unwrap();
                assert_eq!(scene, generate_lit(&params).unwrap());
                assert_eq!(emitters(&scene), 0, "{kind:?} {edges}");
                let ratio = scene.edges().len() as f64 / edges as f64;
                assert!((0.75..=1.2).contains(&ratio), "{kind:?} {edges}: {ratio}");
                let lights = scene.lights();
                assert!(!lights.is_empty() && lights.iter().all(|l| l.power > 0.0));
                if kind == SceneKind::FloorPlan {
                    let rooms = edges as f64 / EDGES_PER_ROOM;
                    assert!(lights.len() as f64 >= 0.8 * rooms, "{} lamps", lights.len());
                }
                if edges <= 1000 {
                    for (i, l) in lights.iter().enumerate() {
                        let nearest = scene
                            .edges()
                            .iter()
                            .map(|e| distance_to_segment(l.at, e.a, e.b))
                            .fold(f64::INFINITY, f64::min);
                        assert!(nearest >= 0.4 - 1e-9, "{kind:?}: lamp {i} at {nearest}");
                    }
                }
            }
        }
        // The emitting version is unchanged by the lamps' code: same scene as before, no light.
        assert!(floor_plan(300, 7).unwrap().lights().is_empty());
        assert!(floor_plan_lit(300, 7).unwrap().is_lit());
        assert!(hall_lit(300, 7).unwrap().is_lit());
    }

    fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
        let d = b - a;
        let u = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        p.distance(a + d * u)
    }

    #[test]
    fn a_floor_plan_has_rooms_doors_furniture_and_two_lamps() {
        let scene = floor_plan(1000, 1).unwrap();
        assert!(emitters(&scene) >= 8, "two lamps of four faces");
        // Walls are 0.2 thick: many pairs of parallel faces 0.2 apart.
        let e = scene.edges();
        let thick = e
            .iter()
            .filter(|x| {
                e.iter().any(|y| {
                    let d = x.normal().dot(y.a - x.a);
                    x.normal().dot(y.normal()) < -0.99 && (d + WALL).abs() < 1e-9
                })
            })
            .count();
        assert!(thick > 20, "{thick} faces of thick walls");
        let turned = e
            .iter()
            .filter(|x| {
                let d = x.b - x.a;
                d.x.abs() > 1e-9 && d.y.abs() > 1e-9
            })
            .count();
        assert!(turned > 0, "some furniture is turned");
    }
}
