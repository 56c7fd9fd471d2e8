//! Edges, validated scenes and the arc-length parameterization (docs/ALGORITHM.md §1).

mod build;
mod edge;
mod edit;
mod fingerprint;
mod light;
mod param;
mod raw;

use std::fmt;

use glam::DVec2;

use crate::{EdgeId, GeomError, SurfaceRank};
pub use edge::{Edge, Role};
pub use light::{LightCheck, PointLight};
pub use param::SurfacePoint;
pub(crate) use raw::RawScene;

/// A run of consecutive edges cut from one parent edge by [`Scene::subdivide`] (or a single
/// edge). All pieces share the parent's material; the parent's exact end points are kept so that
/// the parameterization, the normals and the occlusion tests of a subdivided scene are bit for
/// bit those of the original.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Group {
    /// Index of the first piece in `Scene::edges`.
    pub first: usize,
    /// Number of equal pieces.
    pub count: usize,
    /// Parent start point (= first piece's `a`).
    pub a: DVec2,
    /// Parent end point (= last piece's `b`).
    pub b: DVec2,
    /// Parent front normal.
    pub normal: DVec2,
    /// Parent length.
    pub length: f64,
    /// Parent material and role (shared by every piece).
    pub edge: Edge,
    /// Rank among the surface groups (parameter order), `None` for a blocker.
    pub rank: Option<SurfaceRank>,
}

/// A validated Flatland scene (docs/ALGORITHM.md §1): edges, its point lights, the arc-length
/// parameterization of its surface edges, and the parent structure left by [`Scene::subdivide`].
///
/// The only ways to get one are [`Scene::new`], loading/deserializing (which validate) and the
/// methods that derive a scene from another, so every `Scene` in memory is valid: finite
/// coordinates, positive lengths, ρ ∈ [0, 1], finite E ≥ 0, at least one surface edge; lights
/// at finite points off every edge, with finite power Φ ≥ 0.
///
/// Serialized form (`.ron` or `.json`): `{"edges": [{"a": [0, 0], "b": [1, 0], "reflectance":
/// 0.5, "emission": 0.0, "role": "surface", "two_sided": false}, ...], "lights": [{"at": [0.5,
/// 0.5], "power": 2.0}]}`; `emission`, `role`, `two_sided` and `lights` are optional (a scene
/// without lights is written without the key, so its file is what it was before lights
/// existed). The parent structure is not serialized: a saved subdivided scene loads as
/// independent edges (same kernel up to rounding, but culling no longer merges pieces).
///
/// Lights are not part of the kernel `k(s, t)` (nor of [`Scene::fingerprint`]): they light the
/// scene, they do not change how its surfaces exchange light.
#[derive(Clone, PartialEq)]
pub struct Scene {
    edges: Vec<Edge>,
    lights: Vec<PointLight>,
    group_of: Vec<usize>,
    groups: Vec<Group>,
    surface_edges: Vec<EdgeId>,
    /// Surface group indices in parameter order.
    surface_groups: Vec<usize>,
    /// `cum[r]` = arc length before surface group of rank `r`; `cum[n] = L`.
    cum: Vec<f64>,
    /// `1 / length` of the surface group of rank `r`.
    inv_length: Vec<f64>,
    /// `buckets[b]`: a rank near the one containing `s = b / buckets.len()`, where
    /// [`Scene::locate`] starts its (usually zero-step) scan instead of a binary search.
    buckets: Vec<u32>,
    total_length: f64,
}

impl fmt::Debug for Scene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Scene")
            .field("edges", &self.edges)
            .field("lights", &self.lights)
            .field("parent_groups", &self.groups.len())
            .field("total_length", &self.total_length)
            .finish()
    }
}

impl Scene {
    /// All edges, surfaces and blockers, in file order.
    #[must_use]
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The point lights, in file order (empty for a scene lit by its edges only).
    #[must_use]
    pub fn lights(&self) -> &[PointLight] {
        &self.lights
    }

    /// The same scene lit by `lights` instead of its own (validated: finite, power ≥ 0, off
    /// every edge; errors name the light by its index and the edge it lies on). Nothing that
    /// depends on the edges is rebuilt, so moving a light costs a look-up per light in a grid
    /// of the edges.
    pub fn with_lights(mut self, lights: Vec<PointLight>) -> Result<Scene, GeomError> {
        light::check_lights(&self.edges, &lights)?;
        self.lights = lights;
        Ok(self)
    }

    /// Whether anything lights the scene: an emitting edge or a light of positive power.
    #[must_use]
    pub fn is_lit(&self) -> bool {
        self.max_emission() > 0.0 || self.lights.iter().any(|l| l.power > 0.0)
    }

    /// Edge `id`.
    ///
    /// # Panics
    /// If `id` is not an edge of this scene.
    #[must_use]
    pub fn edge(&self, id: EdgeId) -> &Edge {
        &self.edges[id.index()]
    }

    /// The surface edges, in parameter (file) order.
    #[must_use]
    pub fn surface_edges(&self) -> &[EdgeId] {
        &self.surface_edges
    }

    /// Total length `L` of the surface edges.
    #[must_use]
    pub fn total_length(&self) -> f64 {
        self.total_length
    }

    /// The largest emission of any edge (0 if nothing emits).
    #[must_use]
    pub fn max_emission(&self) -> f64 {
        self.edges.iter().map(|e| e.emission).fold(0.0, f64::max)
    }

    /// Minimum and maximum corner of the bounding box of all edges (blockers included).
    #[must_use]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        self.edges
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), e| {
                (lo.min(e.a).min(e.b), hi.max(e.a).max(e.b))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::bundled;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn bounds_and_max_emission() {
        let scene = bundled("fig3");
        assert_eq!(scene.bounds(), (v(0.0, 0.0), v(4.0, 3.0)));
        assert_eq!(scene.max_emission(), 1.0);
    }
}
