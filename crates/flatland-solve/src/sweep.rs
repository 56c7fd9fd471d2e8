//! The exact operator without pairs of edges: per collocation point, what it sees, by an
//! angular sweep over a hierarchy of every edge of the scene.
//!
//! Seen from a receiving point `y` (one side of its edge, normal `n`), every direction of the
//! half-plane ends on the nearest segment, surface or blocker. The *envelope* records that
//! nearest segment per direction, as pieces of the range of `σ = sin φ` (φ the angle from `n`):
//! a surface facing `y` that owns the piece `[σ₁, σ₂]` receives the closed-form transfer
//! `(σ₂ − σ₁) / 2` of that piece, split among its elements — the same integral of `G·V` as the
//! dense operator's visible intervals, with no pair table and no ray.
//!
//! The envelope is built by walking a bounding-volume hierarchy of all edges nearest first,
//! skipping (culling) any box whose directions are all covered by pieces nearer than the box:
//! nothing inside it can be seen. Each row costs about `log n` plus what is seen, so the whole
//! operator is `O(N (log n + visible))` in time and `O(N · visible)` in memory, where the dense
//! one is `O(n²)` pair classifications and `N²` numbers.
//!
//! A point light is seen the same way, by two half-plane views from where it stands
//! (`light.rs`): what it lights, exactly, with the hierarchy built once for every light.

mod envelope;
mod light;
mod probe;
mod row;
mod view;

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use flatland_geom::{EdgeId, Kernel, Role, Scene};

use crate::bvh::{Aabb, Bvh, Contents};
use crate::exact::check_scene;
use crate::{Mesh, SolveError, SparseOperator, Stop};

pub(crate) use light::{LitPiece, element_angles, holds};
pub use probe::{ProbeBuffers, SeenSpan, Sweep};
pub(crate) use row::{transfers, transfers_to_both};

use envelope::Envelope;
use view::{Segment, View};

/// Every edge of a scene as the sweep sees it: whole (parent) edges in the mesh's unit frame,
/// their hierarchy, and which mesh edge each surface is.
#[derive(Clone, Debug)]
pub(crate) struct SweepScene {
    segments: Vec<Segment>,
    bvh: Bvh,
    /// Per segment: the mesh edge it is, `None` for a blocker.
    mesh_edge: Vec<Option<u32>>,
    /// Per mesh edge: its segment.
    segment_of: Vec<u32>,
}

impl SweepScene {
    /// The sweep's view of `scene`, meshed by `mesh`.
    pub fn new(scene: &Scene, mesh: &Mesh) -> SweepScene {
        let edges = scene.edges();
        let mut segments = Vec::new();
        let mut first_piece = Vec::new();
        for e in 0..edges.len() {
            let pieces = scene
                .parent_pieces(EdgeId::new(e))
                .expect("an edge of the scene");
            if pieces.start.index() == e {
                segments.push(Segment {
                    a: mesh.to_local(edges[e].a),
                    b: mesh.to_local(edges[pieces.end.index() - 1].b),
                    front: edges[e].role == Role::Surface,
                });
                first_piece.push(e);
            }
        }
        let mut mesh_edge = vec![None; segments.len()];
        let segment_of: Vec<u32> = mesh
            .edges()
            .iter()
            .enumerate()
            .map(|(k, edge)| {
                let id = first_piece
                    .binary_search(&edge.pieces.start)
                    .expect("a mesh edge is a parent edge");
                mesh_edge[id] = Some(k as u32);
                id as u32
            })
            .collect();
        let boxes: Vec<Aabb> = segments
            .iter()
            .map(|s| Aabb::of_segment(s.a, s.b))
            .collect();
        SweepScene {
            bvh: Bvh::new(&boxes),
            segments,
            mesh_edge,
            segment_of,
        }
    }

    /// Builds in `buffers.envelope` what `view` sees, skipping segment `skip` (the receiver's
    /// own edge, which it lies on). With `cull` false every box is opened: the same envelope
    /// (culling only skips what cannot be seen), the slow way, for tests.
    fn envelope(&self, view: &View, skip: u32, cull: bool, buffers: &mut SweepBuffers) {
        let (envelope, pending) = (&mut buffers.envelope, &mut buffers.pending);
        envelope.clear();
        pending.clear();
        if let Some(root) = self.bvh.root() {
            pending.push(Pending::new(
                root,
                self.bvh.node(root).bounds.distance_to(view.y),
            ));
        }
        while let Some(Pending { distance, node }) = pending.pop() {
            let node = self.bvh.node(node);
            if cull {
                match view.box_span(&node.bounds) {
                    Some(span) if !envelope.hides(span, distance) => {}
                    _ => continue,
                }
            }
            match node.contents {
                Contents::Leaf { first, count } => {
                    for &id in self.bvh.items(first, count) {
                        if id == skip {
                            continue;
                        }
                        if let Some(span) = view.span(&self.segments[id as usize]) {
                            envelope.insert(view, &self.segments, id, span);
                        }
                    }
                }
                Contents::Inner { left, right } => {
                    for child in [left, right] {
                        let bounds = self.bvh.node(child).bounds;
                        if !(cull && view.behind(&bounds)) {
                            pending.push(Pending::new(child, bounds.distance_to(view.y)));
                        }
                    }
                }
            }
        }
    }
}

/// A box waiting to be opened, nearest first (ties by node index, so the walk is the same on
/// every machine).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pending {
    distance: f64,
    node: u32,
}

impl Pending {
    fn new(node: u32, distance: f64) -> Pending {
        Pending { distance, node }
    }
}

impl Eq for Pending {}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Pending {
    /// Reversed: the heap pops the nearest.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .distance
            .total_cmp(&self.distance)
            .then(other.node.cmp(&self.node))
    }
}

/// What one thread reuses from row to row, so a row allocates nothing once warm.
#[derive(Debug, Default)]
pub(crate) struct SweepBuffers {
    envelope: Envelope,
    pending: BinaryHeap<Pending>,
    /// `(element, transfer)` of the row being built.
    transfers: Vec<(u32, f64)>,
}

/// The exact collocation operator of `kernel` on `mesh` by the visibility sweep:
/// `K_ij = ρ_i ∫_{element j} G(x, y_i) V(x, y_i) dl_x`, the numbers of
/// [`exact_operator`](crate::exact_operator) up to rounding, stored sparse (only what `y_i`
/// sees). No pair of edges is classified, so it scales to 10⁵ edges. Rows in parallel; `stop`
/// is polled per row. Errors: a mesh of another scene, or more non-zero numbers than
/// [`MAX_NONZEROS`](crate::MAX_NONZEROS).
pub fn sweep_operator(
    kernel: &Kernel,
    mesh: &Mesh,
    stop: &Stop,
) -> Result<SparseOperator, SolveError> {
    check_scene(kernel, mesh)?;
    let scene = SweepScene::new(kernel.scene(), mesh);
    sweep_operator_with(&scene, mesh, true, stop)
}

/// [`sweep_operator`] on a prepared scene, culling or not.
pub(crate) fn sweep_operator_with(
    scene: &SweepScene,
    mesh: &Mesh,
    cull: bool,
    stop: &Stop,
) -> Result<SparseOperator, SolveError> {
    SparseOperator::assemble(
        mesh.len(),
        SweepBuffers::default,
        |i, buffers, out| {
            let rho = mesh.edge_of(i).reflectance;
            if rho == 0.0 {
                return;
            }
            let k = mesh.elements()[i].mesh_edge;
            let row = transfers(scene, mesh, k, mesh.local(i)[2], cull, buffers);
            out.extend(row.iter().map(|&(j, t)| (j, rho * t)));
        },
        stop,
    )
}

/// The operators of a solve and of its Gauss refinement, from one view per collocation point
/// of the refinement: the refinement's rows (`fine`), the coarse rows at the coarse
/// midpoints (`coarse`, the refinement's middle points), and the coarse transfers to the two
/// outer Gauss points of each coarse element (`gather`, rows `2i` and `2i + 1`; ρ included),
/// which give the coarse solve's final gather there.
#[derive(Clone, Debug)]
pub(crate) struct GaussOperators {
    pub fine: SparseOperator,
    pub coarse: SparseOperator,
    pub gather: SparseOperator,
}

/// One coarse element's rows: for each of its three Gauss points, the row to the fine mesh
/// and the row to the coarse mesh (ρ included).
#[derive(Default)]
struct GaussRows {
    fine: [Vec<(u32, f64)>; 3],
    coarse: [Vec<(u32, f64)>; 3],
}

/// Which of the kept rows is row `r` of an operator.
type RowOf = fn(&[GaussRows], usize) -> &[(u32, f64)];

/// [`GaussOperators`] of `coarse` and `fine` (its Gauss refinement: element `3i + k` is the
/// `k`-th piece of coarse element `i`), elements in parallel. Three views per coarse
/// element, where separate assemblies and gathers would take six.
pub(crate) fn gauss_operators(
    scene: &SweepScene,
    coarse: &Mesh,
    fine: &Mesh,
    stop: &Stop,
) -> Result<GaussOperators, SolveError> {
    use rayon::prelude::*;
    debug_assert_eq!(fine.len(), 3 * coarse.len());
    let rows: Vec<GaussRows> = (0..coarse.len())
        .into_par_iter()
        .with_min_len(4)
        .map_init(SweepBuffers::default, |buffers, i| {
            if stop() {
                return Err(SolveError::Interrupted);
            }
            let mut rows = GaussRows::default();
            let rho = coarse.edge_of(i).reflectance;
            if rho == 0.0 {
                return Ok(rows);
            }
            let k = coarse.elements()[i].mesh_edge;
            for p in 0..3 {
                let y = fine.local(3 * i + p)[2];
                let to_fine =
                    transfers_to_both(scene, fine, coarse, k, y, buffers, &mut rows.coarse[p]);
                rows.fine[p] = to_fine.iter().map(|&(j, t)| (j, rho * t)).collect();
                for entry in &mut rows.coarse[p] {
                    entry.1 *= rho;
                }
            }
            Ok(rows)
        })
        .collect::<Result<_, SolveError>>()?;
    let copy = |n: usize, pick: RowOf| {
        SparseOperator::assemble(
            n,
            || (),
            |r, _, out| out.extend_from_slice(pick(&rows, r)),
            stop,
        )
    };
    Ok(GaussOperators {
        fine: copy(fine.len(), |rows, r| &rows[r / 3].fine[r % 3])?,
        coarse: copy(coarse.len(), |rows, r| &rows[r].coarse[1])?,
        gather: copy(2 * coarse.len(), |rows, r| &rows[r / 2].coarse[2 * (r % 2)])?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, floor_plan, hall, l_room, random_room, thin_wall_plan};
    use crate::{
        DenseOperator, SolveParams, TransferOperator, exact_operator, never, solve_operator,
    };
    use flatland_geom::Edge;
    use proptest::prelude::*;

    fn both(scene: Scene, elements: usize) -> (Mesh, DenseOperator, SparseOperator) {
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, elements).unwrap();
        let dense = exact_operator(&kernel, &mesh, &never).unwrap();
        let sparse = sweep_operator(&kernel, &mesh, &never).unwrap();
        (mesh, dense, sparse)
    }

    /// Every entry within `1e-9` relative, or `1e-14` absolute: both methods take an entry as
    /// a difference of two sines of order one, so a small entry carries their rounding (a
    /// sliver grazing the horizon next to a junction is `1e-15` in one and 0 in the other).
    fn assert_equal_entries(name: &str, dense: &DenseOperator, sparse: &SparseOperator) {
        let n = dense.len();
        let mut compared = 0;
        for i in 0..n {
            for j in 0..n {
                let (d, s) = (dense.get(i, j), sparse.get(i, j));
                let scale = d.abs().max(s.abs());
                assert!(
                    (d - s).abs() <= 1e-9 * scale + 1e-14,
                    "{name}: K[{i}][{j}] dense {d:e} vs sweep {s:e}"
                );
                compared += usize::from(scale > 0.0);
            }
        }
        assert!(compared > n, "{name}: only {compared} non-zero entries");
    }

    #[test]
    fn the_sweep_is_the_dense_operator_entry_by_entry() {
        for name in ["fig3", "box", "maze", "corners"] {
            let (_, dense, sparse) = both(bundled(name), 150);
            assert_equal_entries(name, &dense, &sparse);
        }
        // Pieces of a subdivided edge are one edge, and the L room's reflex corner occludes.
        let (_, dense, sparse) = both(bundled("fig3").subdivide(4).unwrap(), 90);
        assert_equal_entries("fig3 ×4", &dense, &sparse);
        let (_, dense, sparse) = both(l_room(0.6), 120);
        assert_equal_entries("L room", &dense, &sparse);
    }

    #[test]
    fn the_sweep_is_the_dense_operator_on_generated_scenes() {
        for (name, scene) in [("floor plan", floor_plan(200)), ("hall", hall(200))] {
            let edges = scene.edges().len();
            assert!((150..=260).contains(&edges), "{name}: {edges} edges");
            let (_, dense, sparse) = both(scene, 2 * edges);
            assert_equal_entries(name, &dense, &sparse);
            assert!(
                sparse.nonzeros() < dense.len() * dense.len() / 4,
                "{name}: hardly sparse"
            );
        }
        for seed in 0..4 {
            let (_, dense, sparse) = both(random_room(12, seed), 160);
            assert_equal_entries(&format!("random room {seed}"), &dense, &sparse);
        }
        // Thin walls: faces back to back, each seen only from its own side.
        let (_, dense, sparse) = both(thin_wall_plan(3, 2, 5), 240);
        assert_equal_entries("thin walls", &dense, &sparse);
    }

    #[test]
    fn one_view_per_gauss_point_gives_both_meshes_operators() {
        // The refinement's rows and the coarse rows are the sweep operators of the two meshes;
        // the gather rows are the coarse transfers to the outer Gauss points.
        for scene in [floor_plan(200), bundled("maze"), thin_wall_plan(2, 2, 3)] {
            let kernel = Kernel::new(scene);
            let coarse = Mesh::new(&kernel, 240).unwrap();
            let fine = crate::gauss_refinement(&kernel, &coarse).unwrap();
            let ops = gauss_operators(
                &SweepScene::new(kernel.scene(), &coarse),
                &coarse,
                &fine,
                &never,
            )
            .unwrap();
            // Entry by entry (the coarse midpoint is the refinement's middle one, equal to
            // rounding: a sliver grazing the horizon may be 1e-15 in one and absent in the other).
            let close = |a: &SparseOperator, b: &SparseOperator| {
                for i in 0..a.len() {
                    for &j in a.row(i).0.iter().chain(b.row(i).0) {
                        let (x, y) = (a.get(i, j as usize), b.get(i, j as usize));
                        let scale = x.abs().max(y.abs());
                        assert!(
                            (x - y).abs() <= 1e-9 * scale + 1e-14,
                            "K[{i}][{j}]: {x} vs {y}"
                        );
                    }
                }
            };
            close(&ops.fine, &sweep_operator(&kernel, &fine, &never).unwrap());
            close(
                &ops.coarse,
                &sweep_operator(&kernel, &coarse, &never).unwrap(),
            );
            let scene = SweepScene::new(kernel.scene(), &coarse);
            let mut buffers = SweepBuffers::default();
            for r in 0..2 * coarse.len() {
                let (i, p) = (r / 2, 2 * (r % 2));
                let rho = coarse.edge_of(i).reflectance;
                let y = fine.local(3 * i + p)[2];
                let row = transfers(
                    &scene,
                    &coarse,
                    coarse.elements()[i].mesh_edge,
                    y,
                    true,
                    &mut buffers,
                );
                let expected: Vec<(u32, f64)> = if rho == 0.0 {
                    Vec::new()
                } else {
                    row.iter().map(|&(j, t)| (j, rho * t)).collect()
                };
                let (columns, values) = ops.gather.row(r);
                let got: Vec<(u32, f64)> = columns
                    .iter()
                    .copied()
                    .zip(values.iter().copied())
                    .collect();
                assert_eq!(got, expected, "gather row {r}");
            }
        }
    }

    #[test]
    fn rows_sum_to_rho_in_closed_scenes() {
        // Every direction from a point of a closed scene without blockers ends on a surface
        // facing it: Σ_j K_ij = ρ_i, to rounding, however much is hidden.
        for (name, scene) in [
            ("box", bundled("box")),
            ("L room", l_room(0.6)),
            ("floor plan", floor_plan(1000)),
            ("hall", hall(1000)),
            ("thin walls", thin_wall_plan(5, 4, 1)),
        ] {
            let kernel = Kernel::new(scene);
            let elements = 3 * Mesh::min_elements(kernel.scene());
            let mesh = Mesh::new(&kernel, elements).unwrap();
            let op = sweep_operator(&kernel, &mesh, &never).unwrap();
            for i in 0..mesh.len() {
                let sum: f64 = op.row(i).1.iter().sum();
                let rho = mesh.edge_of(i).reflectance;
                assert!(
                    (sum - rho).abs() < 1e-12,
                    "{name}, row {i}: {sum} vs ρ = {rho}"
                );
            }
        }
    }

    /// The sweep's operator with and without culling, entry by entry.
    fn culling_changes_nothing(scene: Scene, elements: usize) {
        let kernel = Kernel::new(scene);
        let elements = elements.max(Mesh::min_elements(kernel.scene()));
        let mesh = Mesh::new(&kernel, elements).unwrap();
        let sweep = SweepScene::new(kernel.scene(), &mesh);
        let culled = sweep_operator_with(&sweep, &mesh, true, &never).unwrap();
        let all = sweep_operator_with(&sweep, &mesh, false, &never).unwrap();
        for i in 0..mesh.len() {
            for j in 0..mesh.len() {
                let (c, a) = (culled.get(i, j), all.get(i, j));
                assert!((c - a).abs() <= 1e-15, "K[{i}][{j}]: culled {c} vs all {a}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        #[test]
        fn culling_on_equals_culling_off(inside in 1usize..40, seed in 0u64..1_000_000, per in 1usize..4) {
            let scene = random_room(inside, seed);
            let elements = per * scene.edges().len();
            culling_changes_nothing(scene, elements);
        }
    }

    #[test]
    fn culling_changes_nothing_on_generated_scenes() {
        culling_changes_nothing(floor_plan(300), 900);
        culling_changes_nothing(hall(300), 900);
    }

    /// Emitted and absorbed power of a sweep solve (see `solve::tests::power_balance`).
    fn power_balance(scene: Scene, elements: usize) -> (f64, f64) {
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, elements).unwrap();
        let op = sweep_operator(&kernel, &mesh, &never).unwrap();
        crate::test_support::power_balance(&op, &mesh)
    }

    #[test]
    fn emitted_power_equals_absorbed_power_in_generated_scenes() {
        // Closed scenes without blockers: what the surfaces absorb is what they emit, to the
        // discretisation (collocation conserves it only in the limit).
        for (name, scene) in [("floor plan", floor_plan(300)), ("hall", hall(300))] {
            let elements = 8 * Mesh::min_elements(&scene);
            let (emitted, absorbed) = power_balance(scene, elements);
            assert!(
                (emitted - absorbed).abs() <= 5e-3 * emitted,
                "{name}: emitted {emitted} vs absorbed {absorbed}"
            );
        }
    }

    #[test]
    fn a_closed_uniform_scene_gives_e_over_one_minus_rho() {
        // B = E + ρ ∫ G V B and ∫ G V = 1 from every point of a closed scene: B = E / (1 − ρ),
        // in a floor plan full of walls and furniture as in an empty box.
        let (rho, e) = (0.7, 0.4);
        let uniform: Vec<Edge> = floor_plan(400)
            .edges()
            .iter()
            .map(|edge| Edge {
                reflectance: rho,
                emission: e,
                ..*edge
            })
            .collect();
        let kernel = Kernel::new(Scene::new(uniform).unwrap());
        let mesh = Mesh::new(&kernel, 2 * Mesh::min_elements(kernel.scene())).unwrap();
        let op = sweep_operator(&kernel, &mesh, &never).unwrap();
        let solution = solve_operator(&op, &mesh, &SolveParams::default(), &never).unwrap();
        let expected = e / (1.0 - rho);
        for (i, b) in solution.radiosity.iter().enumerate() {
            assert!(
                (b - expected).abs() <= 1e-8 * expected,
                "element {i}: B = {b} vs {expected}"
            );
        }
    }

    #[test]
    fn the_sweep_refuses_another_scenes_mesh_and_stops() {
        let kernel = Kernel::new(bundled("fig3"));
        let other = Mesh::new(&Kernel::new(bundled("box")), 40).unwrap();
        assert!(matches!(
            sweep_operator(&kernel, &other, &never),
            Err(SolveError::SceneMismatch { .. })
        ));
        let mesh = Mesh::new(&kernel, 200).unwrap();
        assert!(matches!(
            sweep_operator(&kernel, &mesh, &|| true),
            Err(SolveError::Interrupted)
        ));
    }
}
