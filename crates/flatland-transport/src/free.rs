//! Points of the free space, found from the surfaces alone: a point on the open segment between
//! a surface element's midpoint and the first edge a ray from it into its front meets is in
//! the space that element faces — never inside a wall, a piece of furniture or behind the
//! outer wall. The transport's own validation lights (and the probes' test points) are drawn
//! this way, so the set-up needs no list of rooms.

use flatland_geom::{DVec2, Kernel};
use flatland_solve::Mesh;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// Rays a point's clearance is tested with.
const CLEARANCE_RAYS: usize = 16;

/// Tries before giving up on a scene (as a multiple of the points asked for).
const TRIES_PER_POINT: usize = 50;

/// The distance from `p` to the nearest edge any of [`CLEARANCE_RAYS`] rays meets (infinite
/// when they all leave the scene).
#[must_use]
pub(crate) fn clearance(kernel: &Kernel, p: DVec2) -> f64 {
    (0..CLEARANCE_RAYS)
        .map(|k| {
            let angle = std::f64::consts::TAU * (k as f64 + 0.5) / CLEARANCE_RAYS as f64;
            let direction = DVec2::new(angle.cos(), angle.sin());
            kernel
                .first_hit(p, direction, None)
                .map_or(f64::INFINITY, |hit| hit.distance)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Up to `count` points of the free space, drawn with `rng`: an element by length, a direction
/// within 80° of its normal, a point 15–85 % of the way to the first edge met, kept if no edge
/// is nearer than `margin` times that way (nor than `margin` absolute). Fewer when the scene
/// has no such space (every ray from the surfaces leaves the scene, or every room is thinner).
pub(crate) fn free_points(
    kernel: &Kernel,
    mesh: &Mesh,
    count: usize,
    margin: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<DVec2> {
    let total: f64 = mesh.total_length();
    let mut cumulative = Vec::with_capacity(mesh.len());
    let mut sum = 0.0;
    for e in mesh.elements() {
        sum += e.length;
        cumulative.push(sum);
    }
    let mut points = Vec::with_capacity(count);
    for _ in 0..count * TRIES_PER_POINT {
        if points.len() == count {
            break;
        }
        let pick = rng.random_range(0.0..total.max(f64::MIN_POSITIVE));
        let i = cumulative
            .partition_point(|&c| c < pick)
            .min(mesh.len() - 1);
        let element = mesh.elements()[i];
        let normal = mesh.edge_of(i).normal;
        let turn = rng.random_range(-1.4..1.4_f64);
        let (s, c) = turn.sin_cos();
        let direction = DVec2::new(c * normal.x - s * normal.y, s * normal.x + c * normal.y);
        let Some(hit) = kernel.first_hit(element.midpoint, direction, Some(element.edge)) else {
            continue;
        };
        let point = element.midpoint + direction * hit.distance * rng.random_range(0.15..0.85);
        if clearance(kernel, point) >= margin * hit.distance.max(1.0) {
            points.push(point);
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::rng;

    #[test]
    fn free_points_are_clear_of_every_edge_and_inside_the_plan() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(300, 5).unwrap());
        let mesh = Mesh::new(&kernel, 800).unwrap();
        let points = free_points(&kernel, &mesh, 40, 0.05, &mut rng(1));
        assert_eq!(points.len(), 40);
        for p in &points {
            assert!(clearance(&kernel, *p) >= 0.05, "{p}");
            // Inside the closed outer wall: every ray meets a surface's front.
            for k in 0..8 {
                let angle = 0.7 + k as f64;
                let d = DVec2::new(angle.cos(), angle.sin());
                let hit = kernel.first_hit(*p, d, None).expect("a closed plan");
                let normal = kernel.scene().edge(hit.edge).normal();
                assert!(
                    d.dot(normal) < 0.0,
                    "{p} sees the back of edge {}",
                    hit.edge
                );
            }
        }
        assert_eq!(points, free_points(&kernel, &mesh, 40, 0.05, &mut rng(1)));
    }
}
