//! [`LightFit`]: the light-driven learner as a user runs it — rounds on one mesh until the lit
//! scene meets its tolerance.

use std::sync::Arc;
use std::time::Instant;

use flatland_geom::Kernel;
use flatland_solve::{Mesh, SolveParams, Stop, Sweep, TransferOperator, solve_linear};

use super::probes::{ProbeCell, Probes};
use super::rows::Rows;
use super::{LightParams, LightStop, Round, borrow, probe};
use crate::{LightError, LightEstimate};

/// Relative residual of a round's solve: the ranking and the estimate need a few digits of B,
/// not ten; the round that stops polishes its B to the solve's own tolerance.
const ROUND_TOLERANCE: f64 = 1e-7;
/// Relative residual of the estimate's solve: the estimate is a figure of one or two digits.
const ESTIMATE_TOLERANCE: f64 = 1e-3;

/// A light-driven fit of one scene on one mesh (see the crate docs and docs/ALGORITHM.md
/// §4a): [`LightFit::round`] or [`LightFit::run`], then read the solved
/// radiosity, the estimated error and the cells, or solve with it as a
/// [`Representation`](flatland_solve::Representation).
///
/// ```
/// use std::sync::Arc;
/// use flatland_geom::{Kernel, generate};
/// use flatland_solve::{Mesh, never};
/// use flatland_light::{LightFit, LightParams};
///
/// let kernel = Arc::new(Kernel::new(generate::floor_plan(80, 1).unwrap()));
/// let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
/// let mut fit = LightFit::new(kernel, mesh, LightParams::default()).unwrap();
/// let stopped = fit.run(&never, |_| {}).unwrap();
/// let last = fit.history().last().unwrap();
/// assert!(last.estimated_error <= 0.01 || stopped != flatland_light::LightStop::Tolerance);
/// assert!(fit.radiosity().iter().all(|&b| b >= 0.0));
/// ```
#[derive(Clone)]
pub struct LightFit {
    pub(super) kernel: Arc<Kernel>,
    pub(super) mesh: Mesh,
    params: LightParams,
    solve: SolveParams,
    sweep: Sweep,
    pub(super) probes: Probes,
    /// Shared with the operators handed out, copied only if one is alive when rows change.
    pub(super) rows: Arc<Rows>,
    radiosity: Vec<f64>,
    next_round: usize,
    started: Instant,
    history: Vec<Round>,
    stopped: Option<LightStop>,
}

impl LightFit {
    /// The fit of `kernel` on `mesh` (a mesh of the same scene): no probe yet. Builds the
    /// sweep's hierarchy of the scene's edges (`O(n log n)`).
    pub fn new(
        kernel: Arc<Kernel>,
        mesh: Mesh,
        params: LightParams,
    ) -> Result<LightFit, LightError> {
        params.check()?;
        let sweep = Sweep::new(&kernel, &mesh)?;
        Ok(LightFit {
            probes: Probes::new(&mesh),
            rows: Arc::new(Rows::new(mesh.len())),
            radiosity: mesh.emission(),
            kernel,
            mesh,
            params,
            solve: SolveParams::default(),
            sweep,
            next_round: params.first_round,
            started: Instant::now(),
            history: Vec::new(),
            stopped: None,
        })
    }

    /// One round: (the first time, probe both ends of every section;) solve, estimate, and
    /// unless the estimate meets the tolerance or a budget ran out, probe the gaps the most
    /// uncertain light flows through. `Some` once it has stopped; later calls return the same
    /// reason and do nothing.
    pub fn round(&mut self, stop: &Stop) -> Result<Option<LightStop>, LightError> {
        if self.stopped.is_some() {
            return Ok(self.stopped);
        }
        if self.probes.len() == 0 {
            self.first_probes(stop)?;
        }
        let emission = self.mesh.emission();
        let warm = std::mem::take(&mut self.radiosity);
        let rough = SolveParams {
            tolerance: ROUND_TOLERANCE.max(self.solve.tolerance),
            ..self.solve
        };
        self.radiosity = solve_linear(&*self.rows, &emission, warm, &rough, stop)?.radiosity;
        let doubt = self.rows.doubt(&self.radiosity);
        let estimated_error = self.estimate(&doubt, stop)?;
        self.history.push(Round {
            cells: self.probes.len(),
            estimated_error,
            seconds: self.started.elapsed().as_secs_f64(),
        });
        self.stopped = self.should_stop(estimated_error);
        if self.stopped.is_some() {
            let rough = std::mem::take(&mut self.radiosity);
            self.radiosity =
                solve_linear(&*self.rows, &emission, rough, &self.solve, stop)?.radiosity;
        } else {
            self.refine(&doubt, estimated_error, stop)?;
        }
        Ok(self.stopped)
    }

    /// Rounds until it stops; `on_round` sees the fit after each (the viewer's snapshots).
    pub fn run(
        &mut self,
        stop: &Stop,
        mut on_round: impl FnMut(&LightFit),
    ) -> Result<LightStop, LightError> {
        loop {
            let stopped = self.round(stop)?;
            on_round(self);
            if let Some(reason) = stopped {
                return Ok(reason);
            }
        }
    }

    /// The probes of the first round and every row they bracket.
    fn first_probes(&mut self, stop: &Stop) -> Result<(), LightError> {
        let first = self.probes.first();
        let rows = Arc::make_mut(&mut self.rows);
        probe(
            &self.sweep,
            &self.mesh,
            &first,
            &mut self.probes,
            rows,
            stop,
        )?;
        let all: Vec<usize> = (0..self.mesh.len()).collect();
        borrow(&self.sweep, &self.mesh, &all, &self.probes, rows, stop)
    }

    fn should_stop(&self, estimated_error: f64) -> Option<LightStop> {
        if self.probes.complete() || !self.rows.doubtful() {
            Some(LightStop::Exact)
        } else if estimated_error <= self.params.tolerance {
            Some(LightStop::Tolerance)
        } else if self.probes.len() >= self.params.max_cells {
            Some(LightStop::Cells)
        } else if self.started.elapsed().as_secs_f64() >= self.params.max_seconds {
            Some(LightStop::Time)
        } else {
            None
        }
    }

    /// The relative L2 error of `B − E` the rows' doubt leaves: each row's uncertain light
    /// `doubt`, carried through the bounces by `(I − K)⁻¹`, over `‖B − E‖` (element lengths
    /// as weights).
    fn estimate(&self, doubt: &[f64], stop: &Stop) -> Result<f64, LightError> {
        if doubt.iter().all(|&d| d == 0.0) {
            return Ok(0.0);
        }
        let loose = SolveParams {
            tolerance: ESTIMATE_TOLERANCE.max(self.solve.tolerance),
            ..self.solve
        };
        let spread = solve_linear(&*self.rows, doubt, doubt.to_vec(), &loose, stop)?.radiosity;
        let elements = self.mesh.elements();
        let norm = |v: &mut dyn Iterator<Item = f64>| -> f64 {
            v.zip(elements)
                .map(|(x, e)| x * x * e.length)
                .sum::<f64>()
                .sqrt()
        };
        let emission = self.mesh.emission();
        let reflected = norm(&mut self.radiosity.iter().zip(&emission).map(|(b, e)| b - e));
        let error = norm(&mut spread.iter().copied());
        Ok(if reflected > 0.0 {
            error / reflected
        } else {
            f64::INFINITY
        })
    }

    /// Probes the middle of the gaps the most uncertain power flows through, and rebuilds
    /// the rows of those gaps.
    fn refine(
        &mut self,
        doubt: &[f64],
        estimated_error: f64,
        stop: &Stop,
    ) -> Result<(), LightError> {
        let elements = self.mesh.elements();
        let mut gaps: Vec<(f64, usize, usize)> = self
            .probes
            .gaps()
            .map(|(l, r)| {
                let power = (l + 1..r).map(|i| doubt[i] * elements[i].length).sum();
                (power, l, r)
            })
            .filter(|g| g.0 > 0.0)
            .collect();
        let room = self.params.max_cells.saturating_sub(self.probes.len());
        let count = self.next_round.min(room).min(gaps.len());
        if count == 0 {
            return Ok(());
        }
        let total: f64 = gaps.iter().map(|g| g.0).sum();
        let by_power = |x: &(f64, usize, usize), y: &(f64, usize, usize)| {
            y.0.total_cmp(&x.0).then(x.1.cmp(&y.1))
        };
        gaps.select_nth_unstable_by(count - 1, by_power);
        gaps.truncate(count);
        gaps.sort_unstable_by(by_power);
        // Near the tolerance, only the power it takes to get there (with a margin: the
        // estimate falls more slowly than the power probed, as rows change).
        let share = (1.0 - 0.5 * self.params.tolerance / estimated_error).clamp(0.0, 1.0);
        let mut covered = 0.0;
        let enough = gaps
            .iter()
            .position(|g| {
                covered += g.0;
                covered >= share * total
            })
            .map_or(count, |k| k + 1);
        gaps.truncate(enough);
        let new: Vec<usize> = gaps.iter().map(|&(_, l, r)| (l + r) / 2).collect();
        let rebuilt: Vec<usize> = gaps.iter().flat_map(|&(_, l, r)| l + 1..r).collect();
        let rows = Arc::make_mut(&mut self.rows);
        probe(&self.sweep, &self.mesh, &new, &mut self.probes, rows, stop)?;
        borrow(&self.sweep, &self.mesh, &rebuilt, &self.probes, rows, stop)?;
        self.next_round = self.next_round.saturating_mul(2);
        Ok(())
    }

    /// The settings it runs with.
    pub fn params(&self) -> &LightParams {
        &self.params
    }

    /// Changes the stop rules (tolerance, budgets) of a fit that may be running; a fit that
    /// had stopped goes on if the new ones ask for more.
    pub fn set_params(&mut self, params: LightParams) -> Result<(), LightError> {
        params.check()?;
        self.params = params;
        if self.stopped != Some(LightStop::Exact) {
            self.stopped = None;
        }
        Ok(())
    }

    /// The mesh it learns on.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The kernel it learns.
    pub fn kernel(&self) -> &Arc<Kernel> {
        &self.kernel
    }

    /// B per element from the last round's solve (the emission before the first round).
    pub fn radiosity(&self) -> &[f64] {
        &self.radiosity
    }

    /// Every round so far, as it ended.
    pub fn history(&self) -> &[Round] {
        &self.history
    }

    /// The estimated relative L2 error of the solved `B − E` against the exact solve on the
    /// same mesh, after the last round.
    pub fn estimated_error(&self) -> Option<f64> {
        self.history.last().map(|r| r.estimated_error)
    }

    /// [`LightFit::estimated_error`] with what it covers; add the mesh's own error with
    /// [`LightEstimate::with_discretization`].
    pub fn error_estimate(&self) -> Option<LightEstimate> {
        self.estimated_error()
            .map(|e| LightEstimate::on_mesh(e, self.mesh.len()))
    }

    /// Why it stopped, once it has.
    pub fn stopped(&self) -> Option<LightStop> {
        self.stopped
    }

    /// The cells so far, one per probe, in the order probed (the order the light led the
    /// learner to them).
    pub fn cells(&self) -> Vec<ProbeCell> {
        self.probes.cells(&self.mesh)
    }

    /// The stretches of the sender parameter `s` that cell `cell`'s point sees, `[s₀, s₁]`
    /// each: its row of the kernel where `V = 1`.
    pub fn seen(&self, cell: usize) -> Vec<[f64; 2]> {
        let edges = self.mesh.edges();
        self.probes
            .spans(cell)
            .iter()
            .map(|span| {
                let [s0, s1] = edges[span.edge as usize].s;
                [s0 + span.u[0] * (s1 - s0), s0 + span.u[1] * (s1 - s0)]
            })
            .collect()
    }

    /// Non-zero entries of the learned operator (what a solve with it multiplies per sweep).
    pub fn nonzeros(&self) -> usize {
        self.rows.nonzeros()
    }

    /// The learned operator on its own mesh, sharing the fit's rows.
    pub(super) fn own_operator(&self) -> Box<dyn TransferOperator> {
        Box::new(SharedRows(Arc::clone(&self.rows)))
    }
}

/// The rows of a fit, owned by a solve that may outlive the fit's borrow.
struct SharedRows(Arc<Rows>);

impl TransferOperator for SharedRows {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        self.0.apply(b, out);
    }
}
