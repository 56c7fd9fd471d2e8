//! The transport's own error estimate: the set-up lights the scene from validation lights of
//! its own (free points drawn from its seed, never a query's position), solves their later
//! bounces exactly by local solves, and compares.

use flatland_geom::{Kernel, PointLight};
use flatland_solve::{DirectLight, LightBuffers, Mesh};
use rayon::prelude::*;

use crate::Columns;
use crate::free::free_points;
use crate::local::{Block, Workspace};
use crate::{ErrorEstimate, Move, QueryBuffers, Stop, TransportError, lit_source};

/// Clearance a validation light keeps from every edge, as a fraction of the free way it was
/// drawn on (see `free_points`).
const MARGIN: f64 = 0.05;

/// Threshold of the exact local solves the estimate compares with: far below any tolerance a
/// transport is built to.
pub(crate) const EXACT_SOLVE: f64 = 1e-8;

/// Validation lights: `count` free points drawn with `seed`'s own stream, unit power.
pub(crate) fn validation_lights(
    kernel: &Kernel,
    mesh: &Mesh,
    count: usize,
    seed: u64,
) -> Vec<PointLight> {
    let mut rng = flatland_solve::seeds::stream(seed, VALIDATION_STREAM);
    free_points(kernel, mesh, count, MARGIN, &mut rng)
        .into_iter()
        .map(|at| PointLight { at, power: 1.0 })
        .collect()
}

/// The stream of a seed the validation lights are drawn from.
const VALIDATION_STREAM: u64 = 0x7a11_d47e;

/// `later(move, buffers)` accumulates a form's `M₂ B₀` (unclamped) in `buffers`; measured on
/// `lights`, one at a time, `stop` polled per light.
pub(crate) fn estimate(
    kernel: &Kernel,
    mesh: &Mesh,
    columns: &Columns,
    lights: &[PointLight],
    stop: &Stop,
    later: &(dyn Fn(Move<'_>, &mut QueryBuffers) + Sync),
) -> Result<ErrorEstimate, TransportError> {
    let direct = DirectLight::new(kernel, mesh)?;
    let weights: Vec<f64> = mesh.elements().iter().map(|e| e.length).collect();
    let errors = lights
        .par_iter()
        .map_init(
            || {
                let buffers = (LightBuffers::default(), QueryBuffers::default());
                (Workspace::new(mesh.len()), buffers)
            },
            |(work, (view, query)), light| {
                if stop() {
                    return Err(TransportError::Interrupted);
                }
                let lights = std::slice::from_ref(light);
                let lit = lit_source(&direct, mesh, lights, view);
                let parts = Parts::solved(work, columns, &lit, mesh.len(), EXACT_SOLVE)?;
                let mut approximate = vec![0.0; mesh.len()];
                query.start(mesh.len());
                later(Move { lights, lit: &lit }, query);
                query.finish(&mut approximate, true);
                Ok(parts.errors(&approximate, &weights))
            },
        )
        .collect::<Result<Vec<[f64; 3]>, TransportError>>()?;
    Ok(summarize(&errors))
}

/// Mean and largest of per-light `[later, indirect, b]` errors.
pub(crate) fn summarize(errors: &[[f64; 3]]) -> ErrorEstimate {
    let count = errors.len().max(1) as f64;
    let mean = |k: usize| errors.iter().map(|e| e[k]).sum::<f64>() / count;
    let max = |k: usize| errors.iter().map(|e| e[k]).fold(0.0, f64::max);
    ErrorEstimate {
        lights: errors.len(),
        later_mean: mean(0),
        later_max: max(0),
        indirect_mean: mean(1),
        b_mean: mean(2),
        b_max: max(2),
    }
}

/// One lighting's exact parts, dense: B₀, `K B₀` and `M₂ B₀`.
pub(crate) struct Parts {
    pub direct: Vec<f64>,
    pub first: Vec<f64>,
    pub later: Vec<f64>,
}

impl Parts {
    /// The parts of `lit` by local solves to `tolerance` (exact to rounding at [`EXACT_SOLVE`]).
    pub fn solved(
        work: &mut Workspace,
        columns: &Columns,
        lit: &[(u32, f64)],
        n: usize,
        tolerance: f64,
    ) -> Result<Parts, TransportError> {
        let source = Block {
            width: 1,
            elements: lit.iter().map(|&(j, _)| j).collect(),
            values: lit.iter().map(|&(_, b)| b).collect(),
        };
        let once = work.apply(columns, &source);
        let twice = work.apply(columns, &once);
        let later = work.solve(columns, &twice, tolerance)?;
        let dense = |b: &Block| {
            let mut out = vec![0.0; n];
            for (&e, &v) in b.elements.iter().zip(&b.values) {
                out[e as usize] = v;
            }
            out
        };
        Ok(Parts {
            direct: dense(&source),
            first: dense(&once),
            later: dense(&later),
        })
    }

    /// `[later, indirect, b]` relative errors of `approximate` later bounces.
    pub fn errors(&self, approximate: &[f64], weights: &[f64]) -> [f64; 3] {
        let mut sums = [0.0; 4];
        for i in 0..approximate.len() {
            let w = weights[i];
            let error = approximate[i] - self.later[i];
            let indirect = self.first[i] + self.later[i];
            sums[0] += w * error * error;
            sums[1] += w * self.later[i] * self.later[i];
            sums[2] += w * indirect * indirect;
            sums[3] += w * (self.direct[i] + indirect).powi(2);
        }
        let relative = |d: f64| if d > 0.0 { (sums[0] / d).sqrt() } else { 0.0 };
        [relative(sums[1]), relative(sums[2]), relative(sums[3])]
    }
}
