//! The learner's operator on one mesh, by blocks: a receiver element and one sending edge.
//!
//! Row `i` of `K` gathers at element `i`'s midpoint `y_i` the light of every sending surface
//! edge `k`: `K_ij = ρ_i ∫_{element j} G(x, y_i) V(x, y_i) dl_x` for the elements `j` of `k`.
//! `ρ_i ∫ G` without `V` is a closed form, cheap for every pair; `V` is not. So each block
//! `(i, k)` with any unoccluded transfer starts **unresolved**, holding its unoccluded
//! transfers `U_ij`, and stands in the operator as `p_i · U_ij`, where the row's **prior**
//! `p_i` spreads the light row `i` can still receive over its unresolved directions
//! ([`Blocks::priors`]). **Resolving** a block replaces its entries with the exact
//! `ρ_i ∫ G Ṽ` of the model's visibility: nothing where the geometry proves the pair hidden,
//! the closed form where it proves it clear, and where visibility varies the closed form over
//! each piece of the sending edge between faces of the pair's visibility structure, times the
//! face's `V` (learned by one ray the first time any block meets the face, shared by every
//! block after; [`Faces`]).
//!
//! Pairs are classified only when a block of theirs is resolved, so a pair whose light never
//! matters is never classified.

use std::ops::Range;

use flatland_geom::{Kernel, PairClass};
use flatland_solve::{Mesh, Sender, Stop, TransferOperator, point_to_segment, receiver, sender};
use rayon::prelude::*;

use crate::FitError;
use crate::visibility::FaceKey;

/// Rows per rayon task in the block loops.
const ROWS_PER_TASK: usize = 16;

/// One block: receiver element `row`, sending mesh edge `edge`.
#[derive(Clone, Copy, Debug)]
struct Block {
    row: u32,
    edge: u32,
    /// Where its entries start in [`Blocks::values`] (one per element of `edge`).
    first: u32,
    resolved: bool,
    /// `Σ_j` of its entries: the unoccluded transfer while unresolved, the exact one after.
    sum: f64,
}

/// Where the visibility of a face comes from: the learner's model.
pub(crate) trait Faces: Sync {
    /// `Ṽ` on face `key`, if a cell of the model lies in it.
    fn known(&self, key: &FaceKey) -> Option<f64>;
    /// Learns each face of `rays` (a face the model does not know yet and the `(s, t)` of a
    /// ray in it; one ray each); returns how many rays it cast.
    fn learn(&mut self, rays: &[(FaceKey, [f64; 2])]) -> Result<u64, FitError>;
}

/// Every block of a mesh, in row order (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct Blocks {
    n: usize,
    blocks: Vec<Block>,
    /// The blocks of row `i`.
    rows: Vec<Range<u32>>,
    values: Vec<f64>,
    /// `ρ_i`, the most a row can gather (a one-sided receiver sees at most a half-plane).
    reach: Vec<f64>,
    /// The rank of each mesh edge's parent surface edge.
    rank: Vec<usize>,
}

impl Blocks {
    /// The unresolved blocks of `mesh`: one per receiver element and sending edge with any
    /// unoccluded transfer (a closed form each, no ray, no pair classified).
    pub(crate) fn new(kernel: &Kernel, mesh: &Mesh, stop: &Stop) -> Result<Blocks, FitError> {
        flatland_solve::check_scene(kernel, mesh)?;
        let edges = mesh.edges();
        let n = mesh.len();
        let per_row: Vec<UnoccludedRow> = (0..n)
            .into_par_iter()
            .with_min_len(ROWS_PER_TASK)
            .map(|i| {
                if stop() {
                    return Err(FitError::Interrupted);
                }
                Ok(unoccluded_row(mesh, i))
            })
            .collect::<Result<_, _>>()?;
        let mut blocks = Vec::new();
        let mut rows = Vec::with_capacity(n);
        let mut values = Vec::new();
        for (i, (row_blocks, row_values)) in per_row.into_iter().enumerate() {
            let start = blocks.len() as u32;
            let mut offset = values.len();
            for (edge, sum) in row_blocks {
                blocks.push(Block {
                    row: i as u32,
                    edge,
                    first: offset as u32,
                    resolved: false,
                    sum,
                });
                offset += edges[edge as usize].elements.len();
            }
            values.extend(row_values);
            rows.push(start..blocks.len() as u32);
        }
        let reach = (0..n)
            .map(|i| {
                let e = mesh.edge_of(i);
                e.reflectance * if e.two_sided { 2.0 } else { 1.0 }
            })
            .collect();
        let rank = edges
            .iter()
            .map(|e| kernel.unoccluded((e.s[0] + e.s[1]) / 2.0, 0.0).sender)
            .collect();
        Ok(Blocks {
            n,
            blocks,
            rows,
            values,
            reach,
            rank,
        })
    }

    /// Number of blocks.
    pub(crate) fn len(&self) -> usize {
        self.blocks.len()
    }

    /// Number of blocks not yet resolved.
    pub(crate) fn unresolved(&self) -> usize {
        self.blocks.iter().filter(|b| !b.resolved).count()
    }

    /// Bytes of the structure.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.blocks.len() * std::mem::size_of::<Block>()
            + self.values.len() * 8
            + self.rows.len() * 8
            + self.reach.len() * 8
            + self.rank.len() * 8
    }

    /// Each row's prior: what it can still gather (`ρ_i` less its resolved blocks' light)
    /// spread over its unresolved blocks' unoccluded light, in `[0, 1]`; 0 for a row with
    /// nothing unresolved.
    ///
    /// Why this and not a fixed guess such as ½: behind a wall, every block of a floor plan
    /// "could" see a lamp, and a guess per block that ignores the others passes light through
    /// walls — rows then gather more than they can receive and the solve gains energy. Spread
    /// this way a row never gathers more than `ρ_i`, and as blocks are resolved the prior
    /// moves to the directions not yet explained.
    pub(crate) fn priors(&self) -> Vec<f64> {
        self.rows
            .par_iter()
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .map(|(i, range)| {
                let (mut known, mut open) = (0.0, 0.0);
                for b in &self.blocks[range.start as usize..range.end as usize] {
                    if b.resolved {
                        known += b.sum;
                    } else {
                        open += b.sum;
                    }
                }
                if open > 0.0 {
                    ((self.reach[i] - known).max(0.0) / open).min(1.0)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The operator with `priors` standing in for the unresolved blocks.
    pub(crate) fn operator<'a>(&'a self, mesh: &'a Mesh, priors: &'a [f64]) -> BlockOperator<'a> {
        BlockOperator {
            blocks: self,
            mesh,
            priors,
        }
    }

    /// Per row `i`: `Σ` over its unresolved blocks of `w(p_i) Σ_j U_ij b_j` — with
    /// `w(p) = 2 p (1 − p)`, the expected error `E|V − p|` of a row's light if each
    /// unresolved face were visible with probability `p`.
    pub(crate) fn unresolved_error(&self, mesh: &Mesh, priors: &[f64], b: &[f64]) -> Vec<f64> {
        let edges = mesh.edges();
        self.rows
            .par_iter()
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .map(|(i, range)| {
                let p = priors[i];
                let w = 2.0 * p * (1.0 - p);
                if w == 0.0 {
                    return 0.0;
                }
                let mut total = 0.0;
                for blk in &self.blocks[range.start as usize..range.end as usize] {
                    if !blk.resolved {
                        total += self.gathered(blk, edges, b).abs();
                    }
                }
                w * total
            })
            .collect()
    }

    /// The unresolved blocks through which the prior sends the most light, as power
    /// (`p_i Σ_j U_ij b_j` times the receiver element's length), largest first: at most
    /// `count`, and no more than it takes to cover `share` of the power of every unresolved
    /// block (a share of 1 takes all `count`).
    pub(crate) fn most_light(
        &self,
        mesh: &Mesh,
        priors: &[f64],
        b: &[f64],
        count: usize,
        share: f64,
    ) -> Vec<usize> {
        let (edges, elements) = (mesh.edges(), mesh.elements());
        let mut flow: Vec<(f64, usize)> = self
            .blocks
            .par_iter()
            .enumerate()
            .with_min_len(1024)
            .filter(|(_, blk)| !blk.resolved)
            .map(|(q, blk)| {
                let i = blk.row as usize;
                let power = priors[i] * self.gathered(blk, edges, b) * elements[i].length;
                (power, q)
            })
            .collect();
        let count = count.min(flow.len());
        if count == 0 {
            return Vec::new();
        }
        let total: f64 = flow.iter().map(|f| f.0.abs()).sum();
        let by_power = |x: &(f64, usize), y: &(f64, usize)| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1));
        flow.select_nth_unstable_by(count - 1, by_power);
        flow.truncate(count);
        flow.sort_unstable_by(by_power);
        let mut covered = 0.0;
        let enough = flow
            .iter()
            .position(|f| {
                covered += f.0.abs();
                covered >= share * total
            })
            .map_or(count, |k| k + 1);
        flow.into_iter().take(enough).map(|(_, q)| q).collect()
    }

    /// `Σ_j values_j b_j` of one block.
    fn gathered(&self, blk: &Block, edges: &[flatland_solve::MeshEdge], b: &[f64]) -> f64 {
        let elements = edges[blk.edge as usize].elements.clone();
        let first = blk.first as usize;
        self.values[first..first + elements.len()]
            .iter()
            .zip(&b[elements])
            .map(|(v, x)| v * x)
            .sum()
    }

    /// Resolves the blocks `which` with the visibility `faces` knows, first letting it learn
    /// the faces none of its cells lies in (the rays of this round). Returns the rays cast.
    pub(crate) fn resolve(
        &mut self,
        kernel: &Kernel,
        mesh: &Mesh,
        which: &[usize],
        faces: &mut impl Faces,
        stop: &Stop,
    ) -> Result<u64, FitError> {
        // 1. Every piece of every block to resolve, and the faces nobody knows yet.
        let plans: Vec<Plan> = which
            .par_iter()
            .map(|&q| {
                if stop() {
                    return Err(FitError::Interrupted);
                }
                Ok(self.plan(kernel, mesh, q))
            })
            .collect::<Result<_, _>>()?;
        let mut unknown: Vec<(FaceKey, [f64; 2])> = plans
            .par_iter()
            .flat_map_iter(|plan| plan.pieces.iter())
            .filter(|p| faces.known(&p.face).is_none())
            .map(|p| (p.face.clone(), p.st))
            .collect();
        // One ray per new face: the first piece met (in block order) stands for it.
        let mut seen = foldhash::HashSet::default();
        unknown.retain(|(key, _)| seen.insert(key.clone()));
        // 2. The rays (the model files a cell for each).
        let rays = faces.learn(&unknown)?;
        // 3. The blocks' entries with every face now known.
        let faces: &(dyn Faces + Sync) = faces;
        let entries: Vec<(usize, Vec<f64>)> = plans
            .into_par_iter()
            .map(|plan| {
                (
                    plan.block,
                    plan.entries(|key| faces.known(key).unwrap_or(0.0)),
                )
            })
            .collect();
        for (q, values) in entries {
            let blk = &mut self.blocks[q];
            let first = blk.first as usize;
            self.values[first..first + values.len()].copy_from_slice(&values);
            blk.sum = values.iter().sum();
            blk.resolved = true;
        }
        Ok(rays)
    }

    /// The pieces of block `q` as its resolution would see them: face, ray and length (as a
    /// share of the sending edge).
    #[cfg(test)]
    pub(crate) fn pieces_of(
        &self,
        kernel: &Kernel,
        mesh: &Mesh,
        q: usize,
    ) -> Vec<(FaceKey, [f64; 2], f64)> {
        let width = {
            let e = &mesh.edges()[self.blocks[q].edge as usize];
            e.s[1] - e.s[0]
        };
        self.plan(kernel, mesh, q)
            .pieces
            .into_iter()
            .map(|p| (p.face, p.st, p.length / width))
            .collect()
    }

    /// What resolving block `q` takes: its pieces between faces, or its entries outright
    /// where the geometry decides.
    fn plan(&self, kernel: &Kernel, mesh: &Mesh, q: usize) -> Plan {
        let blk = self.blocks[q];
        let (i, k) = (blk.row as usize, blk.edge as usize);
        let edge = &mesh.edges()[k];
        let here = &mesh.elements()[i];
        let first = blk.first as usize;
        let unoccluded = self.values[first..first + edge.elements.len()].to_vec();
        let (a, b) = (self.rank[k], self.rank[here.mesh_edge]);
        let mut plan = Plan {
            block: q,
            fixed: None,
            pieces: Vec::new(),
            count: edge.elements.len(),
        };
        match kernel.pair_class(a, b) {
            PairClass::Zero | PairClass::Hidden => plan.fixed = Some(vec![0.0; unoccluded.len()]),
            PairClass::Visible => plan.fixed = Some(unoccluded),
            PairClass::Varies => match kernel.visibility_events(a, b) {
                // The receiver sees the sending edge between the pair's faces.
                Some(events) => {
                    let y = kernel.scene().point(here.s_mid).position;
                    let stretches = events.sender_faces(y);
                    plan.pieces = pieces(mesh, i, k, a, b, stretches);
                }
                None => plan.fixed = Some(vec![0.0; unoccluded.len()]),
            },
        }
        plan
    }
}

/// The entries of one block being resolved.
struct Plan {
    block: usize,
    /// Entries the geometry decides outright.
    fixed: Option<Vec<f64>>,
    /// Otherwise each piece between faces: its element (0-based within the edge), its
    /// closed-form transfer and the `(s, t)` of its ray.
    pieces: Vec<Piece>,
    count: usize,
}

struct Piece {
    element: usize,
    transfer: f64,
    face: FaceKey,
    st: [f64; 2],
    /// Its extent in `s` (what the tests compare).
    #[cfg(test)]
    length: f64,
}

impl Plan {
    fn entries(self, visibility: impl Fn(&FaceKey) -> f64) -> Vec<f64> {
        if let Some(fixed) = self.fixed {
            return fixed;
        }
        let mut out = vec![0.0; self.count];
        for p in &self.pieces {
            out[p.element] += p.transfer * visibility(&p.face);
        }
        out
    }
}

/// The pieces of sending edge `k` (parent rank `a`) as seen from element `i`'s midpoint (rank
/// `b`): each element of `k` cut where the faces of the pair's visibility structure change
/// (`stretches`, parameters along the edge), with the closed-form transfer (`ρ_i` included) of
/// each piece, its face and the `(s, t)` of the ray from its middle to `y_i`.
fn pieces(
    mesh: &Mesh,
    i: usize,
    k: usize,
    a: usize,
    b: usize,
    stretches: Vec<flatland_geom::SenderFace>,
) -> Vec<Piece> {
    let edge = &mesh.edges()[k];
    let here = &mesh.elements()[i];
    let rho = mesh.edge_of(i).reflectance;
    let r = receiver(mesh, here.mesh_edge, mesh.local(i)[2]);
    let width = edge.s[1] - edge.s[0];
    let bounds: Vec<(f64, f64)> = edge
        .elements
        .clone()
        .map(|j| {
            let e = &mesh.elements()[j];
            ((e.s[0] - edge.s[0]) / width, (e.s[1] - edge.s[0]) / width)
        })
        .collect();
    let mut out = Vec::new();
    for stretch in stretches {
        let [w0, w1] = stretch.u;
        let face = FaceKey::of_stretch(a, b, stretch);
        // The elements this stretch overlaps.
        let first = bounds.partition_point(|&(_, u1)| u1 <= w0);
        for (o, &(u0, u1)) in bounds.iter().enumerate().skip(first) {
            if u0 >= w1 {
                break;
            }
            let (from, to) = (w0.max(u0), w1.min(u1));
            if to <= from {
                continue;
            }
            let j = edge.elements.start + o;
            let whole = sender(mesh, j);
            let at = |u: f64| whole.a + (whole.b - whole.a) * ((u - u0) / (u1 - u0));
            let piece = Sender {
                a: at(from),
                b: at(to),
                ..whole
            };
            let transfer = rho * point_to_segment(&r, &piece);
            if transfer > 0.0 {
                let s = edge.s[0] + width * 0.5 * (from + to);
                out.push(Piece {
                    element: o,
                    transfer,
                    face: face.clone(),
                    st: [s, here.s_mid],
                    #[cfg(test)]
                    length: width * (to - from),
                });
            }
        }
    }
    out
}

/// A row's sending edges with any unoccluded transfer (edge, sum), and their entries.
type UnoccludedRow = (Vec<(u32, f64)>, Vec<f64>);

/// The closed-form unoccluded transfers of row `i` (`ρ_i` included): the sending edges with
/// any, each with its sum, and their entries in edge order.
fn unoccluded_row(mesh: &Mesh, i: usize) -> UnoccludedRow {
    let rho = mesh.edge_of(i).reflectance;
    let own = mesh.elements()[i].mesh_edge;
    let mut blocks = Vec::new();
    let mut values = Vec::new();
    if rho == 0.0 {
        return (blocks, values);
    }
    let r = receiver(mesh, own, mesh.local(i)[2]);
    for (k, edge) in mesh.edges().iter().enumerate() {
        if k == own {
            continue;
        }
        let start = values.len();
        values.extend(
            edge.elements
                .clone()
                .map(|j| rho * point_to_segment(&r, &sender(mesh, j))),
        );
        let sum: f64 = values[start..].iter().sum();
        if sum > 0.0 {
            blocks.push((k as u32, sum));
        } else {
            values.truncate(start);
        }
    }
    (blocks, values)
}

/// `K` of [`Blocks`] with a prior per row for the unresolved blocks, matrix-free.
pub(crate) struct BlockOperator<'a> {
    blocks: &'a Blocks,
    mesh: &'a Mesh,
    priors: &'a [f64],
}

impl TransferOperator for BlockOperator<'_> {
    fn len(&self) -> usize {
        self.blocks.n
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        let blocks = self.blocks;
        let edges = self.mesh.edges();
        out.par_iter_mut()
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .for_each(|(i, o)| {
                let p = self.priors[i];
                let mut total = 0.0;
                for blk in
                    &blocks.blocks[blocks.rows[i].start as usize..blocks.rows[i].end as usize]
                {
                    let weight = if blk.resolved { 1.0 } else { p };
                    if weight != 0.0 && blk.sum != 0.0 {
                        total += weight * blocks.gathered(blk, edges, b);
                    }
                }
                *o = total;
            });
    }
}
