//! The radiosity kernel `k(s, t)` and the learning target `ζ(s, t)` (docs/ALGORITHM.md §2).

mod batch;
mod cache;
mod eval;
mod free;
mod lamps;
mod pairs;
mod params;
mod rays;
mod values;
mod varying;
mod visible;

use std::sync::OnceLock;

use glam::DVec2;

use crate::scene::{Role, Scene};
use crate::visibility::{Bvh, Segment};
use crate::{EdgeId, GeomError, SurfaceRank};
use cache::PairCache;
#[cfg(test)]
pub(crate) use free::point_segment_distance;

pub use pairs::PairEventsRef;
pub use params::KernelParams;
pub use values::{Hit, KernelSample, PairClass, Unoccluded};
pub use varying::VaryingPairs;

/// What the hot loop needs of one parent edge, packed together.
#[derive(Clone, Copy, Debug)]
struct Parent {
    a: DVec2,
    d: DVec2,
    normal: DVec2,
    reflectance: f64,
    weight: f64,
    /// Rank among surface parents, `None` for a blocker.
    rank: Option<SurfaceRank>,
}

/// The exact kernel of one scene, with its acceleration structures. `Send + Sync`: share it
/// between threads by reference.
///
/// # Conventions
/// `s` is the sender parameter, `t` the receiver's; `x = point(s)` on `e_x`, `y = point(t)` on
/// `e_y`, `d = y − x`, `r = |d|`:
/// `k(s, t) = ρ(e_y) · cos_x · cos_y / (2 r) · V(x, y)`, with `cos_x = max(0, n_x·d/r)`,
/// `cos_y = max(0, −n_y·d/r)` (surfaces are one-sided), and `k = 0` when `e_x` and `e_y`
/// are the same edge or pieces of the same parent edge, or when `x = y`. `k` grows like `1/r`
/// near a shared vertex; it is always finite and ≥ 0.
///
/// # Work skipped
/// No ray for back-facing pairs (`G = 0`). Per pair of parent surface edges a shaft
/// classification decides "clear", "blocked by one occluder" or "test these candidates"; rays
/// that still need testing go through a BVH over the parent edges. All of it works on parent
/// edges, so `scene.subdivide(1000)` costs about what the original scene does.
///
/// Pairs are classified lazily, only those asked about, each in about `log n` BVH steps
/// plus the occluders near its shaft, and kept in bounded memory: a cell per pair up to 512
/// surface parents, a sharded cache of at most 64 MB above (see `kernel/cache.rs`). Nothing
/// is built over all pairs, so building a kernel costs `O(n log n)`.
pub struct Kernel {
    scene: Scene,
    params: KernelParams,
    parents: Vec<Parent>,
    segments: Vec<Segment>,
    bvh: Bvh,
    /// Surface parent index by rank.
    surface_parents: Vec<usize>,
    /// The shafts of the pairs asked about, by ranks.
    shafts: PairCache,
    /// The pairs whose visibility varies, once listed ([`Kernel::varying_pairs`]).
    varying: OnceLock<VaryingPairs>,
}

impl std::fmt::Debug for Kernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Kernel")
            .field("scene", &self.scene)
            .field("params", &self.params)
            .finish()
    }
}

impl Kernel {
    /// The kernel of `scene` with default [`KernelParams`].
    #[must_use]
    pub fn new(scene: Scene) -> Kernel {
        Kernel::build(scene, KernelParams::default())
    }

    /// The kernel of `scene` with `params` (validated).
    pub fn with_params(scene: Scene, params: KernelParams) -> Result<Kernel, GeomError> {
        params.validate()?;
        Ok(Kernel::build(scene, params))
    }

    fn build(scene: Scene, params: KernelParams) -> Kernel {
        let parents: Vec<Parent> = scene
            .groups()
            .iter()
            .map(|g| Parent {
                a: g.a,
                d: g.b - g.a,
                normal: g.normal,
                reflectance: g.edge.reflectance,
                // Set below, once the kernel can cast the lamps' rays.
                weight: g.edge.emission,
                rank: g.rank,
            })
            .collect();
        let segments: Vec<Segment> = scene
            .groups()
            .iter()
            .map(|g| Segment { a: g.a, b: g.b })
            .collect();
        let bvh = Bvh::new(&segments);
        let surface_parents: Vec<usize> = scene
            .groups()
            .iter()
            .enumerate()
            .filter(|(_, g)| g.edge.role == Role::Surface)
            .map(|(i, _)| i)
            .collect();
        let shafts = PairCache::new(surface_parents.len());
        let mut kernel = Kernel {
            scene,
            params,
            parents,
            segments,
            bvh,
            surface_parents,
            shafts,
            varying: OnceLock::new(),
        };
        kernel.weigh_senders();
        kernel
    }

    /// `E'` of every parent (docs/ALGORITHM.md §2): what it sends of the first light, its
    /// emission plus what it reflects of the lamps' direct light, and for an edge that emits
    /// nothing at least the floor, `emission_floor` times the largest of them. Without lamps
    /// this is the emission of an emitter and the floor elsewhere.
    fn weigh_senders(&mut self) {
        let lit = self.lamp_light();
        let first: Vec<f64> = self
            .parents
            .iter()
            .zip(&lit)
            .map(|(p, l)| p.weight + l)
            .collect();
        let floor = self.params.emission_floor * first.iter().copied().fold(0.0, f64::max);
        for (p, light) in self.parents.iter_mut().zip(first) {
            p.weight = if p.weight > 0.0 {
                light
            } else {
                light.max(floor)
            };
        }
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> KernelParams {
        self.params
    }

    /// `E'` of docs/ALGORITHM.md §2, the light an edge sends first: its emission plus what it
    /// reflects of the scene's lamps' direct light (measured by rays, `kernel/lamps.rs`), and
    /// for an edge that emits nothing at least `emission_floor` times the largest `E'` (so 0
    /// everywhere only if nothing emits and no lamp shines). 0 for an edge not in the scene.
    #[must_use]
    pub fn source_weight(&self, edge: EdgeId) -> f64 {
        self.group(edge).map_or(0.0, |g| self.parents[g].weight)
    }

    /// Number of parent surface edges (the ranks of [`Unoccluded`] run over `0..this`).
    #[must_use]
    pub fn surface_parents(&self) -> usize {
        self.surface_parents.len()
    }

    /// Every parent surface edge's rank, in order: `0..surface_parents()`.
    pub fn surface_ranks(&self) -> impl ExactSizeIterator<Item = SurfaceRank> + use<> {
        (0..self.surface_parents.len()).map(SurfaceRank::new)
    }

    /// The end points `(a, b)` of the parent surface edge of rank `rank`.
    ///
    /// # Panics
    /// If `rank >= surface_parents()`.
    #[must_use]
    pub fn surface_parent(&self, rank: SurfaceRank) -> (DVec2, DVec2) {
        let s = self.segments[self.surface_parents[rank.index()]];
        (s.a, s.b)
    }

    /// The parent (group) of `edge`, `None` for an edge not in the scene.
    fn group(&self, edge: EdgeId) -> Option<usize> {
        (edge.index() < self.scene.edges().len()).then(|| self.scene.group_of(edge.index()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const _: () = {
        const fn send_sync<T: Send + Sync>() {}
        send_sync::<Kernel>();
    };
}
