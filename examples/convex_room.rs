//! A convex room of many independent edges: the scene of issue 20's "fits in ≤ 5 s" case.
//!
//! `cargo run --release --example convex_room -- [EDGES] [OUT.json]` (defaults: 4096,
//! `convex.json`): a regular polygon of `EDGES` one-sided surfaces facing inwards (radius 10,
//! reflectance 0.5), one of them emitting, and a small blocker box (a square of side 1) off the
//! centre. No two surfaces are collinear, so none shares a parent: every pair is its own pair.

use std::error::Error;
use std::f64::consts::TAU;

use flatland_geom::{DVec2, Edge, Scene};

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let edges: usize = args.next().map_or(Ok(4096), |n| n.parse())?;
    let out = args.next().unwrap_or_else(|| "convex.json".into());
    let scene = convex_room(edges)?;
    scene.save(std::path::Path::new(&out))?;
    println!("wrote {out}: {} edges", scene.edges().len());
    Ok(())
}

/// The room: `n` ≥ 3 inward-facing surfaces, the first emitting, and a 4-edge blocker box.
fn convex_room(n: usize) -> Result<Scene, Box<dyn Error>> {
    if n < 3 {
        return Err(format!("EDGES must be at least 3, got {n}").into());
    }
    // Counter-clockwise, so the fronts (left of a → b) face the centre.
    let points: Vec<DVec2> = (0..n)
        .map(|i| 10.0 * DVec2::from_angle(TAU * i as f64 / n as f64))
        .collect();
    let mut edges = Edge::polygon(&points, 0.5);
    edges[0] = edges[0].with_emission(1.0);
    let c = DVec2::new(2.0, 1.0);
    let corner =
        [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, y)| c + DVec2::new(x, y));
    edges.extend((0..4).map(|i| Edge::blocker(corner[i], corner[(i + 1) % 4])));
    Ok(Scene::new(edges)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_room_has_its_edges_and_refuses_too_few() {
        let scene = convex_room(16).unwrap();
        assert_eq!(scene.edges().len(), 20);
        assert_eq!(scene.edges().iter().filter(|e| e.emission > 0.0).count(), 1);
        assert!(convex_room(2).is_err());
    }
}
