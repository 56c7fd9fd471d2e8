//! Helpers shared by the solver's tests: bundled scenes, small rooms built in code, generated
//! scenes and random ones.

use flatland_geom::{DVec2, Edge, Scene};

use crate::{Mesh, SolveParams, TransferOperator, never, solve_operator};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The bundled scene `NAME`.
pub fn bundled(name: &str) -> Scene {
    flatland_geom::bundled::scene(name).expect("bundled scene")
}

/// A closed polygon room listed counter-clockwise (facing in), every wall with `rho` and `e`.
pub fn room(points: &[DVec2], rho: f64, e: f64) -> Scene {
    let edges = Edge::polygon(points, rho)
        .into_iter()
        .map(|edge| edge.with_emission(e))
        .collect();
    Scene::new(edges).expect("valid room")
}

/// An L-shaped (non-convex) closed room: walls occlude each other around the reflex corner.
pub fn l_room(rho: f64) -> Scene {
    let p = |x: f64, y: f64| DVec2::new(x, y);
    let pts = [
        p(0.0, 0.0),
        p(3.0, 0.0),
        p(3.0, 1.0),
        p(1.0, 1.0),
        p(1.0, 3.0),
        p(0.0, 3.0),
    ];
    let mut edges: Vec<Edge> = (0..pts.len())
        .map(|i| Edge::surface(pts[i], pts[(i + 1) % pts.len()], rho))
        .collect();
    // The light at the far end of the short leg, out of sight of most of the long one.
    edges[1].emission = 1.0;
    Scene::new(edges).expect("valid L room")
}

/// A generated floor plan of about `edges` edges (seed 1).
pub fn floor_plan(edges: usize) -> Scene {
    flatland_geom::generate::floor_plan(edges, 1).expect("a generated floor plan")
}

/// A generated hall of about `edges` edges (seed 1).
pub fn hall(edges: usize) -> Scene {
    flatland_geom::generate::hall(edges, 1).expect("a generated hall")
}

/// A floor plan of `cols × rows` rooms (3–5 units a side, from `seed`) whose interior walls
/// are thin: each a pair of one-sided faces back to back (the same end points, swapped), with
/// a door 0.9 wide in every wall between two rooms, and oblique stretches where a door is cut
/// (so wall points round off their lines). Lamps are small emitting boxes in two rooms. Closed
/// and without blockers: every direction from every point ends on a surface facing it.
pub fn thin_wall_plan(cols: usize, rows: usize, seed: u64) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut cuts = |n: usize| {
        let mut at = vec![0.0];
        for _ in 0..n {
            let next = at.last().copied().unwrap_or(0.0) + rng.random_range(3.0..5.0);
            at.push(next);
        }
        at
    };
    let (xs, ys) = (cuts(cols), cuts(rows));
    let (w, h) = (xs[cols], ys[rows]);
    let p = DVec2::new;
    let mut edges = Edge::polygon(&[p(0.0, 0.0), p(w, 0.0), p(w, h), p(0.0, h)], 0.6);
    // Each wall between two rooms: from `from` to `to`, a door somewhere in its middle; the
    // two stretches beside it tilt a little towards the door, so the walls are not all
    // axis-aligned.
    let mut wall = |from: DVec2, to: DVec2, rng: &mut ChaCha8Rng| {
        let len = from.distance(to);
        let d = rng.random_range(0.3..0.7) * len;
        let (u0, u1) = ((d - 0.45) / len, (d + 0.45) / len);
        let side = (to - from).perp().normalize() * rng.random_range(-0.2..0.2);
        let stretches = [
            (from, from + (to - from) * u0 + side),
            (from + (to - from) * u1 + side, to),
        ];
        for (a, b) in stretches {
            let rho = rng.random_range(0.3..0.8);
            edges.push(Edge::surface(a, b, rho));
            edges.push(Edge::surface(b, a, rho));
        }
    };
    for &x in &xs[1..cols] {
        for y in ys[..=rows].windows(2) {
            wall(p(x, y[0]), p(x, y[1]), &mut rng);
        }
    }
    for &y in &ys[1..rows] {
        for x in xs[..=cols].windows(2) {
            wall(p(x[0], y), p(x[1], y), &mut rng);
        }
    }
    for lamp in 0..2 {
        let (c, r) = if lamp == 0 {
            (0, 0)
        } else {
            (cols - 1, rows - 1)
        };
        let centre = p(
            0.5 * (xs[c] + xs[c + 1]) + 0.3,
            0.5 * (ys[r] + ys[r + 1]) - 0.2,
        );
        let q = [p(-0.1, -0.1), p(-0.1, 0.1), p(0.1, 0.1), p(0.1, -0.1)].map(|o| centre + o);
        // Clockwise: the box's faces point out.
        edges.extend(
            Edge::polygon(&q, 0.3)
                .into_iter()
                .map(|e| e.with_emission(5.0)),
        );
    }
    Scene::new(edges).expect("a valid thin-wall plan")
}

/// A closed 4 × 3 room holding about `inside` random segments from `seed`: surfaces, thin walls
/// (two surfaces back to back) and blockers, crossing and touching each other and the walls at random; some
/// end exactly on a wall or on another segment's end (T-junctions and shared corners).
pub fn random_room(inside: usize, seed: u64) -> Scene {
    let mut rng = flatland_testkit::rng(seed);
    let corners = [
        DVec2::new(0.0, 0.0),
        DVec2::new(4.0, 0.0),
        DVec2::new(4.0, 3.0),
        DVec2::new(0.0, 3.0),
    ];
    let mut edges = Edge::polygon(&corners, 0.6);
    edges[2].emission = 1.0;
    let mut ends: Vec<DVec2> = corners.to_vec();
    while edges.len() < 4 + inside {
        let a = match rng.random_range(0..4) {
            // On the floor, or at the end of an earlier segment.
            0 => DVec2::new(rng.random_range(0.2..3.8), 0.0),
            1 => ends[rng.random_range(0..ends.len())],
            _ => DVec2::new(rng.random_range(0.1..3.9), rng.random_range(0.1..2.9)),
        };
        let b = DVec2::new(rng.random_range(0.1..3.9), rng.random_range(0.1..2.9));
        if a.distance(b) < 0.05 {
            continue;
        }
        match rng.random_range(0..3) {
            0 => edges.push(Edge::blocker(a, b)),
            // A thin wall: two one-sided faces back to back.
            1 => edges.extend([Edge::surface(a, b, 0.5), Edge::surface(b, a, 0.5)]),
            _ => edges.push(Edge::surface(a, b, 0.7).with_emission(rng.random_range(0.0..1.0))),
        }
        ends.push(b);
    }
    Scene::new(edges).expect("a valid random room")
}

/// Emitted and absorbed power of the solve with `op` on `mesh`: `∫ E dl + Σ Φ` and
/// `∫ (1 − ρ) H dl`, with H the irradiance `H̄_i + (K B)_i / ρ_i`, the point lights' direct
/// light and what the surfaces send (equal in a closed scene without blockers).
pub fn power_balance(op: &dyn TransferOperator, mesh: &Mesh) -> (f64, f64) {
    let solution = solve_operator(op, mesh, &SolveParams::default(), &never).unwrap();
    let mut gathered = vec![0.0; mesh.len()];
    op.apply(&solution.radiosity, &mut gathered);
    let mut emitted: f64 = mesh.lights().iter().map(|l| l.power).sum();
    let mut absorbed = 0.0;
    let direct = mesh.direct_irradiance();
    for (i, el) in mesh.elements().iter().enumerate() {
        let edge = mesh.edge_of(i);
        let h = direct.get(i).copied().unwrap_or(0.0) + gathered[i] / edge.reflectance;
        emitted += edge.emission * el.length;
        absorbed += (1.0 - edge.reflectance) * h * el.length;
    }
    (emitted, absorbed)
}
