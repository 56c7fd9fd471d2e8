//! A scene's scale-free unit frame: the mesh computes its geometry in it, and the learner's
//! network inputs `γ(s, t) = (x₁, y₁, x₂, y₂)` are points of it.

use flatland_geom::{DVec2, Scene};
use serde::{Deserialize, Serialize};

/// Maps scene coordinates into the unit box the network learns in.
///
/// The network's step sizes and widths are absolute, so feeding raw coordinates would make the
/// learning depend on the scene's units and origin. One uniform scale (the larger side of the
/// bounding box) keeps distances isotropic: the 4-D distance between two ray inputs stays a
/// scaled Euclidean distance between their end points.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputFrame {
    /// The scene's lower-left bounding-box corner.
    pub origin: [f64; 2],
    /// 1 / (larger side of the bounding box).
    pub inv_scale: f64,
}

impl InputFrame {
    /// The frame of a scene's bounding box.
    pub fn of(scene: &Scene) -> InputFrame {
        let (lo, hi) = scene.bounds();
        let side = (hi - lo).max_element();
        // A valid scene has a non-zero edge, so side > 0; guard anyway so no NaN can start here.
        let inv_scale = if side > 0.0 && side.is_finite() {
            1.0 / side
        } else {
            1.0
        };
        InputFrame {
            origin: [lo.x, lo.y],
            inv_scale,
        }
    }

    /// A scene point in frame coordinates (each in [0, 1] for points of the scene).
    #[inline]
    pub fn map(&self, p: DVec2) -> [f64; 2] {
        [
            (p.x - self.origin[0]) * self.inv_scale,
            (p.y - self.origin[1]) * self.inv_scale,
        ]
    }

    /// The scene point of frame coordinates `w` (the inverse of [`InputFrame::map`]).
    #[inline]
    pub fn unmap(&self, w: [f64; 2]) -> DVec2 {
        DVec2::new(
            w[0] / self.inv_scale + self.origin[0],
            w[1] / self.inv_scale + self.origin[1],
        )
    }

    /// `γ(s, t)`: sender point then receiver point, in frame coordinates.
    #[inline]
    pub fn gamma(&self, scene: &Scene, s: f64, t: f64) -> [f64; 4] {
        let [x1, y1] = self.map(scene.point(s).position);
        let [x2, y2] = self.map(scene.point(t).position);
        [x1, y1, x2, y2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::{Edge, Role};

    fn segment_scene(scale: f64, shift: f64) -> Scene {
        let e = |a: [f64; 2], b: [f64; 2]| Edge {
            a: DVec2::new(a[0] * scale + shift, a[1] * scale + shift),
            b: DVec2::new(b[0] * scale + shift, b[1] * scale + shift),
            reflectance: 0.5,
            emission: 1.0,
            role: Role::Surface,
            two_sided: false,
        };
        Scene::new(vec![e([0.0, 0.0], [2.0, 0.0]), e([2.0, 1.0], [0.0, 1.0])]).unwrap()
    }

    #[test]
    fn gamma_is_independent_of_units_and_origin() {
        let base = segment_scene(1.0, 0.0);
        let g0 = InputFrame::of(&base).gamma(&base, 0.3, 0.8);
        for (scale, shift) in [(1e-6, 0.0), (1e6, 0.0), (1.0, 1e6), (3.0, -7.0)] {
            let scene = segment_scene(scale, shift);
            let g = InputFrame::of(&scene).gamma(&scene, 0.3, 0.8);
            for (a, b) in g0.iter().zip(g) {
                assert!(
                    (a - b).abs() < 1e-9,
                    "scale {scale} shift {shift}: {g0:?} vs {g:?}"
                );
            }
        }
    }

    #[test]
    fn scene_points_land_in_the_unit_box() {
        let scene = segment_scene(5.0, -3.0);
        let frame = InputFrame::of(&scene);
        for i in 0..100 {
            let s = i as f64 / 100.0;
            for v in frame.gamma(&scene, s, 1.0 - s - 1e-9) {
                assert!((-1e-12..=1.0 + 1e-12).contains(&v), "{v}");
            }
        }
    }
}
