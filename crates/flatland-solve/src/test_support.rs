//! Helpers shared by the solver's tests: bundled scenes and small rooms built in code.

use flatland_geom::{DVec2, Edge, Scene};

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
