//! Edges, validated scenes and the arc-length parameterization (docs/ALGORITHM.md §1).

use std::fmt;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::GeomError;

/// What an edge does: a `Surface` is parameterized, reflects, emits and occludes; a `Blocker`
/// only occludes (the paper's Fig. 3 blocker is "not included into the parametrization").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// Part of the parameterization; reflects, emits and occludes.
    #[default]
    Surface,
    /// Occludes only.
    Blocker,
}

/// A line segment from `a` to `b` with its material. A plain value: build scenes from it with
/// [`Scene::new`], which validates every field.
///
/// The front side is the left of `a → b`; see [`Edge::normal`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Diffuse reflectance ρ in `[0, 1]`.
    pub reflectance: f64,
    /// Emitted radiosity E ≥ 0.
    pub emission: f64,
    /// Surface (parameterized) or blocker (occludes only).
    pub role: Role,
    /// Whether both sides face the scene (`|cos|` instead of `max(0, cos)`).
    pub two_sided: bool,
}

impl Edge {
    /// A one-sided, non-emitting surface edge.
    #[must_use]
    pub const fn surface(a: DVec2, b: DVec2, reflectance: f64) -> Edge {
        Edge {
            a,
            b,
            reflectance,
            emission: 0.0,
            role: Role::Surface,
            two_sided: false,
        }
    }

    /// The walls of a closed polygon room through `points`, each with `reflectance`: listed
    /// counter-clockwise, they face inwards.
    #[must_use]
    pub fn polygon(points: &[DVec2], reflectance: f64) -> Vec<Edge> {
        (0..points.len())
            .map(|i| Edge::surface(points[i], points[(i + 1) % points.len()], reflectance))
            .collect()
    }

    /// A blocker edge (occludes only; reflectance and emission are 0).
    #[must_use]
    pub const fn blocker(a: DVec2, b: DVec2) -> Edge {
        Edge {
            a,
            b,
            reflectance: 0.0,
            emission: 0.0,
            role: Role::Blocker,
            two_sided: false,
        }
    }

    /// The same edge with emission `emission`.
    #[must_use]
    pub const fn with_emission(self, emission: f64) -> Edge {
        Edge { emission, ..self }
    }

    /// The same edge, two-sided or not.
    #[must_use]
    pub const fn with_two_sided(self, two_sided: bool) -> Edge {
        Edge { two_sided, ..self }
    }

    /// Euclidean length `|b − a|`.
    #[must_use]
    pub fn length(&self) -> f64 {
        (self.b - self.a).length()
    }

    /// Front normal `perp(b − a) / |b − a|` with `perp(x, y) = (−y, x)`: the left of `a → b`.
    /// A room listed counter-clockwise faces inwards.
    #[must_use]
    pub fn normal(&self) -> DVec2 {
        let d = self.b - self.a;
        DVec2::new(-d.y, d.x) / d.length()
    }

    /// The point `a + u (b − a)`; `u = 0` is `a`, `u = 1` is `b`.
    #[must_use]
    pub fn point_at(&self, u: f64) -> DVec2 {
        self.a + (self.b - self.a) * u
    }

    /// Checks every rule of docs/ALGORITHM.md §1 for this edge; `index` names it in the error.
    fn validate(&self, index: usize) -> Result<(), GeomError> {
        let coords = [
            ("a.x", self.a.x),
            ("a.y", self.a.y),
            ("b.x", self.b.x),
            ("b.y", self.b.y),
        ];
        for (field, value) in coords {
            if !value.is_finite() {
                return Err(GeomError::NonFinite {
                    edge: index,
                    field,
                    value,
                });
            }
        }
        let d = self.b - self.a;
        if !d.x.is_finite() || !d.y.is_finite() || !d.length().is_finite() {
            return Err(GeomError::NonFinite {
                edge: index,
                field: "length |b - a|",
                value: d.length(),
            });
        }
        // An edge so short that |b − a|² underflows has no usable normal: same rule as a == b.
        if d.length_squared() <= 0.0 || !self.normal().is_finite() {
            return Err(GeomError::ZeroLength {
                edge: index,
                ax: self.a.x,
                ay: self.a.y,
                bx: self.b.x,
                by: self.b.y,
            });
        }
        if !(0.0..=1.0).contains(&self.reflectance) {
            return Err(GeomError::Reflectance {
                edge: index,
                value: self.reflectance,
            });
        }
        if !self.emission.is_finite() || self.emission < 0.0 {
            return Err(GeomError::Emission {
                edge: index,
                value: self.emission,
            });
        }
        Ok(())
    }
}

/// A point of the parameterization: which edge, where, and that edge's front normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Index into [`Scene::edges`].
    pub edge: usize,
    /// The point.
    pub position: DVec2,
    /// Front normal of the edge (of its parent edge for a piece made by [`Scene::subdivide`]).
    pub normal: DVec2,
}

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
    pub rank: Option<usize>,
}

/// A validated Flatland scene (docs/ALGORITHM.md §1): edges, the arc-length parameterization of its surface
/// edges, and the parent structure left by [`Scene::subdivide`].
///
/// The only ways to get one are [`Scene::new`], loading/deserializing (which validate) and the
/// methods that derive a scene from another, so every `Scene` in memory is valid: finite
/// coordinates, positive lengths, ρ ∈ [0, 1], finite E ≥ 0, at least one surface edge.
///
/// Serialized form (`.ron` or `.json`): `{"edges": [{"a": [0, 0], "b": [1, 0], "reflectance":
/// 0.5, "emission": 0.0, "role": "surface", "two_sided": false}, ...]}`; `emission`, `role` and
/// `two_sided` are optional. The parent structure is not serialized: a saved subdivided scene
/// loads as independent edges (same kernel up to rounding, but culling no longer merges pieces).
#[derive(Clone, PartialEq)]
pub struct Scene {
    edges: Vec<Edge>,
    group_of: Vec<usize>,
    groups: Vec<Group>,
    surface_edges: Vec<usize>,
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
            .field("parent_groups", &self.groups.len())
            .field("total_length", &self.total_length)
            .finish()
    }
}

impl Scene {
    /// Validates `edges` and builds the scene. Errors name the first offending edge and the rule.
    pub fn new(edges: Vec<Edge>) -> Result<Scene, GeomError> {
        let runs = vec![1; edges.len()];
        Scene::from_runs(edges, &runs)
    }

    /// Builds a scene whose edges are grouped in consecutive runs of `runs[i]` pieces.
    fn from_runs(edges: Vec<Edge>, runs: &[usize]) -> Result<Scene, GeomError> {
        for (i, edge) in edges.iter().enumerate() {
            edge.validate(i)?;
        }
        if !edges.iter().any(|e| e.role == Role::Surface) {
            return Err(GeomError::NoSurface { edges: edges.len() });
        }
        debug_assert_eq!(runs.iter().sum::<usize>(), edges.len());
        let mut groups = Vec::with_capacity(runs.len());
        let mut group_of = Vec::with_capacity(edges.len());
        let mut surface_groups = Vec::new();
        let mut cum = vec![0.0];
        let mut first = 0;
        for &count in runs {
            let parent = Edge {
                a: edges[first].a,
                b: edges[first + count - 1].b,
                ..edges[first]
            };
            let rank = (parent.role == Role::Surface).then(|| {
                surface_groups.push(groups.len());
                cum.push(cum.last().copied().unwrap_or(0.0) + parent.length());
                surface_groups.len() - 1
            });
            group_of.extend(std::iter::repeat_n(groups.len(), count));
            groups.push(Group {
                first,
                count,
                a: parent.a,
                b: parent.b,
                normal: parent.normal(),
                length: parent.length(),
                edge: parent,
                rank,
            });
            first += count;
        }
        let total_length = *cum.last().unwrap_or(&0.0);
        // L is finite: every length passed `validate`, where |b − a|² must not overflow, so
        // each is below 1.4e154 and no realistic edge count can sum past f64::MAX.
        let surface_edges = (0..edges.len())
            .filter(|&i| edges[i].role == Role::Surface)
            .collect();
        let inv_length = surface_groups
            .iter()
            .map(|&g| 1.0 / groups[g].length)
            .collect();
        let n = surface_groups.len();
        let nb = (4 * n).max(64);
        let buckets = (0..nb)
            .map(|b| {
                let arc = b as f64 / nb as f64 * total_length;
                cum[1..n].partition_point(|&c| c <= arc).min(n - 1) as u32
            })
            .collect();
        Ok(Scene {
            edges,
            group_of,
            groups,
            surface_edges,
            surface_groups,
            cum,
            inv_length,
            buckets,
            total_length,
        })
    }

    /// All edges, surfaces and blockers, in file order.
    #[must_use]
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Indices (into [`Scene::edges`]) of the surface edges, in parameter (file) order.
    #[must_use]
    pub fn surface_edges(&self) -> &[usize] {
        &self.surface_edges
    }

    /// Total length `L` of the surface edges.
    #[must_use]
    pub fn total_length(&self) -> f64 {
        self.total_length
    }

    /// The edges cut from the same parent edge as `edge` by [`Scene::subdivide`], as a range of
    /// consecutive indices (`edge..edge + 1` for an edge that was never subdivided); `None` for
    /// a bad index. The parent runs from `edges()[range.start].a` to `edges()[range.end - 1].b`
    /// and has the material of every piece: a solver that meshes or occludes with whole
    /// edges uses this, so a subdivided scene costs what the original does.
    #[must_use]
    pub fn parent_pieces(&self, edge: usize) -> Option<std::ops::Range<usize>> {
        let g = &self.groups[*self.group_of.get(edge)?];
        Some(g.first..g.first + g.count)
    }

    /// The parameter interval `[s0, s1)` of a surface edge, `None` for a blocker or a bad index.
    #[must_use]
    pub fn edge_param_range(&self, edge: usize) -> Option<(f64, f64)> {
        let g = &self.groups[*self.group_of.get(edge)?];
        let rank = g.rank?;
        let k = (edge - g.first) as f64;
        let n = g.count as f64;
        let l = self.total_length;
        let s0 = (self.cum[rank] + g.length * (k / n)) / l;
        let last = rank + 1 == self.surface_groups.len() && edge + 1 == g.first + g.count;
        let s1 = if last {
            1.0
        } else {
            (self.cum[rank] + g.length * ((k + 1.0) / n)) / l
        };
        Some((s0, s1))
    }

    /// The point at arc length `s·L` along the surface chain.
    ///
    /// `s` is taken modulo 1 (the chain is a loop of parameter: `point(-0.25) == point(0.75)`);
    /// a non-finite `s` gives `point(0)`. Never panics. For a scene made by
    /// [`Scene::subdivide`] the result is bit for bit the original scene's, except `edge`, which
    /// names the piece.
    #[must_use]
    pub fn point(&self, s: f64) -> SurfacePoint {
        let (g, u) = self.locate(s);
        let group = &self.groups[g];
        SurfacePoint {
            edge: piece_of(group, u),
            position: lerp(group.a, group.b, u),
            normal: group.normal,
        }
    }

    /// The parameter `s` of the point of surface edge `edge` nearest to `p` (orthogonal
    /// projection, clamped to the edge): the inverse of [`Scene::point`]. `None` for a blocker,
    /// a bad index or a non-finite `p`.
    #[must_use]
    pub fn param_of(&self, edge: usize, p: DVec2) -> Option<f64> {
        let g = &self.groups[*self.group_of.get(edge)?];
        let rank = g.rank?;
        if !p.is_finite() {
            return None;
        }
        let d = g.b - g.a;
        let k = (edge - g.first) as f64;
        let n = g.count as f64;
        let u = ((p - g.a).dot(d) / d.length_squared()).clamp(k / n, (k + 1.0) / n);
        Some(below_one(
            (self.cum[rank] + u * g.length) / self.total_length,
        ))
    }

    /// Splits every surface edge into `m` equal edges (blockers stay as they are).
    /// [`Scene::point`] is unchanged for every `s`, and the kernel over `(s, t)` is the same
    /// function: the pieces remember their parent edge. `m = 0` is an error.
    pub fn subdivide(&self, m: usize) -> Result<Scene, GeomError> {
        if m == 0 {
            return Err(GeomError::Param {
                name: "subdivision count m",
                range: "[1, inf)",
                value: 0.0,
            });
        }
        let mut edges = Vec::with_capacity(self.edges.len() * m);
        let mut runs = Vec::with_capacity(self.groups.len());
        for g in &self.groups {
            if g.rank.is_none() {
                edges.extend_from_slice(&self.edges[g.first..g.first + g.count]);
                runs.push(g.count);
                continue;
            }
            let n = g.count.checked_mul(m).ok_or(GeomError::Param {
                name: "subdivision count m",
                range: "[1, usize::MAX / pieces]",
                value: m as f64,
            })?;
            let at = |k: usize| {
                if k == n {
                    g.b
                } else {
                    lerp(g.a, g.b, k as f64 / n as f64)
                }
            };
            for k in 0..n {
                edges.push(Edge {
                    a: at(k),
                    b: at(k + 1),
                    ..g.edge
                });
            }
            runs.push(n);
        }
        Scene::from_runs(edges, &runs)
    }

    /// The scene with edge `index` replaced by `edge` (validated). If `index` was a piece of a
    /// subdivided edge, that parent's pieces become independent edges.
    pub fn with_edge(&self, index: usize, edge: Edge) -> Result<Scene, GeomError> {
        if index >= self.edges.len() {
            return Err(GeomError::EdgeIndex {
                index,
                len: self.edges.len(),
            });
        }
        let mut edges = self.edges.clone();
        edges[index] = edge;
        let hit = self.group_of[index];
        let mut runs = Vec::with_capacity(self.groups.len());
        for (i, g) in self.groups.iter().enumerate() {
            if i == hit {
                runs.extend(std::iter::repeat_n(1, g.count));
            } else {
                runs.push(g.count);
            }
        }
        Scene::from_runs(edges, &runs)
    }

    /// A stable 64-bit fingerprint of the edges: FNV-1a over, in order, the edge count and for
    /// each edge the IEEE bits of `a.x, a.y, b.x, b.y, reflectance, emission` (little endian,
    /// `-0.0` counted as `0.0`), then one byte for the role (0 surface, 1 blocker) and one for
    /// `two_sided`. Same on every run and platform; the parent structure is not included.
    #[must_use]
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv1a::default();
        h.write(&(self.edges.len() as u64).to_le_bytes());
        for e in &self.edges {
            for v in [e.a.x, e.a.y, e.b.x, e.b.y, e.reflectance, e.emission] {
                let v = if v == 0.0 { 0.0 } else { v };
                h.write(&v.to_bits().to_le_bytes());
            }
            h.write(&[u8::from(e.role == Role::Blocker), u8::from(e.two_sided)]);
        }
        h.0
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

    /// The parameter interval `[s0, s1)` of the parent surface edge of rank `rank` (the
    /// surface edges laid end to end, pieces of a subdivided edge together); `None` past the
    /// last rank.
    #[must_use]
    pub fn parent_param_range(&self, rank: usize) -> Option<(f64, f64)> {
        if rank + 1 >= self.cum.len() {
            return None;
        }
        let l = self.total_length;
        let s1 = if rank + 2 == self.cum.len() {
            1.0
        } else {
            self.cum[rank + 1] / l
        };
        Some((self.cum[rank] / l, s1))
    }

    // ----- crate internals used by the kernel -----

    /// The parent groups (a single edge is a group of one).
    pub(crate) fn groups(&self) -> &[Group] {
        &self.groups
    }

    /// The group of edge `edge`.
    pub(crate) fn group_of(&self, edge: usize) -> usize {
        self.group_of[edge]
    }

    /// Group index and parameter `u ∈ [0, 1]` along it of the point `s` (see [`Scene::point`]).
    /// The hot path of every kernel evaluation.
    #[inline(always)]
    pub(crate) fn locate(&self, s: f64) -> (usize, f64) {
        let s = wrap(s);
        let arc = s * self.total_length;
        let n = self.surface_groups.len();
        let r = if n <= SMALL_SCENE {
            // Branch-free count of the group starts at or before `arc`: no data-dependent
            // branch or load chain, which is what a binary search costs on a few edges.
            self.cum[1..n].iter().map(|&c| usize::from(c <= arc)).sum()
        } else {
            // Start from the bucket's rank; the scans fix any rounding at bucket borders.
            let nb = self.buckets.len();
            let mut r = self.buckets[((s * nb as f64) as usize).min(nb - 1)] as usize;
            while r > 0 && self.cum[r] > arc {
                r -= 1;
            }
            while r + 1 < n && self.cum[r + 1] <= arc {
                r += 1;
            }
            r
        };
        let g = self.surface_groups[r];
        let u = ((arc - self.cum[r]) * self.inv_length[r]).clamp(0.0, 1.0);
        (g, u)
    }

    /// The position at parameter `u` along group `g` (what [`Scene::point`] returns).
    #[inline]
    pub(crate) fn group_point(&self, g: usize, u: f64) -> DVec2 {
        let group = &self.groups[g];
        lerp(group.a, group.b, u)
    }

    /// The piece of group `g` containing parameter `u`.
    #[inline]
    pub(crate) fn piece(&self, g: usize, u: f64) -> usize {
        piece_of(&self.groups[g], u)
    }

    /// The serializable form.
    pub(crate) fn to_raw(&self) -> RawScene {
        RawScene {
            edges: self.edges.iter().map(RawEdge::from).collect(),
        }
    }
}

/// Up to this many surface groups [`Scene::locate`] counts instead of searching.
const SMALL_SCENE: usize = 16;

#[inline]
fn lerp(a: DVec2, b: DVec2, u: f64) -> DVec2 {
    a + (b - a) * u
}

#[inline]
fn piece_of(g: &Group, u: f64) -> usize {
    g.first + ((u * g.count as f64) as usize).min(g.count - 1)
}

/// `s` modulo 1 in `[0, 1)`; non-finite gives 0.
#[inline]
fn wrap(s: f64) -> f64 {
    if (0.0..1.0).contains(&s) {
        s
    } else if s.is_finite() {
        below_one(s.rem_euclid(1.0))
    } else {
        0.0
    }
}

/// Maps a value that rounded up to 1 to the largest `f64` below 1.
#[inline]
fn below_one(s: f64) -> f64 {
    if s >= 1.0 {
        1.0 - f64::EPSILON / 2.0
    } else {
        s.max(0.0)
    }
}

/// 64-bit FNV-1a.
struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The file schema of a scene, before validation.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    pub edges: Vec<RawEdge>,
}

/// The file schema of an edge.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEdge {
    a: [f64; 2],
    b: [f64; 2],
    reflectance: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    emission: f64,
    #[serde(default, skip_serializing_if = "is_surface")]
    role: Role,
    #[serde(default, skip_serializing_if = "is_false")]
    two_sided: bool,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
fn is_surface(r: &Role) -> bool {
    *r == Role::Surface
}
fn is_false(b: &bool) -> bool {
    !*b
}

impl From<&Edge> for RawEdge {
    fn from(e: &Edge) -> Self {
        RawEdge {
            a: e.a.to_array(),
            b: e.b.to_array(),
            reflectance: e.reflectance,
            emission: e.emission,
            role: e.role,
            two_sided: e.two_sided,
        }
    }
}

impl TryFrom<RawScene> for Scene {
    type Error = GeomError;
    fn try_from(raw: RawScene) -> Result<Scene, GeomError> {
        Scene::new(
            raw.edges
                .into_iter()
                .map(|e| Edge {
                    a: DVec2::from_array(e.a),
                    b: DVec2::from_array(e.b),
                    reflectance: e.reflectance,
                    emission: e.emission,
                    role: e.role,
                    two_sided: e.two_sided,
                })
                .collect(),
        )
    }
}

impl Serialize for Scene {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_raw().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Scene {
    /// Deserializes through validation: an invalid scene is a deserialization error.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Scene, D::Error> {
        let raw = RawScene::deserialize(deserializer)?;
        Scene::try_from(raw).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assert_close;
    use crate::test_support::{bundled, rng, room, unit_box};
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn triangle() -> Vec<Edge> {
        room(&[v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)], 0.5)
    }

    /// Builds a scene whose edge 1 is `bad` and checks the message names edge 1 and `rule`.
    fn assert_rejected(bad: Edge, rule: &str) {
        let mut edges = triangle();
        edges[1] = bad;
        let err = Scene::new(edges).unwrap_err().to_string();
        assert!(
            err.starts_with("edge 1: "),
            "message does not name the edge: {err}"
        );
        assert!(
            err.contains(rule),
            "message does not state the rule `{rule}`: {err}"
        );
    }

    #[test]
    fn non_finite_coordinates_are_rejected_naming_the_edge() {
        assert_rejected(
            Edge::surface(v(f64::NAN, 0.0), v(1.0, 0.0), 0.5),
            "a.x must be finite",
        );
        assert_rejected(
            Edge::surface(v(0.0, 0.0), v(1.0, f64::INFINITY), 0.5),
            "b.y must be finite",
        );
        let overflow = Edge::surface(v(-1e308, 0.0), v(1e308, 0.0), 0.5);
        assert_rejected(overflow, "length |b - a| must be finite");
    }

    #[test]
    fn zero_length_is_rejected_naming_the_edge() {
        assert_rejected(Edge::surface(v(1.0, 1.0), v(1.0, 1.0), 0.5), "zero length");
        // |b − a|² underflows: no usable normal, same rule.
        assert_rejected(
            Edge::surface(v(0.0, 0.0), v(1e-170, 0.0), 0.5),
            "zero length",
        );
    }

    #[test]
    fn reflectance_outside_unit_interval_is_rejected_naming_the_edge() {
        for bad in [-0.1, 1.5, f64::NAN] {
            assert_rejected(
                Edge::surface(v(0.0, 0.0), v(1.0, 0.0), bad),
                "reflectance must be in [0, 1]",
            );
        }
    }

    #[test]
    fn bad_emission_is_rejected_naming_the_edge() {
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let e = Edge::surface(v(0.0, 0.0), v(1.0, 0.0), 0.5).with_emission(bad);
            assert_rejected(e, "emission must be finite and >= 0");
        }
    }

    #[test]
    fn a_scene_without_surfaces_is_rejected() {
        let err = Scene::new(vec![Edge::blocker(v(0.0, 0.0), v(1.0, 0.0))])
            .unwrap_err()
            .to_string();
        assert!(err.contains("no surface edge"), "{err}");
        assert!(
            Scene::new(vec![])
                .unwrap_err()
                .to_string()
                .contains("no surface edge")
        );
    }

    #[test]
    fn normal_is_the_left_of_a_to_b() {
        let e = Edge::surface(v(0.0, 0.0), v(2.0, 0.0), 0.5);
        assert_eq!(e.normal(), v(0.0, 1.0));
        assert_eq!(e.length(), 2.0);
        assert_eq!(e.point_at(0.25), v(0.5, 0.0));
    }

    #[test]
    fn point_walks_arc_length_in_file_order_skipping_blockers() {
        let mut edges = room(&[v(0.0, 0.0), v(2.0, 0.0), v(2.0, 1.0), v(0.0, 1.0)], 0.5);
        edges.insert(1, Edge::blocker(v(0.5, 0.5), v(1.5, 0.5)));
        let scene = Scene::new(edges).unwrap();
        assert_eq!(scene.total_length(), 6.0);
        assert_eq!(scene.surface_edges(), &[0, 2, 3, 4]);
        let p = scene.point(1.0 / 6.0);
        assert_eq!(
            (p.edge, p.position, p.normal),
            (0, v(1.0, 0.0), v(0.0, 1.0))
        );
        let p = scene.point(2.5 / 6.0);
        assert_eq!((p.edge, p.position), (2, v(2.0, 0.5)));
        assert_eq!(scene.edge_param_range(1), None);
        assert_eq!(scene.edge_param_range(0), Some((0.0, 2.0 / 6.0)));
        assert_eq!(scene.edge_param_range(4), Some((5.0 / 6.0, 1.0)));
        assert_eq!(scene.param_of(1, v(1.0, 0.5)), None);
        assert_eq!(scene.param_of(99, v(1.0, 0.5)), None);
    }

    #[test]
    fn point_wraps_outside_the_unit_interval_and_never_panics() {
        let scene = unit_box();
        assert_eq!(scene.point(-0.25), scene.point(0.75));
        assert_eq!(scene.point(1.25), scene.point(0.25));
        assert_eq!(scene.point(f64::NAN), scene.point(0.0));
        assert_eq!(scene.point(f64::INFINITY), scene.point(0.0));
        let end = scene.point(-1e-300);
        assert_eq!(end.edge, 3);
        assert!(end.position.distance(v(0.0, 0.0)) < 1e-12);
    }

    #[test]
    fn param_of_inverts_point() {
        let scene = bundled("fig3");
        let mut r = rng(1);
        for _ in 0..1000 {
            let s: f64 = r.random_range(0.0..1.0);
            let p = scene.point(s);
            let back = scene.param_of(p.edge, p.position).unwrap();
            assert_close!(back, s, 1e-14);
            let (s0, s1) = scene.edge_param_range(p.edge).unwrap();
            assert!(
                s0 <= s && s < s1,
                "{s} not in [{s0}, {s1}) of edge {}",
                p.edge
            );
        }
    }

    #[test]
    fn subdivide_leaves_point_unchanged_bit_for_bit() {
        let scene = bundled("fig3");
        let fine = scene.subdivide(1000).unwrap();
        let surfaces = scene.surface_edges().len();
        assert_eq!(
            fine.edges().len(),
            surfaces * 1000 + (scene.edges().len() - surfaces)
        );
        assert_eq!(fine.total_length(), scene.total_length());
        let mut r = rng(2);
        for _ in 0..10_000 {
            let s: f64 = r.random_range(0.0..1.0);
            let (p, q) = (scene.point(s), fine.point(s));
            assert_eq!((p.position, p.normal), (q.position, q.normal), "s = {s}");
            let piece = fine.edges()[q.edge];
            assert!(
                piece.a.distance(q.position) + q.position.distance(piece.b)
                    <= piece.length() + 1e-12
            );
            let back = fine.param_of(q.edge, q.position).unwrap();
            assert_close!(back, s, 1e-14);
        }
        // Every piece knows its parent's run; an edge never subdivided is its own run.
        let first = fine.surface_edges()[0];
        assert_eq!(fine.parent_pieces(first), Some(first..first + 1000));
        assert_eq!(fine.parent_pieces(first + 999), Some(first..first + 1000));
        let blocker = fine.edges().len() - 1;
        assert_eq!(fine.parent_pieces(blocker), Some(blocker..blocker + 1));
        assert_eq!(fine.parent_pieces(fine.edges().len()), None);
        // Subdividing twice is the same as once with the product.
        let twice = scene.subdivide(10).unwrap().subdivide(100).unwrap();
        assert_eq!(twice.edges().len(), fine.edges().len());
        assert!(
            scene
                .subdivide(0)
                .unwrap_err()
                .to_string()
                .contains("[1, inf)")
        );
    }

    #[test]
    fn locate_agrees_with_a_binary_search_on_large_and_small_scenes() {
        let mut r = rng(9);
        for n in [3, 16, 17, 300] {
            // A polygon with uneven edge lengths (above 16 surfaces, locate uses its buckets).
            let mut angles: Vec<f64> = (0..n)
                .map(|_| r.random_range(0.0..std::f64::consts::TAU))
                .collect();
            angles.sort_by(f64::total_cmp);
            angles.dedup();
            let pts: Vec<DVec2> = angles.iter().map(|a| v(a.cos(), a.sin())).collect();
            let scene = Scene::new(room(&pts, 0.5)).unwrap();
            let mut samples: Vec<f64> = (0..2000).map(|_| r.random_range(0.0..1.0)).collect();
            samples.extend(scene.cum.iter().map(|c| c / scene.total_length));
            for s in samples {
                let arc = wrap(s) * scene.total_length;
                let n = scene.surface_groups.len();
                let expected = scene.cum[1..n].partition_point(|&c| c <= arc);
                let (g, u) = scene.locate(s);
                assert_eq!(scene.groups[g].rank, Some(expected), "s = {s}");
                assert!((0.0..=1.0).contains(&u));
            }
        }
    }

    #[test]
    fn with_edge_replaces_and_validates() {
        let scene = unit_box();
        let moved = scene
            .with_edge(1, Edge::surface(v(1.0, 0.0), v(1.2, 1.0), 0.5))
            .unwrap();
        assert_eq!(moved.edges()[1].b, v(1.2, 1.0));
        assert_ne!(moved.fingerprint(), scene.fingerprint());
        let err = scene
            .with_edge(2, Edge::surface(v(1.0, 1.0), v(1.0, 1.0), 0.5))
            .unwrap_err();
        assert!(err.to_string().starts_with("edge 2: zero length"), "{err}");
        assert!(
            scene
                .with_edge(9, scene.edges()[0])
                .unwrap_err()
                .to_string()
                .contains("index 9")
        );
        // Moving one piece of a subdivided edge frees its siblings.
        let fine = scene.subdivide(4).unwrap();
        let e = fine.edges()[5];
        let moved = fine
            .with_edge(
                5,
                Edge {
                    b: e.b + v(0.1, 0.0),
                    ..e
                },
            )
            .unwrap();
        assert_eq!(moved.edges().len(), 16);
        assert_eq!(moved.groups().len(), 3 + 4);
    }

    #[test]
    fn fingerprint_is_stable_and_sensitive() {
        let scene = unit_box();
        // Pinned: the fingerprint must not change across runs, versions or platforms. The value
        // was checked against an independent FNV-1a (Python, struct.pack('<d')).
        assert_eq!(scene.fingerprint(), unit_box().fingerprint());
        assert_eq!(
            scene.fingerprint(),
            0xbf7f_c1e8_79d8_5ffc,
            "{:#x}",
            scene.fingerprint()
        );
        let mut edges = scene.edges().to_vec();
        edges[0].reflectance = 0.25;
        assert_ne!(
            Scene::new(edges.clone()).unwrap().fingerprint(),
            scene.fingerprint()
        );
        edges[0].reflectance = 0.5;
        edges[0].a = v(-0.0, 0.0);
        assert_eq!(
            Scene::new(edges).unwrap().fingerprint(),
            scene.fingerprint()
        );
    }

    #[test]
    fn bounds_and_max_emission() {
        let scene = bundled("fig3");
        assert_eq!(scene.bounds(), (v(0.0, 0.0), v(4.0, 3.0)));
        assert_eq!(scene.max_emission(), 1.0);
    }

    #[test]
    fn json_and_ron_round_trip_and_defaults() {
        let text = r#"{"edges":[{"a":[0,0],"b":[1,0],"reflectance":0.5},
            {"a":[1,0],"b":[0,1],"reflectance":0.5,"emission":2,"two_sided":true},
            {"a":[0,1],"b":[0,0],"reflectance":0.5,"role":"blocker"}]}"#;
        let scene = Scene::from_json_str(text).unwrap();
        assert_eq!(scene.edges()[0].role, Role::Surface);
        assert!(scene.edges()[1].two_sided);
        assert_eq!(scene.edges()[2].role, Role::Blocker);
        let dir = std::env::temp_dir().join(format!("flatland-geom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for ext in ["ron", "json", "RON"] {
            let path = dir.join(format!("scene.{ext}"));
            scene.save(&path).unwrap();
            assert_eq!(Scene::load(&path).unwrap(), scene, "{ext}");
        }
        let json = serde_json::to_string(&scene).unwrap();
        assert_eq!(serde_json::from_str::<Scene>(&json).unwrap(), scene);
        assert_eq!(
            Scene::from_ron_str(&ron::to_string(&scene).unwrap()).unwrap(),
            scene
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn parse_errors_name_file_line_and_column() {
        let dir = std::env::temp_dir().join(format!("flatland-geom-err-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.json");
        std::fs::write(
            &path,
            "{\"edges\": [\n  {\"a\": [0, 0], \"b\": [1, 0], \"reflectence\": 0.5}]}",
        )
        .unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}:2:", path.display())), "{err}");
        assert!(err.contains("reflectence"), "{err}");
        let path = dir.join("bad.ron");
        std::fs::write(
            &path,
            "// comment\n(edges: [\n  (a: (0, 0), b: (1, 0), reflectance: 0.5, role: wall)])",
        )
        .unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}:3:", path.display())), "{err}");
        let path = dir.join("invalid.ron");
        std::fs::write(&path, "(edges: [(a: (0, 0), b: (0, 0), reflectance: 0.5)])").unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.contains("invalid.ron: edge 0: zero length"), "{err}");
        let err = Scene::load(dir.join("scene.txt")).unwrap_err().to_string();
        assert!(err.contains("unknown scene format"), "{err}");
        let err = Scene::load(dir.join("missing.ron"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing.ron"), "{err}");
        let err = serde_json::from_str::<Scene>(r#"{"edges":[]}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("no surface edge"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bundled_scenes_load() {
        for name in ["fig3", "box", "maze", "corners"] {
            let scene = bundled(name);
            assert!(scene.total_length() > 0.0);
            assert!(scene.max_emission() > 0.0, "{name} has no light");
        }
    }

    proptest! {
        #[test]
        fn point_stays_on_its_edge(s in -2.0f64..2.0, m in 1usize..50) {
            let scene = bundled("corners").subdivide(m).unwrap();
            let p = scene.point(s);
            let e = scene.edges()[p.edge];
            prop_assert_eq!(e.role, Role::Surface);
            let slack = 1e-12 * (1.0 + e.length());
            prop_assert!(e.a.distance(p.position) + p.position.distance(e.b) <= e.length() + slack);
        }
    }
}
