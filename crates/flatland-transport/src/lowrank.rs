//! The local low-rank form of the later bounces: per cluster `c` of source elements, the block
//! of columns `M₂[:, c]` restricted to the rows its light reaches, `≈ U_c V_cᵀ` with a few
//! columns each. A block is computed exactly by local solves (the light of each element of `c`
//! shot twice through K, then to the end: `(I − K)⁻¹ K² [:, c]`, touching only the rooms it
//! reaches), rows whose share of the block is below the tolerance are dropped, and the rest
//! is truncated by its singular values. Far rooms decouple, so the set-up is
//! `O(clusters × local size)` and a query `O(Σ rank × rows)` over the clusters it lights.

use faer::Mat;
use rayon::prelude::*;

use crate::Columns;
use crate::clusters::Clusters;
use crate::footprint::{BlockFootprint, Watch};
use crate::local::{Block, Workspace};
use crate::{QueryBuffers, Stop, TransportError};

/// One cluster's block `M₂[rows, elements] ≈ U Vᵀ`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ClusterBlock {
    /// The receivers kept, ascending.
    pub rows: Vec<u32>,
    /// `rows.len() × rank`, row-major, the singular values folded in.
    pub u: Vec<f32>,
    /// `elements × rank`, row-major (the cluster's elements in ascending order).
    pub v: Vec<f32>,
    /// The singular values kept, descending.
    pub sigma: Vec<f64>,
    /// `‖M₂[:, c]‖_F` as computed, and the Frobenius norm of what was left out (rows, the
    /// singular values past the rank), the estimate of the block's error.
    pub norm: f64,
    pub dropped: f64,
}

impl ClusterBlock {
    pub fn rank(&self) -> usize {
        self.sigma.len()
    }

    pub fn bytes(&self) -> usize {
        4 * self.rows.len() + 4 * self.u.len() + 4 * self.v.len() + 8 * self.sigma.len() + 16
    }

    /// Keeps the first `rank` singular triplets, adding what goes to the dropped norm.
    pub fn truncate(&mut self, rank: usize) {
        let old = self.rank();
        if rank >= old {
            return;
        }
        let cut: f64 = self.sigma[rank..].iter().map(|s| s * s).sum();
        self.dropped = (self.dropped * self.dropped + cut).sqrt();
        self.sigma.truncate(rank);
        let keep = |m: &[f32]| -> Vec<f32> {
            m.chunks_exact(old)
                .flat_map(|r| r[..rank].iter().copied())
                .collect()
        };
        self.u = keep(&self.u);
        self.v = keep(&self.v);
    }
}

/// What a block is built to.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BlockTolerance {
    /// The relative Frobenius error allowed a block.
    pub block: f64,
    /// The local solves' threshold, relative to a column's largest value.
    pub solve: f64,
}

/// `M₂[:, c]` for every cluster, in parallel (one workspace per thread; each block depends
/// only on its cluster, so the result does not depend on the thread count). Each block's
/// footprint goes to `watch` as soon as it is made, in whatever order the threads finish.
pub(crate) fn build_blocks(
    columns: &Columns,
    clusters: &Clusters,
    tolerance: BlockTolerance,
    stop: &Stop,
    watch: &Watch<'_>,
) -> Result<Vec<ClusterBlock>, TransportError> {
    let n = columns.len();
    clusters
        .members
        .par_iter()
        .enumerate()
        .map_init(
            || Workspace::new(n),
            |work, (c, elements)| {
                if stop() {
                    return Err(TransportError::Interrupted);
                }
                let block = block_of(work, columns, elements, tolerance)?;
                watch(BlockFootprint::of(c, elements, &block.rows, block.rank()));
                Ok(block)
            },
        )
        .collect()
}

/// One cluster's block.
fn block_of(
    work: &mut Workspace,
    columns: &Columns,
    elements: &[u32],
    tolerance: BlockTolerance,
) -> Result<ClusterBlock, TransportError> {
    let once = work.apply(columns, &Block::unit(elements));
    let twice = work.apply(columns, &once);
    let y = work.solve(columns, &twice, tolerance.solve)?;
    Ok(compress(&y, tolerance.block))
}

/// Rows dropped (smallest first) while their share of `‖y‖²_F` stays within a quarter of
/// `tolerance²`, then the singular values past the rank whose tail is within the rest.
fn compress(y: &Block, tolerance: f64) -> ClusterBlock {
    let width = y.width;
    let norms: Vec<f64> = (0..y.elements.len())
        .map(|r| y.row(r).iter().map(|v| v * v).sum())
        .collect();
    let total: f64 = norms.iter().sum();
    let mut order: Vec<usize> = (0..norms.len()).collect();
    order.sort_unstable_by(|&a, &b| norms[a].total_cmp(&norms[b]).then(a.cmp(&b)));
    let row_allowance = 0.25 * tolerance * tolerance * total;
    let mut dropped_rows = 0.0;
    let mut keep = vec![true; norms.len()];
    for &r in &order {
        if dropped_rows + norms[r] > row_allowance {
            break;
        }
        dropped_rows += norms[r];
        keep[r] = false;
    }
    let kept: Vec<usize> = (0..norms.len()).filter(|&r| keep[r]).collect();
    let a = Mat::from_fn(kept.len(), width, |i, j| y.row(kept[i])[j]);
    let svd = a.thin_svd().expect("the SVD of a finite block converges");
    let s = svd.S().column_vector();
    let sigma: Vec<f64> = (0..s.nrows()).map(|k| s[k]).collect();
    let allowance = tolerance * tolerance * total - dropped_rows;
    let mut tail = 0.0;
    let mut rank = sigma.len();
    while rank > 0 && tail + sigma[rank - 1].powi(2) <= allowance {
        tail += sigma[rank - 1].powi(2);
        rank -= 1;
    }
    let (u, v) = (svd.U(), svd.V());
    let sigma = &sigma;
    ClusterBlock {
        rows: kept.iter().map(|&r| y.elements[r]).collect(),
        u: (0..kept.len())
            .flat_map(|i| (0..rank).map(move |k| (u[(i, k)] * sigma[k]) as f32))
            .collect(),
        v: (0..width)
            .flat_map(|j| (0..rank).map(move |k| v[(j, k)] as f32))
            .collect(),
        norm: total.sqrt(),
        dropped: (dropped_rows + tail).sqrt(),
        sigma: sigma[..rank].to_vec(),
    }
}

/// The blocks of all clusters: `M₂ ≈ Σ_c U_c V_cᵀ` (each on its rows and its cluster's
/// columns).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LowRank {
    pub clusters: Clusters,
    pub blocks: Vec<ClusterBlock>,
}

impl LowRank {
    /// Adds `M₂ b` to the answer in `buffers` for `b` given by its non-zero entries
    /// `(element, value)`: per cluster `c` it lights, `U_c (V_cᵀ b_c)`, clusters ascending.
    pub fn accumulate(&self, lit: &[(u32, f64)], buffers: &mut QueryBuffers) {
        let mut pairs = std::mem::take(&mut buffers.pairs);
        let mut coefficients = std::mem::take(&mut buffers.scratch);
        pairs.clear();
        pairs.extend(lit.iter().map(|&(e, b)| {
            let (c, k) = self.clusters.place[e as usize];
            (c, k, b)
        }));
        pairs.sort_unstable_by_key(|&(c, k, _)| (c, k));
        for group in pairs.chunk_by(|a, b| a.0 == b.0) {
            let block = &self.blocks[group[0].0 as usize];
            let rank = block.rank();
            if rank == 0 {
                continue;
            }
            coefficients.clear();
            coefficients.resize(rank, 0.0);
            for &(_, k, b) in group {
                let v = &block.v[k as usize * rank..(k as usize + 1) * rank];
                for (c, &vk) in coefficients.iter_mut().zip(v) {
                    *c += f64::from(vk) * b;
                }
            }
            for (&row, u) in block.rows.iter().zip(block.u.chunks_exact(rank)) {
                let sum: f64 = u
                    .iter()
                    .zip(&coefficients)
                    .map(|(&uk, c)| f64::from(uk) * c)
                    .sum();
                buffers.add(row, sum);
            }
        }
        buffers.pairs = pairs;
        buffers.scratch = coefficients;
    }

    /// Visits every entry `M₂[row, column]` the blocks hold (`U_c V_cᵀ` on each block's rows
    /// and cluster), cluster by cluster.
    pub fn entries(&self, visit: &mut dyn FnMut(u32, u32, f64)) {
        for (block, columns) in self.blocks.iter().zip(&self.clusters.members) {
            let rank = block.rank();
            if rank == 0 {
                continue;
            }
            for (&row, u) in block.rows.iter().zip(block.u.chunks_exact(rank)) {
                for (&column, v) in columns.iter().zip(block.v.chunks_exact(rank)) {
                    let value: f64 = u
                        .iter()
                        .zip(v)
                        .map(|(&a, &b)| f64::from(a) * f64::from(b))
                        .sum();
                    visit(row, column, value);
                }
            }
        }
    }

    /// Every block's footprint, in cluster order.
    pub fn footprints(&self) -> Vec<BlockFootprint> {
        self.blocks
            .iter()
            .zip(&self.clusters.members)
            .enumerate()
            .map(|(c, (block, elements))| {
                BlockFootprint::of(c, elements, &block.rows, block.rank())
            })
            .collect()
    }

    /// Bytes held: the blocks and the clusters' tables.
    pub fn bytes(&self) -> usize {
        self.blocks.iter().map(ClusterBlock::bytes).sum::<usize>() + 12 * self.clusters.place.len()
    }

    /// Drops the singular triplets that cost the most bytes per unit of `σ²` they carry,
    /// smallest `σ²` per byte first, until the blocks fit in `budget` bytes.
    pub fn fit_budget(&mut self, budget: usize) {
        let mut bytes = self.bytes();
        if bytes <= budget {
            return;
        }
        // Every triplet's (σ² per byte, block, index): the last of each block goes first.
        let mut triplets: Vec<(f64, usize, usize)> = self
            .blocks
            .iter()
            .enumerate()
            .flat_map(|(b, block)| {
                let cost = 4 * (block.rows.len() + block.v.len() / block.rank().max(1)) + 8;
                block
                    .sigma
                    .iter()
                    .enumerate()
                    .map(move |(k, s)| (s * s / cost as f64, b, k))
            })
            .collect();
        triplets
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(b.2.cmp(&a.2)));
        let mut ranks: Vec<usize> = self.blocks.iter().map(ClusterBlock::rank).collect();
        for &(_, b, k) in &triplets {
            if bytes <= budget {
                break;
            }
            // Singular values descend within a block, so dropping by σ² drops tails first.
            if k + 1 == ranks[b] {
                let block = &self.blocks[b];
                bytes -= 4 * (block.rows.len() + block.v.len() / block.rank().max(1)) + 8;
                ranks[b] = k;
            }
        }
        for (block, rank) in self.blocks.iter_mut().zip(ranks) {
            block.truncate(rank);
        }
    }
}
