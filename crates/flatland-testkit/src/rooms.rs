//! Small rooms the tests share, as corners: a closed room is its corners counter-clockwise (each
//! wall facing in), which `flatland_geom::Edge::polygon(&corners, ρ)` turns into walls, the
//! wall from corner `i` to corner `i + 1` first.

use glam::DVec2;

/// The closed unit square: floor `(0, 0) → (1, 0)` (wall 0), right wall, ceiling, left wall.
#[must_use]
pub fn unit_square() -> [DVec2; 4] {
    rectangle(1.0, 1.0)
}

/// The closed `width × height` box from the origin, walls in the order of [`unit_square`].
#[must_use]
pub fn rectangle(width: f64, height: f64) -> [DVec2; 4] {
    [
        DVec2::new(0.0, 0.0),
        DVec2::new(width, 0.0),
        DVec2::new(width, height),
        DVec2::new(0.0, height),
    ]
}

/// The blocker of the box with a blocker: a segment floating in the unit square, tilted so that
/// it shades part of every wall from every other (like the paper's Fig. 3); two-sided.
#[must_use]
pub fn box_blocker() -> [DVec2; 2] {
    [DVec2::new(0.3, 0.45), DVec2::new(0.65, 0.55)]
}

/// The convex room of many walls (issue 20's huge geometry): a regular polygon of `n` corners on
/// the circle of `radius` about the origin, the first at `(radius, 0)`.
#[must_use]
pub fn regular_polygon(n: usize, radius: f64) -> Vec<DVec2> {
    (0..n)
        .map(|i| radius * DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64))
        .collect()
}

/// The box that stands in issue 20's convex room: the square of side 1 about `(2, 1)`, its
/// corners counter-clockwise (make its sides blockers, or a clockwise box of surfaces).
#[must_use]
pub fn off_centre_box() -> [DVec2; 4] {
    rectangle(1.0, 1.0).map(|c| c + DVec2::new(1.5, 0.5))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twice the signed area of a closed polygon: positive when counter-clockwise.
    fn twice_area(p: &[DVec2]) -> f64 {
        (0..p.len())
            .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
            .sum()
    }

    #[test]
    fn rooms_are_counter_clockwise_and_the_blocker_floats_inside() {
        crate::assert_close!(twice_area(&unit_square()), 2.0, 0.0);
        crate::assert_close!(twice_area(&rectangle(3.0, 2.0)), 12.0, 0.0);
        // A polygon of many sides has about the circle's area.
        // A polygon of many sides has about the circle's area, and holds the box.
        let pi = std::f64::consts::PI;
        crate::assert_close!(
            twice_area(&regular_polygon(4096, 10.0)),
            200.0 * pi,
            rel = 1e-6
        );
        crate::assert_close!(twice_area(&off_centre_box()), 2.0, 0.0);
        assert!(
            off_centre_box()
                .iter()
                .all(|c| c.length() < 10.0 * (pi / 16.0).cos())
        );
        for p in box_blocker() {
            assert!(
                p.cmpgt(DVec2::ZERO).all() && p.cmplt(DVec2::ONE).all(),
                "{p}"
            );
        }
    }
}
