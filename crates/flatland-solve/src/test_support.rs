//! Helpers shared by the solver's tests: bundled scenes, small rooms built in code, generated
//! scenes and random ones.

use flatland_geom::{DVec2, Edge, Scene};

use crate::{Mesh, SolveParams, TransferOperator, never, solve_operator};
use rand::RngExt;

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

/// A closed 4 × 3 room holding `inside` random segments from `seed`: surfaces one- and
/// two-sided, and blockers, crossing and touching each other and the walls at random; some
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
        let edge = match rng.random_range(0..3) {
            0 => Edge::blocker(a, b),
            1 => Edge::surface(a, b, 0.5).with_two_sided(true),
            _ => Edge::surface(a, b, 0.7).with_emission(rng.random_range(0.0..1.0)),
        };
        edges.push(edge);
        ends.push(b);
    }
    Scene::new(edges).expect("a valid random room")
}

/// Emitted and absorbed power of the solve with `op` on `mesh`: `∫ E dl` and `∫ (1 − ρ) H dl`,
/// with H the irradiance `(K B)_i / ρ_i` (equal in a closed scene without blockers).
pub fn power_balance(op: &dyn TransferOperator, mesh: &Mesh) -> (f64, f64) {
    let solution = solve_operator(op, mesh, &SolveParams::default(), &never).unwrap();
    let mut gathered = vec![0.0; mesh.len()];
    op.apply(&solution.radiosity, &mut gathered);
    let (mut emitted, mut absorbed) = (0.0, 0.0);
    for (i, el) in mesh.elements().iter().enumerate() {
        let edge = mesh.edge_of(i);
        emitted += edge.emission * el.length;
        absorbed += (1.0 - edge.reflectance) * gathered[i] / edge.reflectance * el.length;
    }
    (emitted, absorbed)
}
