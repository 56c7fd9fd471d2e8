//! Random rooms: validation scenes the learners are never tuned on.
//!
//! A room is a rectangle, a rectangle with a notch hanging from its ceiling, or a convex polygon
//! of 5–8 corners, 2–8 units wide and 2–5 high, listed counter-clockwise (facing in), each wall
//! with its own reflectance in `[0.2, 0.9]`. One or two walls carry a light (a middle piece of
//! the wall, emission in `[0.5, 2]`). Up to 12 short segments float inside (three in four are
//! blockers, one in four a thin shelf: two surfaces back to back), and half the rectangles get
//! a thin partition standing on the floor (two surfaces back to back). The same seed gives the
//! same room.

use flatland_geom::{DVec2, Edge, GeomError, Scene};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// The seed stream of the rooms (`flatland_solve::seeds::stream`): no other draw of a seed
/// shares it.
const ROOMS_STREAM: u64 = 0x5ce7e;

/// The random room of `seed` (see the module docs).
pub fn random_room(seed: u64) -> Result<Scene, GeomError> {
    let mut r = flatland_solve::seeds::stream(seed, ROOMS_STREAM);
    let (w, h) = (r.random_range(2.0..8.0), r.random_range(2.0..5.0));
    let kind = r.random_range(0..3);
    let corners = room_corners(&mut r, kind, w, h);
    let mut edges = walls(&mut r, &corners);
    floating(&mut r, &corners, w, h, &mut edges);
    if kind == 0 && r.random_bool(0.5) {
        let x = r.random_range(0.2..0.8) * w;
        let top = r.random_range(0.3..0.7) * h;
        let (p, q) = (DVec2::new(x, 0.0), DVec2::new(x, top));
        edges.extend([Edge::surface(p, q, 0.5), Edge::surface(q, p, 0.5)]);
    }
    Scene::new(edges)
}

/// The corners of a room of `kind` (a rectangle, a notched rectangle, a convex polygon) `w`
/// wide and `h` high, counter-clockwise.
fn room_corners(r: &mut ChaCha8Rng, kind: i32, w: f64, h: f64) -> Vec<DVec2> {
    let v = DVec2::new;
    match kind {
        0 => vec![v(0.0, 0.0), v(w, 0.0), v(w, h), v(0.0, h)],
        1 => {
            let (a, b) = (r.random_range(0.2..0.5) * w, r.random_range(0.55..0.85) * w);
            let d = r.random_range(0.3..0.6) * h;
            vec![
                v(0.0, 0.0),
                v(w, 0.0),
                v(w, h),
                v(b, h),
                v(b, h - d),
                v(a, h - d),
                v(a, h),
                v(0.0, h),
            ]
        }
        _ => {
            let n = r.random_range(5..9);
            (0..n)
                .map(|i| {
                    let a =
                        std::f64::consts::TAU * (i as f64 + r.random_range(-0.3..0.3)) / n as f64;
                    v(w / 2.0 * (1.0 + a.cos()), h / 2.0 * (1.0 + a.sin()))
                })
                .collect()
        }
    }
}

/// The walls between `corners`, one or two of them carrying a light in their middle.
fn walls(r: &mut ChaCha8Rng, corners: &[DVec2]) -> Vec<Edge> {
    let n = corners.len();
    let lights = r.random_range(1..=2);
    let light_walls: Vec<usize> = (0..lights).map(|_| r.random_range(0..n)).collect();
    let mut edges = Vec::new();
    for i in 0..n {
        let (a, b) = (corners[i], corners[(i + 1) % n]);
        let rho = r.random_range(0.2..0.9);
        if light_walls.contains(&i) {
            let (u0, u1) = (r.random_range(0.1..0.45), r.random_range(0.55..0.9));
            let (p0, p1) = (a + (b - a) * u0, a + (b - a) * u1);
            edges.push(Edge::surface(a, p0, rho));
            edges.push(Edge::surface(p0, p1, rho).with_emission(r.random_range(0.5..2.0)));
            edges.push(Edge::surface(p1, b, rho));
        } else {
            edges.push(Edge::surface(a, b, rho));
        }
    }
    edges
}

/// Up to 12 short segments floating inside the room of `corners` (`w` × `h`), clear of its
/// walls: blockers, or one in four a thin shelf.
fn floating(r: &mut ChaCha8Rng, corners: &[DVec2], w: f64, h: f64, edges: &mut Vec<Edge>) {
    let v = DVec2::new;
    let n = corners.len();
    // Strictly inside every wall's half-plane, clear of the walls.
    let inside = |p: DVec2| {
        (0..n).all(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            (b - a).perp_dot(p - a) > 0.05 * w.min(h) * (b - a).length()
        })
    };
    let floating = r.random_range(0..=12);
    let (mut placed, mut tries) = (0, 0);
    while placed < floating && tries < 1000 {
        tries += 1;
        let c = v(r.random_range(0.0..w), r.random_range(0.0..h));
        let len = r.random_range(0.05..0.25) * w.min(h);
        let angle = r.random_range(0.0..std::f64::consts::PI);
        let d = v(angle.cos(), angle.sin()) * len / 2.0;
        let (p, q) = (c - d, c + d);
        if !(inside(p) && inside(q)) {
            continue;
        }
        if r.random_range(0..4) == 0 {
            let rho = r.random_range(0.2..0.9);
            edges.extend([Edge::surface(p, q, rho), Edge::surface(q, p, rho)]);
        } else {
            edges.push(Edge::blocker(p, q));
        }
        placed += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rooms_are_valid_closed_and_lit_and_the_seed_decides() {
        for seed in 0..40 {
            let room = random_room(seed).unwrap();
            assert!(room.max_emission() > 0.0, "seed {seed}: no light");
            assert_eq!(room.fingerprint(), random_room(seed).unwrap().fingerprint());
            assert_ne!(
                room.fingerprint(),
                random_room(seed + 1).unwrap().fingerprint()
            );
            // Closed: every wall's end point is shared with another wall (the floating shelves
            // and partitions, faces back to back, are not walls).
            let thin = |e: &Edge| room.edges().iter().any(|f| f.a == e.b && f.b == e.a);
            let surfaces: Vec<&Edge> = room
                .edges()
                .iter()
                .filter(|e| e.role == flatland_geom::Role::Surface && !thin(e))
                .collect();
            for e in &surfaces {
                assert!(
                    surfaces.iter().any(|f| f.a == e.b),
                    "seed {seed}: open at {:?}",
                    e.b
                );
            }
        }
    }
}
