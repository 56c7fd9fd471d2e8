//! Learning driven by the light that flows: the default learner alternates solving and learning
//! until the lit scene meets a tolerance (docs/ALGORITHM.md §4a).
//!
//! The paper weights what is learned by the first shot `E'` only; its future work is to couple
//! the learner to the energy transfer. Here the coupling is the loop itself. On a mesh of the
//! scene the operator is kept by blocks (a receiver element, a sending edge; [`Blocks`]). A
//! block the model has not learned stands in as its unoccluded transfer times the receiving
//! row's prior — the light that row can still gather, spread over what it has not resolved —
//! so no unlearned face passes or blocks light by accident: an unresolved row gathers exactly
//! what is physically left for it. Each **round**:
//!
//! 1. solves `B = E + K B` with the current operator (warm-started from the last round's B);
//! 2. estimates the error of `B − E` its unresolved blocks leave (each unresolved face's `V`
//!    taken as a coin of the row's prior: `E|V − p| = 2p(1 − p)`, propagated through
//!    `(I − K)⁻¹` by one more solve) and stops when it is within the tolerance;
//! 3. ranks the unresolved blocks by the light the prior sends through them — the sender's
//!    solved `B` × the receiver's `ρ` × `G`, as power — and resolves the largest, twice as
//!    many as the round before (near the tolerance, only as many as carry the share
//!    `1 − tol / (2 · estimate)` of that light): the geometry decides a pair outright where
//!    it can, and on a pair whose visibility varies each face the block sees costs one ray
//!    the first time any block meets it (a new cell), nothing after.
//!
//! Light that flows through doors into a dark room raises that room's B in the next solve, so
//! its walls' blocks rise in the ranking: the loop follows the bounces, not just the lamps.

mod blocks;
mod cells;
mod driver;

use std::time::Instant;

use flatland_geom::Kernel;
use flatland_solve::{Mesh, SolveParams, Stop, TransferOperator, solve_linear};

pub(crate) use blocks::{Blocks, Faces};
pub use cells::FaceCell;
pub use driver::LightFit;

use crate::FitError;

/// Settings of the loop, checked by [`LightParams::check`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightParams {
    /// Stop when the estimated relative L2 error of the solved `B − E` (against the exact
    /// kernel on the same mesh) is at most this. Valid: (0, 1).
    pub tolerance: f64,
    /// Blocks resolved in the first round; each round resolves twice as many as the last.
    /// Valid: ≥ 1.
    pub first_round: usize,
    /// Stop after this many rays. Valid: ≥ 1.
    pub max_rays: u64,
    /// Stop after this many seconds (checked between rounds). Valid: > 0.
    pub max_seconds: f64,
}

impl Default for LightParams {
    fn default() -> Self {
        LightParams {
            tolerance: 0.01,
            first_round: 256,
            max_rays: u64::MAX,
            max_seconds: f64::INFINITY,
        }
    }
}

impl LightParams {
    /// Checks every field; the error names it and its valid range.
    pub fn check(&self) -> Result<(), FitError> {
        let bad = |name: &'static str, value: String, valid: &'static str| {
            Err(FitError::InvalidParameter { name, value, valid })
        };
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("tolerance", self.tolerance.to_string(), "in (0, 1)");
        }
        if self.first_round == 0 {
            return bad("first_round", "0".into(), "at least 1");
        }
        if self.max_rays == 0 {
            return bad("max_rays", "0".into(), "at least 1");
        }
        if self.max_seconds.is_nan() || self.max_seconds <= 0.0 {
            return bad("max_seconds", self.max_seconds.to_string(), "more than 0");
        }
        Ok(())
    }
}

/// Why the loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightStop {
    /// The estimated error is within the tolerance.
    Tolerance,
    /// Every block is resolved: the learned operator is the exact one on this mesh.
    Exact,
    /// The ray budget ran out.
    Rays,
    /// The time budget ran out.
    Time,
}

/// One round as it ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Round {
    /// Rays cast so far.
    pub rays: u64,
    /// Blocks resolved so far.
    pub resolved: usize,
    /// The estimated relative L2 error of `B − E` after this round's solve.
    pub estimated_error: f64,
    /// Seconds since the loop started.
    pub seconds: f64,
}

/// The loop on one mesh, generic over where face visibility is learned (the model).
#[derive(Clone)]
pub(crate) struct LightLoop<F: Faces> {
    blocks: Blocks,
    faces: F,
    radiosity: Vec<f64>,
    priors: Vec<f64>,
    rays: u64,
    next_round: usize,
    started: Instant,
    history: Vec<Round>,
}

impl<F: Faces> LightLoop<F> {
    /// The loop on `mesh`, every block unresolved; no ray yet.
    pub(crate) fn new(
        kernel: &Kernel,
        mesh: &Mesh,
        faces: F,
        params: &LightParams,
        stop: &Stop,
    ) -> Result<Self, FitError> {
        params.check()?;
        let blocks = Blocks::new(kernel, mesh, stop)?;
        let priors = blocks.priors();
        Ok(LightLoop {
            blocks,
            faces,
            radiosity: mesh.emission(),
            priors,
            rays: 0,
            next_round: params.first_round,
            started: Instant::now(),
            history: Vec::new(),
        })
    }

    /// Solves with the current operator and estimates its error; then, unless that meets
    /// `params` or a budget ran out, resolves the next blocks. `None` while it goes on.
    pub(crate) fn round(
        &mut self,
        kernel: &Kernel,
        mesh: &Mesh,
        params: &LightParams,
        solve: &SolveParams,
        stop: &Stop,
    ) -> Result<Option<LightStop>, FitError> {
        let emission = mesh.emission();
        let op = self.blocks.operator(mesh, &self.priors);
        let warm = std::mem::take(&mut self.radiosity);
        self.radiosity = solve_linear(&op, &emission, warm, solve, stop)?.radiosity;
        let estimated_error = self.estimate(mesh, &op, solve, stop)?;
        self.history.push(Round {
            rays: self.rays,
            resolved: self.blocks.len() - self.blocks.unresolved(),
            estimated_error,
            seconds: self.started.elapsed().as_secs_f64(),
        });
        if let Some(reason) = self.should_stop(estimated_error, params) {
            return Ok(Some(reason));
        }
        // Near the tolerance, resolve only the light it takes to get there (with a margin:
        // the estimate falls more slowly than the light resolved, as priors move).
        let share = (1.0 - 0.5 * params.tolerance / estimated_error).clamp(0.0, 1.0);
        let which =
            self.blocks
                .most_light(mesh, &self.priors, &self.radiosity, self.next_round, share);
        self.rays += self
            .blocks
            .resolve(kernel, mesh, &which, &mut self.faces, stop)?;
        self.priors = self.blocks.priors();
        self.next_round = self.next_round.saturating_mul(2);
        Ok(None)
    }

    fn should_stop(&self, estimated_error: f64, params: &LightParams) -> Option<LightStop> {
        if self.blocks.unresolved() == 0 {
            Some(LightStop::Exact)
        } else if estimated_error <= params.tolerance {
            Some(LightStop::Tolerance)
        } else if self.rays >= params.max_rays {
            Some(LightStop::Rays)
        } else if self.started.elapsed().as_secs_f64() >= params.max_seconds {
            Some(LightStop::Time)
        } else {
            None
        }
    }

    /// The relative L2 error of `B − E` the unresolved blocks are expected to leave: their
    /// expected error per row (`Blocks::unresolved_error`), carried through the bounces by
    /// `(I − K)⁻¹`, over `‖B − E‖` (element lengths as weights).
    fn estimate(
        &self,
        mesh: &Mesh,
        op: &dyn TransferOperator,
        solve: &SolveParams,
        stop: &Stop,
    ) -> Result<f64, FitError> {
        let delta = self
            .blocks
            .unresolved_error(mesh, &self.priors, &self.radiosity);
        if delta.iter().all(|&d| d == 0.0) {
            return Ok(0.0);
        }
        let spread = solve_linear(op, &delta, delta.clone(), solve, stop)?.radiosity;
        let norm = |v: &mut dyn Iterator<Item = f64>| -> f64 {
            v.zip(mesh.elements())
                .map(|(x, e)| x * x * e.length)
                .sum::<f64>()
                .sqrt()
        };
        let emission = mesh.emission();
        let reflected = norm(&mut self.radiosity.iter().zip(&emission).map(|(b, e)| b - e));
        let error = norm(&mut spread.iter().copied());
        Ok(if reflected > 0.0 {
            error / reflected
        } else {
            f64::INFINITY
        })
    }

    /// The last solved B per element.
    pub(crate) fn radiosity(&self) -> &[f64] {
        &self.radiosity
    }

    /// Rays cast so far.
    pub(crate) fn rays(&self) -> u64 {
        self.rays
    }

    /// Every round so far.
    pub(crate) fn history(&self) -> &[Round] {
        &self.history
    }

    /// The rows' priors for the unresolved blocks.
    pub(crate) fn priors(&self) -> &[f64] {
        &self.priors
    }

    /// Where face visibility is learned.
    pub(crate) fn faces(&self) -> &F {
        &self.faces
    }

    /// The block structure.
    pub(crate) fn blocks(&self) -> &Blocks {
        &self.blocks
    }
}

#[cfg(test)]
pub(crate) mod test_support {
    //! A face store without a network: one ray per face, remembered by its key. The loop's
    //! behaviour with it is what the model must reproduce.
    use std::sync::Arc;

    use flatland_geom::Kernel;
    use foldhash::HashMap;
    use rayon::prelude::*;

    use super::Faces;
    use crate::FitError;
    use crate::visibility::FaceKey;

    pub(crate) struct RayFaces {
        pub kernel: Arc<Kernel>,
        pub known: HashMap<FaceKey, f64>,
    }

    impl RayFaces {
        pub(crate) fn new(kernel: Arc<Kernel>) -> RayFaces {
            RayFaces {
                kernel,
                known: HashMap::default(),
            }
        }

        /// The face of the ray `(s, t)`, as the model would file it.
        pub(crate) fn key(&self, s: f64, t: f64) -> Option<FaceKey> {
            FaceKey::at(&self.kernel, &self.kernel.unoccluded(s, t))
        }
    }

    impl Faces for RayFaces {
        fn known(&self, key: &FaceKey) -> Option<f64> {
            self.known.get(key).copied()
        }

        fn learn(&mut self, rays: &[(FaceKey, [f64; 2])]) -> Result<u64, FitError> {
            let kernel = &self.kernel;
            let learned: Vec<f64> = rays
                .par_iter()
                .map(|(_, [s, t])| {
                    if kernel.eval(*s, *t).visible {
                        1.0
                    } else {
                        0.0
                    }
                })
                .collect();
            for ((key, _), v) in rays.iter().zip(learned) {
                self.known.entry(key.clone()).or_insert(v);
            }
            Ok(rays.len() as u64)
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use flatland_geom::{Kernel, generate};
    use flatland_solve::{
        ExactReference, Mesh, SolveParams, exact_operator, never, solve_errors, solve_operator,
    };

    use super::test_support::RayFaces;
    use super::*;

    fn floor_plan() -> (Arc<Kernel>, Mesh) {
        let kernel = Arc::new(Kernel::new(generate::floor_plan(150, 4).unwrap()));
        let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
        (kernel, mesh)
    }

    fn run(
        kernel: &Arc<Kernel>,
        mesh: &Mesh,
        params: &LightParams,
    ) -> (LightLoop<RayFaces>, LightStop) {
        let faces = RayFaces::new(Arc::clone(kernel));
        let mut light = LightLoop::new(kernel, mesh, faces, params, &never).unwrap();
        let solve = SolveParams::default();
        loop {
            if let Some(stop) = light.round(kernel, mesh, params, &solve, &never).unwrap() {
                return (light, stop);
            }
        }
    }

    /// Resolved to a tolerance of 1e-12, the learned operator is the exact one: the same B as
    /// the exact kernel's solve on the same mesh. It may stop before every block is resolved:
    /// in a closed scene a row whose prior is 0 or 1 is certain (its resolved light already
    /// fills ρ, or its unresolved blocks can only all be clear), and its estimate is 0.
    #[test]
    fn resolving_every_block_gives_the_exact_solution() {
        let (kernel, mesh) = floor_plan();
        let params = LightParams {
            tolerance: 1e-12,
            ..LightParams::default()
        };
        let (light, stop) = run(&kernel, &mesh, &params);
        let estimate = light.history().last().unwrap().estimated_error;
        assert!(
            stop == LightStop::Exact || (stop == LightStop::Tolerance && estimate <= 1e-12),
            "{stop:?}, estimate {estimate}"
        );
        let exact = solve_operator(
            &exact_operator(&kernel, &mesh, &never).unwrap(),
            &mesh,
            &SolveParams::default(),
            &never,
        )
        .unwrap();
        let errors = solve_errors(&mesh, light.radiosity(), &exact.radiosity);
        assert!(errors.rel_l2_reflected < 1e-9, "{errors:?}");
    }

    /// Stopped at the default tolerance, the measured error against the exact solve on the
    /// same mesh is near the learner's own estimate, and far fewer rays were cast than faces
    /// an exact resolution meets.
    #[test]
    fn the_estimate_tracks_the_measured_error_at_the_tolerance() {
        let (kernel, mesh) = floor_plan();
        let params = LightParams::default();
        let (light, stop) = run(&kernel, &mesh, &params);
        assert_eq!(stop, LightStop::Tolerance, "{:?}", light.history());
        let exact = solve_operator(
            &exact_operator(&kernel, &mesh, &never).unwrap(),
            &mesh,
            &SolveParams::default(),
            &never,
        )
        .unwrap();
        let measured = solve_errors(&mesh, light.radiosity(), &exact.radiosity).rel_l2_reflected;
        let estimated = light.history().last().unwrap().estimated_error;
        assert!(estimated <= params.tolerance);
        assert!(
            measured <= 3.0 * params.tolerance,
            "measured {measured}, estimated {estimated}"
        );
        let _ = ExactReference::default_elements(mesh.len());
    }

    /// The faces the blocks name are the faces the model files a cell of that ray under.
    #[test]
    fn a_pieces_face_is_the_face_of_its_ray() {
        let (kernel, mesh) = floor_plan();
        let faces = RayFaces::new(Arc::clone(&kernel));
        let blocks = Blocks::new(&kernel, &mesh, &never).unwrap();
        let mut checked = 0;
        for q in (0..blocks.len()).step_by(7) {
            for (face, [s, t], length) in blocks.pieces_of(&kernel, &mesh, q) {
                if length > 1e-9 {
                    assert_eq!(
                        Some(&face),
                        faces.key(s, t).as_ref(),
                        "block {q}, ray ({s}, {t})"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked} pieces checked");
    }

    /// The operator never gathers more than a row can receive, whatever is resolved: no light
    /// is made, and B is never negative.
    #[test]
    fn rows_never_gather_more_than_rho_and_b_stays_physical() {
        let (kernel, mesh) = floor_plan();
        let faces = RayFaces::new(Arc::clone(&kernel));
        let params = LightParams::default();
        let mut light = LightLoop::new(&kernel, &mesh, faces, &params, &never).unwrap();
        let solve = SolveParams::default();
        for _ in 0..4 {
            let ones = vec![1.0; mesh.len()];
            let mut sums = vec![0.0; mesh.len()];
            light
                .blocks()
                .operator(&mesh, &light.priors)
                .apply(&ones, &mut sums);
            for (i, s) in sums.iter().enumerate() {
                let rho = mesh.edge_of(i).reflectance;
                assert!(
                    *s <= rho * (1.0 + 1e-12) && *s >= 0.0,
                    "row {i}: {s} > ρ = {rho}"
                );
            }
            if light
                .round(&kernel, &mesh, &params, &solve, &never)
                .unwrap()
                .is_some()
            {
                break;
            }
            assert!(light.radiosity().iter().all(|&b| b >= -1e-12));
        }
    }
}
