//! The exact operator: closed-form transfer where the geometry proves a pair of edges clear,
//! the exact visible part where occluders may intervene, nothing where they cannot interact.
//!
//! Pairs of surface edges are classified once per mesh by the exact kernel's cached shaft test
//! ([`Kernel::pair_class`], no rays), which decides how light passes between them
//! ([`PairTransfer`]): not at all (same edge, never facing, or every ray blocked), *clear*, or
//! *occluded by these candidates* ([`Kernel::pair_occluders`]). Only the last kind needs the
//! visible-interval computation of [`point_to_segment_visible`], and only against its
//! candidates.

use flatland_geom::{DVec2, EdgeId, Kernel, PairClass};
use rayon::prelude::*;

use crate::transfer::{Receiver, Sender, point_to_segment, point_to_segment_visible};
use crate::{DenseOperator, Mesh, SolveError, Stop};

/// How light passes between two surface edges of a mesh: what their [`PairClass`] means for
/// the closed form, with the candidate occluders as segments.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PairTransfer {
    /// No transfer at all.
    Zero,
    /// Nothing can occlude: the closed form as it is.
    Clear,
    /// These segments (frame coordinates) may occlude.
    Occluded(Vec<[DVec2; 2]>),
}

/// [`PairTransfer`] for every ordered pair of mesh edges (symmetric).
#[derive(Clone, Debug)]
pub(crate) struct PairTable {
    n: usize,
    classes: Vec<PairTransfer>,
}

impl PairTable {
    /// Classifies every pair of `mesh`'s edges with `kernel`'s shaft test.
    pub(crate) fn new(kernel: &Kernel, mesh: &Mesh) -> Result<PairTable, SolveError> {
        check_scene(kernel, mesh)?;
        let scene = kernel.scene();
        let edges = mesh.edges();
        let n = edges.len();
        let segment = |edge: EdgeId| -> Option<[DVec2; 2]> {
            let pieces = scene.parent_pieces(edge)?;
            Some([
                mesh.to_local(scene.edge(pieces.start).a),
                mesh.to_local(scene.edges()[pieces.end.index() - 1].b),
            ])
        };
        let rank = |x: usize| {
            let edge = EdgeId::new(edges[x].pieces.start);
            scene
                .surface_rank(edge)
                .expect("a mesh edge is a surface edge")
        };
        let classify = |x: usize, y: usize| -> PairTransfer {
            let (a, b) = (rank(x), rank(y));
            match kernel.pair_class(a, b) {
                PairClass::Visible => PairTransfer::Clear,
                PairClass::Varies => PairTransfer::Occluded(
                    kernel
                        .pair_occluders(a, b)
                        .into_iter()
                        .filter_map(segment)
                        .collect(),
                ),
                PairClass::Zero | PairClass::Hidden => PairTransfer::Zero,
            }
        };
        let upper: Vec<(usize, usize, PairTransfer)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|x| (x..n).map(move |y| (x, y)))
            .map(|(x, y)| {
                (
                    x,
                    y,
                    if x == y {
                        PairTransfer::Zero
                    } else {
                        classify(x, y)
                    },
                )
            })
            .collect();
        let mut classes = vec![PairTransfer::Zero; n * n];
        for (x, y, class) in upper {
            classes[y * n + x] = class.clone();
            classes[x * n + y] = class;
        }
        Ok(PairTable { n, classes })
    }

    /// How light passes from mesh edge `sender` to mesh edge `receiver`.
    pub(crate) fn get(&self, sender: usize, receiver: usize) -> &PairTransfer {
        &self.classes[sender * self.n + receiver]
    }
}

/// How the exact operator of a scene is assembled: from the table of pairs of edges
/// ([`exact_operator`], dense) on small scenes, by the visibility sweep
/// ([`sweep_operator`](crate::sweep_operator), sparse) from [`SWEEP_FROM_EDGES`] whole edges
/// on. [`Representation::operator`](crate::Representation::operator) of the exact kernel and
/// [`ExactReference`](crate::ExactReference) follow it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExactMethod {
    /// The pair table and `N²` numbers: at most [`MAX_ELEMENTS`](crate::MAX_ELEMENTS)
    /// elements.
    Dense,
    /// The visibility sweep, rows of what each point sees.
    Sweep,
}

/// Whole edges (surfaces and blockers, the pieces of a subdivided edge counted once) from which
/// the exact operator is assembled by the sweep. Measured at 512 and 2048 elements, the pair
/// table is faster only on the 6-edge box (1.4 against 2.2 ms at 512); the sweep is 2.5 to 12
/// times faster on every other bundled or generated scene from 7 edges up, 15 to 60 times from
/// 150 edges: speed alone would sweep from 7 edges. The dense path is kept below 32 edges,
/// above every bundled scene (at most 20), so that every figure made with them stays bit for
/// bit what it was; there both take well under a second at 2048 elements.
pub const SWEEP_FROM_EDGES: usize = 32;

impl ExactMethod {
    /// The method for `kernel`'s scene.
    #[must_use]
    pub fn of(kernel: &Kernel) -> ExactMethod {
        let scene = kernel.scene();
        let whole = (0..scene.edges().len())
            .map(EdgeId::new)
            .filter(|&e| scene.parent_pieces(e).is_some_and(|p| p.start == e))
            .count();
        if whole < SWEEP_FROM_EDGES {
            ExactMethod::Dense
        } else {
            ExactMethod::Sweep
        }
    }

    /// Refuses an element count the method cannot hold: a dense operator has at most
    /// [`MAX_ELEMENTS`](crate::MAX_ELEMENTS) (the sweep's limit, on the numbers it holds,
    /// shows only while it assembles).
    pub fn check(self, elements: usize) -> Result<(), SolveError> {
        match self {
            ExactMethod::Dense => crate::operator::check_dense(elements),
            ExactMethod::Sweep => Ok(()),
        }
    }
}

/// Refuses a mesh made for another scene.
pub fn check_scene(kernel: &Kernel, mesh: &Mesh) -> Result<(), SolveError> {
    let actual = kernel.scene().fingerprint();
    if actual == mesh.fingerprint() {
        Ok(())
    } else {
        Err(SolveError::SceneMismatch {
            representation: format!("{actual:016x}"),
            mesh: format!("{:016x}", mesh.fingerprint()),
        })
    }
}

/// The receiver at frame point `y` on mesh edge `edge`.
pub fn receiver(mesh: &Mesh, edge: usize, y: DVec2) -> Receiver {
    let e = &mesh.edges()[edge];
    Receiver {
        position: y,
        normal: e.normal,
    }
}

/// Element `j` as a sender, in frame coordinates.
pub fn sender(mesh: &Mesh, j: usize) -> Sender {
    let e = mesh.edge_of(j);
    let [a, b, _] = mesh.local(j);
    Sender {
        a,
        b,
        normal: e.normal,
    }
}

/// `out[j] = ∫_{element j} G V dl_x` at the frame point `y` of mesh edge `receiver_edge`, for
/// every element `j` of `mesh`; occluded pairs go through `occluded`.
pub(crate) fn transfer_row(
    mesh: &Mesh,
    table: &PairTable,
    receiver_edge: usize,
    y: DVec2,
    out: &mut [f64],
    occluded: &impl Fn(&Receiver, usize, &Sender, &[[DVec2; 2]], &mut Vec<[f64; 2]>) -> f64,
) {
    let r = receiver(mesh, receiver_edge, y);
    let mut scratch = Vec::new();
    for (k, edge) in mesh.edges().iter().enumerate() {
        let range = edge.elements.clone();
        match table.get(k, receiver_edge) {
            PairTransfer::Zero => out[range].fill(0.0),
            PairTransfer::Clear => {
                for j in range {
                    out[j] = point_to_segment(&r, &sender(mesh, j));
                }
            }
            PairTransfer::Occluded(occluders) => {
                for j in range {
                    out[j] = occluded(&r, j, &sender(mesh, j), occluders, &mut scratch);
                }
            }
        }
    }
}

/// The exact collocation operator of `kernel` on `mesh`:
/// `K_ij = ρ_i ∫_{element j} G(x, y_i) V(x, y_i) dl_x`, `y_i` element i's midpoint, with the
/// closed form and exact visible intervals (no rays, no quadrature).
pub fn exact_operator(
    kernel: &Kernel,
    mesh: &Mesh,
    stop: &Stop,
) -> Result<DenseOperator, SolveError> {
    let table = PairTable::new(kernel, mesh)?;
    exact_operator_with(&table, mesh, stop)
}

pub(crate) fn exact_operator_with(
    table: &PairTable,
    mesh: &Mesh,
    stop: &Stop,
) -> Result<DenseOperator, SolveError> {
    DenseOperator::assemble(
        mesh.len(),
        |i, row| {
            let rho = mesh.edge_of(i).reflectance;
            if rho == 0.0 {
                row.fill(0.0);
                return;
            }
            transfer_row(
                mesh,
                table,
                mesh.elements()[i].mesh_edge,
                mesh.local(i)[2],
                row,
                &visible,
            );
            row.iter_mut().for_each(|v| *v *= rho);
        },
        stop,
    )
}

/// The exact visible transfer, as [`transfer_row`] wants it.
pub(crate) fn visible(
    r: &Receiver,
    _: usize,
    s: &Sender,
    occluders: &[[DVec2; 2]],
    scratch: &mut Vec<[f64; 2]>,
) -> f64 {
    point_to_segment_visible(r, s, occluders, scratch)
}

/// Composite Gauss–Legendre along a receiver interval for [`exact_block_means`]: panels × points.
const BLOCK_PANELS: usize = 32;
const BLOCK_POINTS: usize = 8;

/// The exact mean over each block of a `g × g` grid of `(s, t)` of `ζ` (`weighted`) or of `k`,
/// row-major (row ↔ s). The integral over `s` is exact (closed form with exact visibility, per
/// sender edge, so each part gets its own E'); the one over `t` is composite Gauss–Legendre
/// (`BLOCK_PANELS` × `BLOCK_POINTS` = 32 × 8 points per receiver edge in the block), which
/// converges because the inner integral is continuous in `t`. No ray is cast. The uniform
/// grid's exact block values (`flatland_baselines::BlockValue`) are these.
pub fn exact_block_means(
    kernel: &Kernel,
    g: usize,
    weighted: bool,
    stop: &Stop,
) -> Result<Vec<f64>, SolveError> {
    block_means_with(kernel, g, weighted, BLOCK_PANELS, stop)
}

fn block_means_with(
    kernel: &Kernel,
    g: usize,
    weighted: bool,
    panels: usize,
    stop: &Stop,
) -> Result<Vec<f64>, SolveError> {
    let mesh = Mesh::coarsest_unlit(kernel);
    let table = PairTable::new(kernel, &mesh)?;
    let (nodes, weights) = crate::gauss_legendre(BLOCK_POINTS);
    let blocks = Blocks {
        mesh: &mesh,
        table: &table,
        nodes,
        weights,
        panels,
    };
    (0..g * g)
        .into_par_iter()
        .map_init(Vec::new, |scratch, block| {
            if stop() {
                return Err(SolveError::Interrupted);
            }
            let (i, j) = (block / g, block % g);
            let s_range = [i as f64 / g as f64, (i + 1) as f64 / g as f64];
            let t_range = [j as f64 / g as f64, (j + 1) as f64 / g as f64];
            let senders = blocks.senders(s_range, weighted);
            Ok(blocks.received(&senders, t_range, scratch) * (g * g) as f64)
        })
        .collect()
}

/// What every block mean of k is integrated with: the coarsest mesh, its pair table, and the
/// Gauss–Legendre rule on each of `panels` panels of a receiving edge.
struct Blocks<'a> {
    mesh: &'a Mesh,
    table: &'a PairTable,
    nodes: Vec<f64>,
    weights: Vec<f64>,
    panels: usize,
}

/// A mesh edge sending to a block: its index, its part in the block's s range, its weight.
type BlockSender = (usize, Sender, f64);

impl Blocks<'_> {
    /// The part of `range` (arc length parameters) on `edge`, if any.
    fn overlap(range: [f64; 2], edge: &crate::MeshEdge) -> Option<[f64; 2]> {
        let part = [range[0].max(edge.s[0]), range[1].min(edge.s[1])];
        (part[1] > part[0]).then_some(part)
    }

    /// Where on mesh edge `k` (frame coordinates) the parameter `s` lies.
    fn at(&self, k: usize, s: f64) -> DVec2 {
        let e = &self.mesh.edges()[k];
        let u = ((s - e.s[0]) / (e.s[1] - e.s[0])).clamp(0.0, 1.0);
        let (a, b) = (self.mesh.to_local(e.a), self.mesh.to_local(e.b));
        a + (b - a) * u
    }

    /// The parts of the mesh edges in `s_range`, weighted by their source weights if
    /// `weighted`.
    fn senders(&self, s_range: [f64; 2], weighted: bool) -> Vec<BlockSender> {
        let edges = self.mesh.edges();
        (0..edges.len())
            .filter_map(|k| {
                let part = Self::overlap(s_range, &edges[k])?;
                let weight = if weighted {
                    edges[k].source_weight
                } else {
                    1.0
                };
                let s = Sender {
                    a: self.at(k, part[0]),
                    b: self.at(k, part[1]),
                    normal: edges[k].normal,
                };
                Some((k, s, weight))
            })
            .collect()
    }

    /// ∫∫ k over `senders` × `t_range`: what every receiving edge in `t_range` gathers.
    fn received(
        &self,
        senders: &[BlockSender],
        t_range: [f64; 2],
        scratch: &mut Vec<[f64; 2]>,
    ) -> f64 {
        let l = self.mesh.total_length();
        let mut integral = 0.0;
        for (r, edge) in self.mesh.edges().iter().enumerate() {
            let Some([ta, tb]) = Self::overlap(t_range, edge) else {
                continue;
            };
            if edge.reflectance == 0.0 {
                continue;
            }
            let width = (tb - ta) / self.panels as f64;
            let mut along = 0.0;
            for p in 0..self.panels {
                let (p0, p1) = (ta + width * p as f64, ta + width * (p + 1) as f64);
                let (half, mid) = (0.5 * (p1 - p0), 0.5 * (p0 + p1));
                for (x, w) in self.nodes.iter().zip(&self.weights) {
                    let y = receiver(self.mesh, r, self.at(r, mid + half * x));
                    along += w * half * self.gathered(senders, r, &y, scratch);
                }
            }
            // ∫ k ds = ρ ∫ G V dl / L.
            integral += edge.reflectance * along / l;
        }
        integral
    }

    /// What receiver `y` on mesh edge `r` gathers from `senders`.
    fn gathered(
        &self,
        senders: &[BlockSender],
        r: usize,
        y: &Receiver,
        scratch: &mut Vec<[f64; 2]>,
    ) -> f64 {
        senders
            .iter()
            .map(|(k, s, weight)| {
                let t = match self.table.get(*k, r) {
                    PairTransfer::Zero => 0.0,
                    PairTransfer::Clear => point_to_segment(y, s),
                    PairTransfer::Occluded(occ) => point_to_segment_visible(y, s, occ, scratch),
                };
                weight * t
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::never;
    use crate::test_support::{bundled, l_room};

    #[test]
    fn exact_operator_rows_agree_with_the_kernel_integrated_by_rays() {
        // Independent of the closed form: ∫ k(s, t_i) L ds over element j by dense midpoint
        // sampling of the exact kernel (one ray per sample), away from corner singularities.
        for name in ["fig3", "maze", "corners"] {
            let kernel = Kernel::new(bundled(name));
            let mesh = Mesh::new(&kernel, 48).unwrap();
            let op = exact_operator(&kernel, &mesh, &never).unwrap();
            let l = mesh.total_length();
            let mut compared = 0;
            for i in (0..mesh.len()).step_by(7) {
                let t = mesh.elements()[i].s_mid;
                for (j, e) in mesh.elements().iter().enumerate() {
                    if e.a
                        .distance(mesh.elements()[i].midpoint)
                        .min(e.b.distance(mesh.elements()[i].midpoint))
                        < 0.3
                    {
                        continue; // near-singular pairs: quadrature by rays is the poor one there
                    }
                    // Midpoint sampling: its error is at most (jump × spacing) / 2 per jump of
                    // the integrand (a shadow edge), so two jumps stay within max k × spacing.
                    let n = 40_000;
                    let h = (e.s[1] - e.s[0]) * l / n as f64;
                    let samples: Vec<f64> = (0..n)
                        .map(|q| {
                            kernel.k(e.s[0] + (e.s[1] - e.s[0]) * (q as f64 + 0.5) / n as f64, t)
                        })
                        .collect();
                    let rays: f64 = samples.iter().sum::<f64>() * h;
                    let bound = samples.iter().fold(0.0_f64, |m, &k| m.max(k)) * h;
                    let exact = op.get(i, j);
                    // Plus 1e-14: an entry is a difference of sines of order one, so a shadow
                    // ending exactly on an element's end (maze: the blocker's end (3, 1.4) lies
                    // on the line from the floor at 5.625 to the partition's top) leaves a
                    // sliver of rounding that no ray sees.
                    assert!(
                        (exact - rays).abs() <= 1e-6 * exact + bound + 1e-14,
                        "{name}: K[{i}][{j}] = {exact} vs rays {rays} (bound {bound})"
                    );
                    compared += usize::from(exact > 0.0);
                }
            }
            assert!(
                compared > 50,
                "{name}: only {compared} non-zero entries compared"
            );
        }
    }

    #[test]
    fn rows_sum_to_rho_in_closed_rooms_without_blockers() {
        // Every direction from a point of a closed room ends on a wall: Σ_j K_ij = ρ_i,
        // exactly, occluded or not (the L room's reflex corner).
        for scene in [bundled("box"), l_room(0.6)] {
            let kernel = Kernel::new(scene);
            let mesh = Mesh::new(&kernel, 200).unwrap();
            let op = exact_operator(&kernel, &mesh, &never).unwrap();
            for i in 0..mesh.len() {
                let sum: f64 = op.row(i).iter().sum();
                let rho = mesh.edge_of(i).reflectance;
                assert!((sum - rho).abs() < 1e-12, "row {i}: {sum} vs ρ = {rho}");
            }
        }
    }

    #[test]
    fn block_means_converge_and_match_dense_sampling() {
        let kernel = Kernel::new(bundled("fig3"));
        let g = 6;
        let means = exact_block_means(&kernel, g, true, &never).unwrap();
        let finer = block_means_with(&kernel, g, true, 4 * BLOCK_PANELS, &never).unwrap();
        for (b, (m, f)) in means.iter().zip(&finer).enumerate() {
            assert!((m - f).abs() <= 1e-4 * f.max(1e-3), "block {b}: {m} vs {f}");
        }
        // Against the exact ζ sampled densely (midpoints, one ray each) on blocks whose
        // corners are not singular: agreement to the sampling error.
        let n = 300;
        for block in [1, 8, 13, 27, 33, 34] {
            let (i, j) = (block / g, block % g);
            let sum: f64 = (0..n * n)
                .map(|q| {
                    let s = (i as f64 + ((q / n) as f64 + 0.5) / n as f64) / g as f64;
                    let t = (j as f64 + ((q % n) as f64 + 0.5) / n as f64) / g as f64;
                    kernel.zeta(s, t)
                })
                .sum();
            let sampled = sum / (n * n) as f64;
            assert!(
                (means[block] - sampled).abs() <= 2e-3 * sampled.max(1e-4),
                "block {block}: exact mean {} vs sampled {sampled}",
                means[block]
            );
        }
        // Means of k: no E' inside.
        let k_means = exact_block_means(&kernel, g, false, &never).unwrap();
        assert!(k_means.iter().zip(&means).all(|(k, z)| k >= z));
    }
}
