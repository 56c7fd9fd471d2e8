//! Elements: intervals of the surface edges on which the radiosity is constant.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use std::ops::Range;

use flatland_geom::{DVec2, EdgeId, Kernel, PointLight, Scene};
use rayon::prelude::*;

use crate::bvh::{Aabb, Bvh};
use crate::{InputFrame, SolveError};

/// A surface edge as the solver sees it: a whole edge of the scene (all pieces of an edge that
/// [`Scene::subdivide`] cut, which share one line and one material), with its elements.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshEdge {
    /// The scene edges (pieces) it is made of, as indices into [`Scene::edges`]; `pieces.start`
    /// names it.
    pub pieces: Range<usize>,
    /// Its parameter interval `[s0, s1)`.
    pub s: [f64; 2],
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Front normal.
    pub normal: DVec2,
    /// ρ.
    pub reflectance: f64,
    /// E.
    pub emission: f64,
    /// E', the weight ζ = E'·k gives its rows (the exact kernel's source weight).
    pub source_weight: f64,
    /// Its elements (indices into [`Mesh::elements`]).
    pub elements: Range<usize>,
    /// Where other edges touch or cross it, as fractions `u ∈ (0, 1)` from `a` to `b`: B jumps
    /// there (a partition standing on a floor sees different halves of the room from its two
    /// sides), so element boundaries are placed there.
    pub junctions: Vec<f64>,
}

/// One element: an interval of one surface edge, never straddling two. The unknown `B` is
/// constant on it and the equation is collocated at its midpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Index into [`Mesh::edges`].
    pub mesh_edge: usize,
    /// The scene edge (piece) its midpoint lies on.
    pub edge: EdgeId,
    /// Its parameter interval `[s0, s1)`.
    pub s: [f64; 2],
    /// The parameter of its midpoint (the collocation point).
    pub s_mid: f64,
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// The midpoint: where the equation is collocated.
    pub midpoint: DVec2,
    /// Arc length `L · (s1 − s0)`.
    pub length: f64,
}

/// The elements of a scene, in parameter order, with the materials the solver needs and the
/// geometry in a unit frame (so no product of coordinates over- or underflows at any scale).
#[derive(Clone, Debug)]
pub struct Mesh {
    edges: Vec<MeshEdge>,
    elements: Vec<Element>,
    /// Frame coordinates of each element's end points and midpoint.
    local: Vec<[DVec2; 3]>,
    /// Each element's `[u0, u1, u_mid]` along its mesh edge.
    fractions: Vec<[f64; 3]>,
    frame: InputFrame,
    total_length: f64,
    fingerprint: u64,
    /// The scene's point lights.
    lights: Vec<PointLight>,
    /// Their mean irradiance per element; empty without lights.
    direct: Vec<f64>,
}

/// Most elements a dense operator may have: it holds N² numbers (8192² · 8 B = 512 MiB). A mesh
/// may have more ([`MAX_MESH_ELEMENTS`]); the exact kernel's sparse operator
/// ([`sweep_operator`](crate::sweep_operator)) is not bound by it.
pub const MAX_ELEMENTS: usize = 8192;

/// Most elements any mesh may have: about 2 GiB of elements, and column indices of a sparse
/// operator fit in `u32`.
pub const MAX_MESH_ELEMENTS: usize = 1 << 24;

/// The default element count: about this many over the whole scene, and at least
/// [`MIN_PER_EDGE`] per section of a surface edge. Measured against 8192 elements, 512 put the
/// reflected part of every bundled scene's exact solve within 0.1 % (`flatland solve
/// --reference-elements 8192`).
pub const DEFAULT_ELEMENTS: usize = 512;

/// Fewest elements the default gives a section of a surface edge.
pub const MIN_PER_EDGE: usize = 2;

impl Mesh {
    /// The default element count for `scene` when it is compared with dense operators:
    /// [`DEFAULT_ELEMENTS`], raised so every section of a surface edge gets [`MIN_PER_EDGE`]
    /// elements, capped at [`MAX_ELEMENTS`] (but never below one element per section).
    #[must_use]
    pub fn default_elements(scene: &Scene) -> usize {
        let sections = Mesh::min_elements(scene);
        DEFAULT_ELEMENTS
            .max(MIN_PER_EDGE * sections)
            .min(MAX_ELEMENTS.max(sections))
    }

    /// [`Mesh::new`] without the lights' direct light (its source is E alone): the elements
    /// only. `Mesh::new` and `Mesh::coarsest` are in `lights.rs`, above the sweep that lights
    /// them.
    pub(crate) fn unlit(kernel: &Kernel, elements: usize) -> Result<Mesh, SolveError> {
        let scene = kernel.scene();
        let runs = surface_runs(scene);
        let cuts = all_junctions(scene, &runs);
        let fewest = sections(&cuts);
        if elements < fewest || elements > MAX_MESH_ELEMENTS {
            return Err(SolveError::InvalidParameter {
                name: "elements",
                value: elements.to_string(),
                valid: if elements > MAX_MESH_ELEMENTS {
                    "at most 16777216 (2²⁴: a mesh's elements are indexed by u32)"
                } else {
                    "at least one per section of a surface edge (elements never straddle two \
                     edges, nor a point where another edge touches or crosses one)"
                },
            });
        }
        Ok(Mesh::build(kernel, runs, &cuts, elements))
    }

    fn build(kernel: &Kernel, runs: Vec<Range<usize>>, cuts: &[Vec<f64>], elements: usize) -> Mesh {
        let scene = kernel.scene();
        let lengths = run_lengths(scene, &runs);
        // Sections: the parts of each edge between its ends and junctions, in order.
        let sections: Vec<(usize, f64, f64)> = cuts
            .iter()
            .enumerate()
            .flat_map(|(k, c)| c.windows(2).map(move |w| (k, w[0], w[1])))
            .collect();
        let section_lengths: Vec<f64> = sections
            .iter()
            .map(|&(k, u0, u1)| (u1 - u0) * lengths[k])
            .collect();
        let counts = apportion(&section_lengths, elements);
        let mut fractions: Vec<Vec<[f64; 3]>> = vec![Vec::new(); runs.len()];
        for (&(k, u_start, u_end), &count) in sections.iter().zip(&counts) {
            fractions[k].extend((0..count).map(|e| {
                let along = |e: f64| {
                    if e >= count as f64 {
                        u_end
                    } else {
                        u_start + (u_end - u_start) * e / count as f64
                    }
                };
                [
                    along(e as f64),
                    along(e as f64 + 1.0),
                    along(e as f64 + 0.5),
                ]
            }));
        }
        let junctions = cuts.iter().map(|c| c[1..c.len() - 1].to_vec()).collect();
        Mesh::from_fractions(kernel, runs, junctions, fractions)
    }

    /// The mesh whose elements on run `k` span the fractions `fractions[k]` of it (`[u0, u1,
    /// u_mid]` from its start to its end, in order, tiling `[0, 1]`).
    fn from_fractions(
        kernel: &Kernel,
        runs: Vec<Range<usize>>,
        junctions: Vec<Vec<f64>>,
        fractions: Vec<Vec<[f64; 3]>>,
    ) -> Mesh {
        let scene = kernel.scene();
        let frame = InputFrame::of(scene);
        let edges: Vec<MeshEdge> = runs
            .into_iter()
            .zip(junctions)
            .map(|(run, junctions)| {
                let first = scene.edges()[run.start];
                let param = |e: usize| {
                    scene
                        .edge_param_range(EdgeId::new(e))
                        .expect("a surface edge has a parameter range")
                };
                MeshEdge {
                    s: [param(run.start).0, param(run.end - 1).1],
                    a: first.a,
                    b: scene.edges()[run.end - 1].b,
                    normal: first.normal(),
                    reflectance: first.reflectance,
                    emission: first.emission,
                    source_weight: kernel.source_weight(EdgeId::new(run.start)),
                    elements: 0..0,
                    junctions,
                    pieces: run,
                }
            })
            .collect();
        Mesh::assemble(
            edges,
            &fractions,
            frame,
            scene.total_length(),
            scene.fingerprint(),
        )
    }

    /// The elements of `edges` spanning `fractions` (per edge, as in
    /// [`Mesh::from_fractions`]).
    fn assemble(
        mut edges: Vec<MeshEdge>,
        fractions: &[Vec<[f64; 3]>],
        frame: InputFrame,
        total_length: f64,
        fingerprint: u64,
    ) -> Mesh {
        let count: usize = fractions.iter().map(Vec::len).sum();
        let local_point = |p: DVec2| DVec2::from(frame.map(p));
        let mut out = Vec::with_capacity(count);
        let mut local = Vec::with_capacity(count);
        let mut kept = Vec::with_capacity(count);
        for (k, (edge, parts)) in edges.iter_mut().zip(fractions).enumerate() {
            let (a, b, [s0, s1]) = (edge.a, edge.b, edge.s);
            let length = (b - a).length();
            // Positions as Scene::point computes them (a + (b − a) u), so a midpoint's `s`
            // names that very point.
            let at = |u: f64| if u >= 1.0 { b } else { a + (b - a) * u };
            let param = |u: f64| if u >= 1.0 { s1 } else { s0 + (s1 - s0) * u };
            let pieces = edge.pieces.len();
            let first = out.len();
            for &[u0, u1, um] in parts {
                let (pa, pb, pm) = (at(u0), at(u1), at(um));
                out.push(Element {
                    mesh_edge: k,
                    edge: EdgeId::new(
                        edge.pieces.start + ((um * pieces as f64) as usize).min(pieces - 1),
                    ),
                    s: [param(u0), param(u1)],
                    s_mid: param(um),
                    a: pa,
                    b: pb,
                    midpoint: pm,
                    length: (u1 - u0) * length,
                });
                local.push([local_point(pa), local_point(pb), local_point(pm)]);
                kept.push([u0, u1, um]);
            }
            edge.elements = first..out.len();
        }
        Mesh {
            edges,
            elements: out,
            local,
            fractions: kept,
            frame,
            total_length,
            fingerprint,
            lights: Vec::new(),
            direct: Vec::new(),
        }
    }

    /// This mesh with element `i` split into `parts[i]` equal elements (1 keeps it).
    /// Errors: `parts` not one count ≥ 1 per element, or more than [`MAX_MESH_ELEMENTS`] in all.
    pub(crate) fn split_unlit(&self, parts: &[usize]) -> Result<Mesh, SolveError> {
        let total: usize = parts.iter().sum();
        if parts.len() != self.len() || parts.contains(&0) || total > MAX_MESH_ELEMENTS {
            return Err(SolveError::InvalidParameter {
                name: "parts",
                value: format!("{} counts, {total} elements in all", parts.len()),
                valid: "one count ≥ 1 per element, at most 16777216 elements in all",
            });
        }
        Ok(self.refine(|i, [u0, u1, um], out| {
            let n = parts[i];
            if n == 1 {
                out.push([u0, u1, um]);
                return;
            }
            let along = |p: f64| {
                if p >= n as f64 {
                    u1
                } else {
                    u0 + (u1 - u0) * p / n as f64
                }
            };
            out.extend((0..n).map(|p| {
                let p = p as f64;
                [along(p), along(p + 1.0), along(p + 0.5)]
            }));
        }))
    }

    /// This mesh with every element cut at the fractions `cuts` of it (ascending, inside
    /// `(0, 1)`), each new element's midpoint at `mids` (one per new element, inside it): a
    /// nested mesh whose collocation points lie where its parent wants them. Errors: cuts or
    /// midpoints out of order or range, or more than [`MAX_MESH_ELEMENTS`] elements.
    pub(crate) fn cut_unlit(&self, cuts: &[f64], mids: &[f64]) -> Result<Mesh, SolveError> {
        let bounds: Vec<f64> = std::iter::once(0.0)
            .chain(cuts.iter().copied())
            .chain(std::iter::once(1.0))
            .collect();
        let ordered = bounds.windows(2).all(|w| w[0] < w[1]);
        let inside = mids.len() + 1 == bounds.len()
            && mids
                .iter()
                .zip(bounds.windows(2))
                .all(|(m, w)| w[0] < *m && m < &w[1]);
        if !ordered || !inside || mids.len() * self.len() > MAX_MESH_ELEMENTS {
            return Err(SolveError::InvalidParameter {
                name: "cuts",
                value: format!("{cuts:?} with midpoints {mids:?}"),
                valid: "ascending fractions in (0, 1), one midpoint inside each piece, at most \
                        16777216 elements in all",
            });
        }
        Ok(self.refine(|_, [u0, u1, _], out| {
            let at = |x: f64| if x >= 1.0 { u1 } else { u0 + (u1 - u0) * x };
            out.extend(
                bounds
                    .windows(2)
                    .zip(mids)
                    .map(|(w, &m)| [at(w[0]), at(w[1]), at(m)]),
            );
        }))
    }

    /// This mesh with element `i` (`[u0, u1, u_mid]`) replaced by what `pieces(i, span, out)`
    /// appends to `out`: spans tiling it, in order.
    fn refine(&self, pieces: impl Fn(usize, [f64; 3], &mut Vec<[f64; 3]>)) -> Mesh {
        let fractions: Vec<Vec<[f64; 3]>> = self
            .edges
            .iter()
            .map(|edge| {
                let mut out = Vec::with_capacity(edge.elements.len());
                for i in edge.elements.clone() {
                    pieces(i, self.fractions[i], &mut out);
                }
                out
            })
            .collect();
        let mut edges = self.edges.clone();
        for edge in &mut edges {
            edge.elements = 0..0;
        }
        Mesh::assemble(
            edges,
            &fractions,
            self.frame,
            self.total_length,
            self.fingerprint,
        )
    }

    /// Element `i`'s span along its mesh edge: `[u0, u1, u_mid]`, fractions from the edge's
    /// start `a` to its end `b`.
    #[must_use]
    pub fn fractions(&self, i: usize) -> [f64; 3] {
        self.fractions[i]
    }

    /// [`Mesh::coarsest`] without the lights' direct light.
    pub(crate) fn coarsest_unlit(kernel: &Kernel) -> Mesh {
        let scene = kernel.scene();
        let runs = surface_runs(scene);
        let cuts = all_junctions(scene, &runs);
        let fewest = sections(&cuts);
        Mesh::build(kernel, runs, &cuts, fewest)
    }

    /// Lights the mesh: the scene's `lights` and the mean irradiance `direct` they give each
    /// element.
    pub(crate) fn set_lights(&mut self, lights: Vec<PointLight>, direct: Vec<f64>) {
        debug_assert_eq!(direct.len(), self.len());
        self.lights = lights;
        self.direct = direct;
    }

    /// The fewest elements a mesh of `scene` can have: one per section, the parts of a surface
    /// edge between its ends and the points where other edges touch or cross it.
    #[must_use]
    pub fn min_elements(scene: &Scene) -> usize {
        sections(&all_junctions(scene, &surface_runs(scene)))
    }

    /// The elements, in parameter order.
    #[must_use]
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// Number of elements.
    #[must_use]
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// Whether there are no elements (never, for a valid mesh).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The surface edges (whole edges, in parameter order).
    #[must_use]
    pub fn edges(&self) -> &[MeshEdge] {
        &self.edges
    }

    /// The surface edge of element `i`.
    #[must_use]
    pub fn edge_of(&self, i: usize) -> &MeshEdge {
        &self.edges[self.elements[i].mesh_edge]
    }

    /// The source term per element, what the solver's `B = B₀ + K B` starts from:
    /// `B₀_i = E_i + ρ_i H̄_i`, E and the reflected direct light of the scene's point lights
    /// (`H̄_i` their mean irradiance over the element, exact: [`Mesh::direct_irradiance`]).
    /// Without lights it is E, bit for bit. `B − B₀` is the part a kernel decides.
    #[must_use]
    pub fn emission(&self) -> Vec<f64> {
        if self.direct.is_empty() {
            return (0..self.len()).map(|i| self.edge_of(i).emission).collect();
        }
        (0..self.len())
            .map(|i| {
                let edge = self.edge_of(i);
                edge.emission + edge.reflectance * self.direct[i]
            })
            .collect()
    }

    /// This mesh under another emission, `emission` one value per mesh edge
    /// ([`Mesh::edges`]): the same scene relit. It keeps its scene's fingerprint, lights and
    /// direct light, so the exact operator and the final gather of the scene's kernel apply to
    /// it (neither depends on emission but through the mesh's own). Errors: a length other
    /// than the edge count, a value negative or not finite.
    pub fn with_edge_emission(&self, emission: &[f64]) -> Result<Mesh, SolveError> {
        if emission.len() != self.edges.len() {
            return Err(SolveError::InvalidParameter {
                name: "emission",
                value: format!("{} values", emission.len()),
                valid: "one per mesh edge",
            });
        }
        if let Some(bad) = emission.iter().find(|e| !(e.is_finite() && **e >= 0.0)) {
            return Err(SolveError::InvalidParameter {
                name: "emission",
                value: bad.to_string(),
                valid: "finite and at least 0",
            });
        }
        let mut relit = self.clone();
        for (edge, &e) in relit.edges.iter_mut().zip(emission) {
            edge.emission = e;
        }
        Ok(relit)
    }

    /// The point lights of the scene the mesh was made for (what [`Mesh::fingerprint`] leaves
    /// out).
    #[must_use]
    pub fn lights(&self) -> &[PointLight] {
        &self.lights
    }

    /// Their mean irradiance `H̄_i` over each element (`Σ Φ Δφ_i / (2π l_i)`, `Δφ_i` the angle
    /// the element's visible front subtends from a light); empty for a scene without lights.
    #[must_use]
    pub fn direct_irradiance(&self) -> &[f64] {
        &self.direct
    }

    /// Total surface length `L`.
    #[must_use]
    pub fn total_length(&self) -> f64 {
        self.total_length
    }

    /// `Scene::fingerprint` of the scene it was made for.
    #[must_use]
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    /// The unit frame the solver computes geometry in.
    #[must_use]
    pub fn frame(&self) -> InputFrame {
        self.frame
    }

    /// A scene point in the unit frame.
    #[must_use]
    pub fn to_local(&self, p: DVec2) -> DVec2 {
        DVec2::from(self.frame.map(p))
    }

    /// Element `i`'s end points and midpoint in the unit frame.
    pub fn local(&self, i: usize) -> [DVec2; 3] {
        self.local[i]
    }

    /// The element whose `[s0, s1)` holds `s` (`s` clamped into `[0, 1)`).
    #[must_use]
    pub fn element_at(&self, s: f64) -> usize {
        let k = self.elements.partition_point(|e| e.s[0] <= s);
        k.saturating_sub(1)
    }
}

/// The length of each run, end to end.
fn run_lengths(scene: &Scene, runs: &[Range<usize>]) -> Vec<f64> {
    runs.iter()
        .map(|r| {
            let e = scene.edges();
            (e[r.end - 1].b - e[r.start].a).length()
        })
        .collect()
}

/// The surface edges of `scene` as runs of pieces (indices into [`Scene::edges`]), in
/// parameter order.
fn surface_runs(scene: &Scene) -> Vec<Range<usize>> {
    let mut runs: Vec<Range<usize>> = Vec::new();
    for &e in scene.surface_edges() {
        let run = scene.parent_pieces(e).expect("a surface edge has a parent");
        let run = run.start.index()..run.end.index();
        if runs.last() != Some(&run) {
            runs.push(run);
        }
    }
    runs
}

/// Fewest elements: one per section, the parts of a run between consecutive cuts.
fn sections(cuts: &[Vec<f64>]) -> usize {
    cuts.iter().map(|c| c.len() - 1).sum()
}

/// [`junctions`] of every run, through one spatial index over all edges so the whole is
/// `O(n log n)` rather than `O(n²)` in the edges.
fn all_junctions(scene: &Scene, runs: &[Range<usize>]) -> Vec<Vec<f64>> {
    let boxes: Vec<Aabb> = scene
        .edges()
        .iter()
        .map(|e| Aabb::of_segment(e.a, e.b).expanded(slack(e.a, e.b)))
        .collect();
    let index = Bvh::new(&boxes);
    runs.par_iter()
        .map_init(Vec::new, |candidates, run| {
            junctions(scene, run, &index, candidates)
        })
        .collect()
}

/// How far beyond a segment's box a point [`junctions`] accepts may lie: the parameter
/// tolerance along it, and rounding of its coordinates (with room to spare; a candidate too
/// many costs one test).
fn slack(a: DVec2, b: DVec2) -> f64 {
    4.0 * JUNCTION_TOLERANCE * (b - a).length()
        + 16.0 * f64::EPSILON * a.abs().max(b.abs()).max_element()
}

/// Parameters within this of an end are the end (the edge meets another at a corner).
const JUNCTION_TOLERANCE: f64 = 1e-9;

/// `0`, the junctions of surface run `run` (see [`MeshEdge::junctions`]) and `1`, ascending.
/// Only edges whose (slightly grown) boxes overlap the run's can meet it; `index` holds the
/// boxes of all edges, `candidates` is scratch.
fn junctions(
    scene: &Scene,
    run: &Range<usize>,
    index: &Bvh,
    candidates: &mut Vec<u32>,
) -> Vec<f64> {
    let all = scene.edges();
    let (a, b) = (all[run.start].a, all[run.end - 1].b);
    let d = b - a;
    let tol = JUNCTION_TOLERANCE;
    let mut cuts = vec![0.0, 1.0];
    candidates.clear();
    index.overlapping(&Aabb::of_segment(a, b).expanded(slack(a, b)), candidates);
    // In file order, as a scan over all edges would meet them.
    candidates.sort_unstable();
    for &i in candidates.iter() {
        let i = i as usize;
        if run.contains(&i) {
            continue;
        }
        let e = &all[i];
        let q = e.b - e.a;
        let den = d.perp_dot(q);
        if den == 0.0 {
            continue; // parallel: collinear neighbours meet at an end, overlaps have no point
        }
        let w = e.a - a;
        let (u, v) = (w.perp_dot(q) / den, w.perp_dot(d) / den);
        if u > tol && u < 1.0 - tol && (-tol..=1.0 + tol).contains(&v) {
            cuts.push(u);
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|x, y| (*x - *y).abs() <= tol);
    cuts
}

/// An edge's element length, ordered by value (`total_cmp`), ties by edge index, so a heap
/// picks exactly what a scan with `max_by` (the last of equals) or `min_by` (the first)
/// would.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ElementLength(f64, usize);

impl Eq for ElementLength {}

impl PartialOrd for ElementLength {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for ElementLength {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// `total` elements over edges of `lengths`: at least one each, otherwise as close to equal
/// element lengths as whole numbers allow (each step gives one more element to the edge whose
/// elements are longest, or takes one from the edge whose elements are shortest). A heap finds
/// that edge, so large scenes cost `O(n log n)`.
fn apportion(lengths: &[f64], total: usize) -> Vec<usize> {
    let sum: f64 = lengths.iter().sum();
    let mut counts: Vec<usize> = lengths
        .iter()
        .map(|&l| ((l / sum * total as f64).floor() as usize).max(1))
        .collect();
    let mut assigned: usize = counts.iter().sum();
    let element = |k: usize, c: &[usize]| ElementLength(lengths[k] / c[k] as f64, k);
    if assigned < total {
        let mut longest: BinaryHeap<ElementLength> =
            (0..lengths.len()).map(|k| element(k, &counts)).collect();
        while assigned < total {
            let ElementLength(_, k) = longest.pop().expect("at least one edge");
            counts[k] += 1;
            assigned += 1;
            longest.push(element(k, &counts));
        }
    }
    if assigned > total {
        let mut shortest: BinaryHeap<Reverse<ElementLength>> = (0..lengths.len())
            .filter(|&k| counts[k] > 1)
            .map(|k| Reverse(element(k, &counts)))
            .collect();
        while assigned > total {
            let Reverse(ElementLength(_, k)) = shortest.pop().expect("total ≥ number of edges");
            counts[k] -= 1;
            assigned -= 1;
            if counts[k] > 1 {
                shortest.push(Reverse(element(k, &counts)));
            }
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, floor_plan, hall, random_room};
    use flatland_testkit::assert_close;
    use rand::RngExt;

    #[test]
    fn elements_tile_the_parameter_range_in_order_and_never_straddle_edges() {
        for name in ["fig3", "box", "maze", "corners"] {
            let kernel = Kernel::new(bundled(name));
            let scene = kernel.scene();
            for n in [Mesh::min_elements(scene), 100, 513] {
                let mesh = Mesh::new(&kernel, n).unwrap();
                assert_eq!(mesh.len(), n, "{name}");
                let els = mesh.elements();
                assert_eq!(els[0].s[0], 0.0);
                assert_eq!(els[n - 1].s[1], 1.0);
                for w in els.windows(2) {
                    assert_eq!(w[0].s[1], w[1].s[0], "{name}: a gap or overlap");
                }
                let total: f64 = els.iter().map(|e| e.length).sum();
                assert_close!(total, scene.total_length(), 1e-12 * total);
                for (i, e) in els.iter().enumerate() {
                    let p = scene.point(e.s_mid);
                    assert_eq!(p.edge, e.edge, "{name}: element {i}");
                    assert!(
                        p.position.distance(e.midpoint) < 1e-12,
                        "{name}: element {i}"
                    );
                    let edge = mesh.edge_of(i);
                    assert!(edge.s[0] <= e.s[0] && e.s[1] <= edge.s[1]);
                    assert_eq!(mesh.element_at(e.s_mid), i);
                }
            }
        }
    }

    #[test]
    fn a_relit_mesh_emits_as_asked_and_keeps_its_scene() {
        let kernel = Kernel::new(bundled("floorplan"));
        let mesh = Mesh::new(&kernel, 400).unwrap();
        let glow: Vec<f64> = (0..mesh.edges().len()).map(|m| (m % 3) as f64).collect();
        let relit = mesh.with_edge_emission(&glow).unwrap();
        assert_eq!(relit.fingerprint(), mesh.fingerprint());
        assert_eq!(relit.len(), mesh.len());
        let (e, before) = (relit.emission(), mesh.emission());
        for i in 0..mesh.len() {
            let edge = relit.edge_of(i);
            let lamps =
                mesh.edge_of(i).reflectance * mesh.direct_irradiance().get(i).unwrap_or(&0.0);
            assert_eq!(
                edge.emission,
                glow[mesh
                    .edges()
                    .iter()
                    .position(|m| m.elements.contains(&i))
                    .unwrap()]
            );
            // The lamps' direct light is kept: only E changed.
            assert_close!(
                e[i] - edge.emission,
                before[i] - mesh.edge_of(i).emission,
                1e-12
            );
            assert_close!(e[i], edge.emission + lamps, 1e-12);
        }
        let short = mesh.with_edge_emission(&glow[1..]).unwrap_err().to_string();
        assert!(short.contains("one per mesh edge"), "{short}");
        let mut negative = glow.clone();
        negative[2] = -1.0;
        let message = mesh.with_edge_emission(&negative).unwrap_err().to_string();
        assert!(message.contains("at least 0"), "{message}");
    }

    #[test]
    fn subdivided_scenes_mesh_whole_edges() {
        let scene = bundled("fig3");
        let coarse = Mesh::new(&Kernel::new(scene.clone()), 60).unwrap();
        let fine = Mesh::new(&Kernel::new(scene.subdivide(7).unwrap()), 60).unwrap();
        assert_eq!(coarse.edges().len(), fine.edges().len());
        for (a, b) in coarse.elements().iter().zip(fine.elements()) {
            assert_close!(a.s_mid, b.s_mid, 1e-15);
            assert!(a.midpoint.distance(b.midpoint) < 1e-12);
        }
        // Fewer elements than (whole) surface edges is an error naming the rule.
        let err = Mesh::new(&Kernel::new(scene), 5).unwrap_err().to_string();
        assert!(
            err.contains("elements") && err.contains("at least one per section"),
            "{err}"
        );
    }

    #[test]
    fn elements_never_straddle_a_junction() {
        // maze: a partition stands on the floor at x = 1.5 and hangs from the ceiling at x = 5.2;
        // corners: a blocker stands on the right floor piece at x = 3.2.
        let maze = Kernel::new(bundled("maze"));
        let mesh = Mesh::new(&maze, 300).unwrap();
        assert_eq!(mesh.edges()[0].junctions, vec![0.25]);
        assert_close!(mesh.edges()[2].junctions[0], 0.8 / 1.5, 1e-15);
        assert_eq!(Mesh::min_elements(maze.scene()), 14 + 2);
        let corners = Kernel::new(bundled("corners"));
        let mesh = Mesh::new(&corners, 100).unwrap();
        assert_close!(mesh.edges()[1].junctions[0], 0.6, 1e-15);
        for m in [&mesh, &Mesh::new(&maze, 77).unwrap()] {
            for edge in m.edges() {
                for &u in &edge.junctions {
                    let x = edge.a + (edge.b - edge.a) * u;
                    assert!(
                        m.elements()[edge.elements.clone()]
                            .iter()
                            .any(|e| e.a.distance(x) < 1e-12),
                        "no element starts at the junction {x}"
                    );
                }
            }
        }
        assert!(Mesh::new(&maze, 15).is_err());
        assert_eq!(Mesh::coarsest(&maze).unwrap().len(), 16);
    }

    #[test]
    fn apportionment_is_exact_and_near_uniform() {
        let lengths = [4.0, 3.0, 1.5, 1.0, 1.5, 3.0];
        for total in 6..200 {
            let c = apportion(&lengths, total);
            assert_eq!(c.iter().sum::<usize>(), total);
            assert!(c.iter().all(|&k| k >= 1));
        }
        assert_eq!(apportion(&lengths, 28), vec![8, 6, 3, 2, 3, 6]);
        // A tiny edge still gets one element.
        let c = apportion(&[1.0, 1e-6, 1.0], 10);
        assert_eq!(c[1], 1);
    }

    /// The scan over all edges that [`junctions`] replaced: the definition it must match.
    fn junctions_by_scan(scene: &Scene, run: &Range<usize>) -> Vec<f64> {
        let all = scene.edges();
        let (a, b) = (all[run.start].a, all[run.end - 1].b);
        let d = b - a;
        let tol = JUNCTION_TOLERANCE;
        let mut cuts = vec![0.0, 1.0];
        for (i, e) in all.iter().enumerate() {
            if run.contains(&i) {
                continue;
            }
            let q = e.b - e.a;
            let den = d.perp_dot(q);
            if den == 0.0 {
                continue;
            }
            let w = e.a - a;
            let (u, v) = (w.perp_dot(q) / den, w.perp_dot(d) / den);
            if u > tol && u < 1.0 - tol && (-tol..=1.0 + tol).contains(&v) {
                cuts.push(u);
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|x, y| (*x - *y).abs() <= tol);
        cuts
    }

    #[test]
    fn junctions_through_the_index_are_those_of_a_scan() {
        let scenes = [
            bundled("maze"),
            bundled("corners"),
            bundled("fig3").subdivide(3).unwrap(),
            floor_plan(600),
            hall(600),
            random_room(40, 3),
        ];
        let mut found = Vec::new();
        for scene in scenes {
            let runs = surface_runs(&scene);
            let indexed = all_junctions(&scene, &runs);
            for (run, cuts) in runs.iter().zip(&indexed) {
                assert_eq!(cuts, &junctions_by_scan(&scene, run), "run {run:?}");
            }
            found.push(indexed.iter().map(|c| c.len() - 2).sum::<usize>());
        }
        // maze, corners and the random room have T-junctions and crossings; fig3 has none,
        // and the generated scenes leave out every covered part of a face, so where walls
        // abut they meet at corners.
        assert!(found[0] > 0 && found[1] > 0 && found[5] > 0, "{found:?}");
        assert_eq!(found[2..5], [0, 0, 0]);
    }

    /// The scan [`apportion`] replaced: one step at a time over all edges.
    fn apportion_by_scan(lengths: &[f64], total: usize) -> Vec<usize> {
        let sum: f64 = lengths.iter().sum();
        let mut counts: Vec<usize> = lengths
            .iter()
            .map(|&l| ((l / sum * total as f64).floor() as usize).max(1))
            .collect();
        let mut assigned: usize = counts.iter().sum();
        let element = |k: usize, c: &[usize]| lengths[k] / c[k] as f64;
        while assigned < total {
            let k = (0..lengths.len())
                .max_by(|&p, &q| element(p, &counts).total_cmp(&element(q, &counts)))
                .unwrap();
            counts[k] += 1;
            assigned += 1;
        }
        while assigned > total {
            let k = (0..lengths.len())
                .filter(|&k| counts[k] > 1)
                .min_by(|&p, &q| element(p, &counts).total_cmp(&element(q, &counts)))
                .unwrap();
            counts[k] -= 1;
            assigned -= 1;
        }
        counts
    }

    #[test]
    fn apportionment_by_heap_is_the_scan() {
        let mut rng = flatland_testkit::rng(17);
        for case in 0..300 {
            let n = 1 + case % 40;
            // Equal lengths in some cases: ties must go the same way.
            let lengths: Vec<f64> = (0..n)
                .map(|_| {
                    if case % 3 == 0 {
                        [1.0, 2.0, 0.5][rng.random_range(0..3)]
                    } else {
                        rng.random_range(0.001..5.0)
                    }
                })
                .collect();
            let total = n + rng.random_range(0..200);
            assert_eq!(
                apportion(&lengths, total),
                apportion_by_scan(&lengths, total)
            );
        }
    }

    #[test]
    fn large_scenes_mesh_past_the_dense_limit() {
        let kernel = Kernel::new(floor_plan(5000));
        let fewest = Mesh::min_elements(kernel.scene());
        assert!(fewest > MAX_ELEMENTS / 2, "{fewest}");
        let mesh = Mesh::new(&kernel, 3 * fewest).unwrap();
        assert_eq!(mesh.len(), 3 * fewest);
        let err = Mesh::new(&kernel, MAX_MESH_ELEMENTS + 1)
            .unwrap_err()
            .to_string();
        assert!(err.contains("at most 16777216"), "{err}");
    }

    /// Every element of `coarse` is tiled, in order, by `pieces[i]` consecutive elements of
    /// `fine`, each where the scene's parameterization puts it and on the piece it names.
    fn assert_nested(kernel: &Kernel, coarse: &Mesh, fine: &Mesh, pieces: &[usize]) {
        let mut j = 0;
        for (i, e) in coarse.elements().iter().enumerate() {
            let parts = &fine.elements()[j..j + pieces[i]];
            assert_eq!(parts[0].s[0], e.s[0], "element {i}");
            assert_eq!(parts[parts.len() - 1].s[1], e.s[1], "element {i}");
            for w in parts.windows(2) {
                assert_eq!(w[0].s[1], w[1].s[0], "element {i}");
                assert!(w[0].b.distance(w[1].a) < 1e-15, "element {i}");
            }
            let length: f64 = parts.iter().map(|p| p.length).sum();
            assert_close!(length, e.length, 1e-12 * e.length);
            for p in parts {
                assert_eq!(p.mesh_edge, e.mesh_edge);
                let at = kernel.scene().point(p.s_mid);
                assert_eq!(at.edge, p.edge, "element {i}");
                assert!(at.position.distance(p.midpoint) < 1e-12, "element {i}");
                assert!(p.s[0] < p.s_mid && p.s_mid < p.s[1]);
            }
            j += pieces[i];
        }
        assert_eq!(j, fine.len());
        assert_eq!(fine.edges().len(), coarse.edges().len());
        assert_close!(fine.total_length(), coarse.total_length(), 0.0);
    }

    #[test]
    fn split_meshes_nest_in_their_parent() {
        let scenes = [
            bundled("maze"),
            bundled("corners"),
            bundled("fig3").subdivide(3).unwrap(),
        ];
        for scene in scenes {
            let kernel = Kernel::new(scene);
            let mesh = Mesh::new(&kernel, 120).unwrap();
            let same = mesh.split_unlit(&[1; 120]).unwrap();
            assert_eq!(same.elements(), mesh.elements());
            let parts: Vec<usize> = (0..120).map(|i| 1 + i % 4).collect();
            let split = mesh.split_unlit(&parts).unwrap();
            assert_nested(&kernel, &mesh, &split, &parts);
            // Junctions stay element boundaries, and splitting again nests too.
            let again = split.split_unlit(&vec![2; split.len()]).unwrap();
            assert_nested(&kernel, &split, &again, &vec![2; split.len()]);
        }
        let kernel = Kernel::new(bundled("maze"));
        let mesh = Mesh::new(&kernel, 50).unwrap();
        for bad in [vec![1; 49], vec![0; 50]] {
            let err = mesh.split_unlit(&bad).unwrap_err().to_string();
            assert!(err.contains("one count ≥ 1 per element"), "{err}");
        }
    }

    #[test]
    fn cut_meshes_put_their_midpoints_where_asked() {
        let kernel = Kernel::new(bundled("corners"));
        let mesh = Mesh::new(&kernel, 80).unwrap();
        let (cuts, mids) = ([0.2, 0.7], [0.1, 0.45, 0.85]);
        let cut = mesh.cut_unlit(&cuts, &mids).unwrap();
        assert_nested(&kernel, &mesh, &cut, &[3; 80]);
        for (i, e) in mesh.elements().iter().enumerate() {
            for (k, m) in mids.iter().enumerate() {
                let at = e.s[0] + (e.s[1] - e.s[0]) * m;
                assert_close!(cut.elements()[3 * i + k].s_mid, at, 1e-15);
            }
        }
        for (cuts, mids) in [
            (vec![0.7, 0.2], vec![0.1, 0.45, 0.85]),
            (vec![0.2, 0.7], vec![0.3, 0.45, 0.85]),
            (vec![0.2, 0.7], vec![0.1, 0.45]),
            (vec![0.0, 0.7], vec![0.0, 0.45, 0.85]),
        ] {
            let err = mesh.cut_unlit(&cuts, &mids).unwrap_err().to_string();
            assert!(err.contains("ascending fractions in (0, 1)"), "{err}");
        }
    }

    #[test]
    fn default_element_count_follows_the_scene() {
        assert_eq!(Mesh::default_elements(&bundled("fig3")), DEFAULT_ELEMENTS);
        let many = bundled("box").subdivide(1).unwrap();
        assert!(Mesh::default_elements(&many) >= MIN_PER_EDGE * 6);
    }
}
