//! `Transport`: the later bounces of one scene and mesh, built once, queried per move.

use std::time::Instant;

use flatland_geom::Kernel;
use flatland_solve::{Mesh, SparseOperator, TransferOperator};
use serde::{Deserialize, Serialize};

use crate::clusters::Clusters;
use crate::estimate::{ErrorEstimate, estimate, validation_lights};
use crate::local::Paths;
use crate::lowrank::{BlockTolerance, LowRank, build_blocks};
use crate::{Columns, Stop, TransportError, TransportParams};

/// The later bounces `M₂ = K² (I − K)⁻¹` of one scene on one mesh, in a form that answers
/// `M₂ B₀` for a light's direct light B₀ in a fraction of a millisecond.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Transport {
    pub(crate) params: TransportParams,
    pub(crate) identity: MeshIdentity,
    pub(crate) form: LowRank,
    pub(crate) estimate: ErrorEstimate,
    pub(crate) setup_s: f64,
}

/// What a model belongs to: the scene (its fingerprint), the element count and a hash of the
/// elements' parameter intervals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct MeshIdentity {
    pub scene: u64,
    pub elements: usize,
    pub mesh: u64,
}

impl MeshIdentity {
    pub fn of(mesh: &Mesh) -> MeshIdentity {
        // FNV-1a over the bits of every element's interval and reflectance.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut write = |v: f64| {
            for byte in v.to_bits().to_le_bytes() {
                h ^= u64::from(byte);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for (i, e) in mesh.elements().iter().enumerate() {
            write(e.s[0]);
            write(e.s[1]);
            write(mesh.edge_of(i).reflectance);
        }
        MeshIdentity {
            scene: mesh.fingerprint(),
            elements: mesh.len(),
            mesh: h,
        }
    }
}

impl Transport {
    /// Builds the later bounces of `kernel`'s scene on `mesh` from its exact `operator` (the
    /// sweep's, [`flatland_solve::sweep_operator`]): clusters of elements, each cluster's block
    /// of `M₂` by local solves, compressed to `params.tolerance` (and `params.budget`), then
    /// its own error estimate from `params.validation_lights` lights. `stop` is polled per
    /// cluster. Errors: parameters out of range, an operator of another size, light that does
    /// not die out.
    pub fn build(
        kernel: &Kernel,
        mesh: &Mesh,
        operator: &SparseOperator,
        params: &TransportParams,
        stop: &Stop,
    ) -> Result<Transport, TransportError> {
        params.check()?;
        flatland_solve::check_scene(kernel, mesh)?;
        if operator.len() != mesh.len() {
            return Err(TransportError::LengthMismatch {
                what: "the operator",
                found: operator.len(),
                expected: mesh.len(),
            });
        }
        let started = Instant::now();
        let columns = Columns::of(operator);
        let paths = Paths {
            rows: operator,
            columns: &columns,
        };
        let clusters = Clusters::spatial(mesh, params.cluster_elements);
        let tolerance = BlockTolerance {
            block: params.tolerance,
            solve: params.solve_tolerance,
        };
        let blocks = build_blocks(paths, &clusters, tolerance, stop)?;
        let mut form = LowRank { clusters, blocks };
        if let Some(budget) = params.budget {
            form.fit_budget(budget);
        }
        let lights = validation_lights(kernel, mesh, params.validation_lights, params.seed);
        let estimate = estimate(kernel, mesh, paths, &lights, &|lit, out| {
            form.apply_sparse(lit, out);
        })?;
        Ok(Transport {
            params: *params,
            identity: MeshIdentity::of(mesh),
            form,
            estimate,
            setup_s: started.elapsed().as_secs_f64(),
        })
    }

    /// Adds `M₂ B₀` to `out` (length N) for B₀ given by its non-zero entries `(element,
    /// value)` — what a point light lights: one room and what it sees through doors.
    /// Elements past N are an error.
    pub fn add_later_bounces(
        &self,
        lit: &[(u32, f64)],
        out: &mut [f64],
    ) -> Result<(), TransportError> {
        let n = self.identity.elements;
        if out.len() != n {
            return Err(TransportError::LengthMismatch {
                what: "the output",
                found: out.len(),
                expected: n,
            });
        }
        if let Some(&(j, _)) = lit.iter().find(|&&(j, _)| j as usize >= n) {
            return Err(TransportError::InvalidParameter {
                name: "B₀",
                value: format!("an entry for element {j}"),
                valid: "entries for elements of the mesh the model was built on",
            });
        }
        self.form.apply_sparse(lit, out);
        Ok(())
    }

    /// `M₂ B₀` for a dense B₀ (length N).
    pub fn later_bounces(&self, b0: &[f64]) -> Result<Vec<f64>, TransportError> {
        let n = self.identity.elements;
        if b0.len() != n {
            return Err(TransportError::LengthMismatch {
                what: "B₀",
                found: b0.len(),
                expected: n,
            });
        }
        let lit: Vec<(u32, f64)> = b0
            .iter()
            .enumerate()
            .filter(|&(_, &b)| b != 0.0)
            .map(|(j, &b)| (j as u32, b))
            .collect();
        let mut out = vec![0.0; n];
        self.form.apply_sparse(&lit, &mut out);
        Ok(out)
    }

    /// The model's own error estimate, from lights it drew itself.
    #[must_use]
    pub fn estimated_error(&self) -> ErrorEstimate {
        self.estimate
    }

    /// Bytes the model holds (what a query reads; the file is about 4/3 of it).
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.form.bytes()
    }

    /// Seconds the set-up took.
    #[must_use]
    pub fn setup_s(&self) -> f64 {
        self.setup_s
    }

    /// The parameters it was built with.
    #[must_use]
    pub fn params(&self) -> &TransportParams {
        &self.params
    }

    /// Clusters and the mean rank of their blocks.
    #[must_use]
    pub fn shape(&self) -> (usize, f64, f64) {
        let blocks = &self.form.blocks;
        let ranks: usize = blocks.iter().map(|b| b.rank()).sum();
        let rows: usize = blocks.iter().map(|b| b.rows.len()).sum();
        let count = blocks.len().max(1) as f64;
        (blocks.len(), ranks as f64 / count, rows as f64 / count)
    }
}
