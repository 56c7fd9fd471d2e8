//! Shared test helpers: scene generators; `assert_close!` and the seeded generator are the
//! workspace's (`flatland_testkit`), re-exported where the crate's tests have always named them.

use glam::DVec2;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

pub use flatland_testkit::rng;

use crate::{Edge, Scene};

/// A counter-clockwise (inward-facing) closed polygon room with reflectance `rho`.
pub fn room(points: &[DVec2], rho: f64) -> Vec<Edge> {
    Edge::polygon(points, rho)
}

/// The unit-square box room (4 surfaces, the floor emits).
pub fn unit_box() -> Scene {
    let mut edges = room(&flatland_testkit::rooms::unit_square(), 0.5);
    edges[0].emission = 1.0;
    Scene::new(edges).unwrap()
}

/// The bundled scene `NAME`.
pub fn bundled(name: &str) -> Scene {
    crate::bundled::scene(name).unwrap()
}

/// A random point in `[-1, 1]²`.
pub fn point(rng: &mut ChaCha8Rng) -> DVec2 {
    DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
}

/// A random valid scene from `seed`: 2–12 edges, random roles and materials; blockers are
/// two-sided at random. With `snap`, coordinates are multiples of ½ in `[-1, 1]`, so shared end
/// points, collinear, overlapping and touching edges (the grazing cases) are common, and some
/// surfaces get a twin back to back (a thin wall: the same end points, swapped).
pub fn random_scene(seed: u64, snap: bool) -> Scene {
    let mut r = rng(seed);
    let n = r.random_range(2..=12);
    let pick = |r: &mut ChaCha8Rng| {
        let p = point(r);
        if snap { (p * 2.0).round() / 2.0 } else { p }
    };
    let mut edges: Vec<Edge> = Vec::new();
    while edges.len() < n {
        let a = pick(&mut r);
        // Often continue from the previous end point (chains, corners).
        let a = match edges.last() {
            Some(e) if r.random_bool(0.4) => e.b,
            _ => a,
        };
        let b = pick(&mut r);
        if a == b {
            continue;
        }
        let mut e = Edge::surface(a, b, r.random_range(0.0..=1.0));
        if r.random_bool(0.2) {
            e.emission = r.random_range(0.0..3.0);
        }
        let twin = r.random_bool(0.25);
        if !edges.is_empty() && r.random_bool(0.3) {
            e.role = crate::Role::Blocker;
            e.two_sided = twin;
        }
        edges.push(e);
        if snap && twin && e.role == crate::Role::Surface && edges.len() < n {
            edges.push(Edge {
                a: e.b,
                b: e.a,
                ..e
            });
        }
    }
    Scene::new(edges).unwrap()
}

/// The walls of the box `[x0, x1] × [y0, y1]`, clockwise so they face outwards.
pub fn outward_box(x0: f64, y0: f64, x1: f64, y1: f64, rho: f64) -> Vec<Edge> {
    let p = [
        DVec2::new(x0, y0),
        DVec2::new(x0, y1),
        DVec2::new(x1, y1),
        DVec2::new(x1, y0),
    ];
    Edge::polygon(&p, rho)
}

/// Scenes where solid boxes touch other surfaces: standing on a floor (their feet on it, their
/// bottoms along it), against each other, against walls, in a room's corners (sharing its end
/// points), and the maze with its partitions as thin boxes on floor and ceiling. The events of
/// a pair here include occluder end points on the pair's own edges and occluders along them.
pub fn touching_scenes() -> Vec<(&'static str, Scene)> {
    let v = DVec2::new;
    // A 4 × 3 room with a lamp in the ceiling.
    let room = || {
        let mut edges = room(
            &[
                v(0.0, 0.0),
                v(4.0, 0.0),
                v(4.0, 3.0),
                v(2.5, 3.0),
                v(1.5, 3.0),
                v(0.0, 3.0),
            ],
            0.5,
        );
        edges[0].reflectance = 0.7;
        edges[3].emission = 1.0;
        edges
    };
    let scene = |mut edges: Vec<Edge>, boxes: &[[f64; 4]]| {
        for &[x0, y0, x1, y1] in boxes {
            edges.extend(outward_box(x0, y0, x1, y1, 0.6));
        }
        Scene::new(edges).unwrap()
    };
    let floor = scene(
        room(),
        &[
            [0.5, 0.0, 1.0, 0.8],
            [1.5, 0.0, 1.7, 1.5],
            [1.7, 0.0, 2.0, 0.6],
            [2.5, 0.0, 3.25, 0.4],
        ],
    );
    let corners = scene(
        room(),
        &[
            [0.0, 0.0, 0.5, 0.5],
            [3.5, 2.5, 4.0, 3.0],
            [0.0, 1.5, 0.25, 1.75],
            [3.75, 0.0, 4.0, 1.0],
            [1.0, 0.0, 1.25, 0.25],
        ],
    );
    // The maze's room and blockers; its partitions become boxes 0.1 thick.
    let mut maze = room_of_maze();
    for (a, b) in [
        (v(2.2, 1.0), v(3.0, 1.4)),
        (v(4.0, 0.8), v(4.6, 0.5)),
        (v(0.5, 2.8), v(1.0, 3.2)),
        (v(2.6, 2.6), v(3.2, 2.9)),
        (v(0.4, 1.2), v(0.9, 1.0)),
        (v(5.5, 0.6), v(5.8, 1.1)),
        (v(2.0, 3.3), v(2.0, 3.7)),
        (v(3.9, 1.5), v(3.9, 1.2)),
    ] {
        maze.push(Edge::blocker(a, b));
    }
    let maze = scene(maze, &[[1.45, 0.0, 1.55, 2.2], [5.15, 1.2, 5.25, 4.0]]);
    vec![("floor", floor), ("corners", corners), ("maze", maze)]
}

/// The walls of the bundled maze's concave room (the notch hangs from the ceiling).
fn room_of_maze() -> Vec<Edge> {
    let v = DVec2::new;
    let mut edges = room(
        &[
            v(0.0, 0.0),
            v(6.0, 0.0),
            v(6.0, 4.0),
            v(4.5, 4.0),
            v(4.5, 2.0),
            v(3.5, 2.0),
            v(3.5, 4.0),
            v(2.5, 4.0),
            v(1.5, 4.0),
            v(0.0, 4.0),
        ],
        0.5,
    );
    edges[0].reflectance = 0.6;
    for e in &mut edges[3..6] {
        e.reflectance = 0.4;
    }
    edges[7].emission = 1.0;
    edges
}

/// Nodes and weights of 16-point Gauss–Legendre on `[-1, 1]`.
pub const GAUSS16: [(f64, f64); 8] = [
    (0.095_012_509_837_637_44, 0.189_450_610_455_068_47),
    (0.281_603_550_779_258_9, 0.182_603_415_044_923_6),
    (0.458_016_777_657_227_37, 0.169_156_519_395_002_56),
    (0.617_876_244_402_643_8, 0.149_595_988_816_576_82),
    (0.755_404_408_355_003, 0.124_628_971_255_533_95),
    (0.865_631_202_387_831_8, 0.095_158_511_682_492_9),
    (0.944_575_023_073_232_6, 0.062_253_523_938_647_776),
    (0.989_400_934_991_649_9, 0.027_152_459_411_754_058),
];

/// `∫ f` over `[a, b]` with 16-point Gauss–Legendre.
pub fn gauss(a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let (c, h) = ((a + b) / 2.0, (b - a) / 2.0);
    GAUSS16
        .iter()
        .map(|&(x, w)| w * (f(c - h * x) + f(c + h * x)))
        .sum::<f64>()
        * h
}

#[test]
fn gauss16_is_exact_for_degree_31() {
    flatland_testkit::assert_close!(
        gauss(-1.0, 1.0, |x| x.powi(30) + x.powi(31)),
        2.0 / 31.0,
        1e-14
    );
    flatland_testkit::assert_close!(gauss(0.0, 2.0, |x| x * x), 8.0 / 3.0, 1e-14);
}
