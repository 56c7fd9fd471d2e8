//! The methods that relight a scene per move of its lights, behind one trait ([`Mover`]): the
//! exact re-solve, clustered HR re-solved with each move's source, the tracer at a time per
//! move, the learned transport of the later bounces, and a uniform grid of light-position
//! probes of the transport's bytes.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use flatland_baselines::{
    ClusteredParams, LightTracer, Lighting, TraceBudget, TraceParams, run_clustered,
};
use flatland_geom::{Kernel, PointLight};
use flatland_solve::{
    DirectLight, Mesh, RelightParams, Relighter, Representation, SolveParams, Stop,
    TransferOperator, solve_linear,
};

use flatland_transport::{
    LightProbes, ProbeParams, Transport, TransportParams, TransportRelighter,
};

use super::Method;

/// What a method did at one move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moved<'a> {
    /// B per element of the mesh (held by the method until its next move).
    pub radiosity: &'a [f64],
    /// Its work: products with K (the re-solves), photons (the tracer).
    pub work: u64,
}

/// A method that relights one scene and mesh per move of its point lights: built once, then
/// [`Mover::relight`] per move. What `bench --relight` times; the learned transport is the
/// learned transport implements it too.
pub trait Mover {
    /// The method.
    fn method(&self) -> Method;
    /// What it runs at, in words (`tolerance 1e-6`, `1 000 000 links`).
    fn setting(&self) -> String;
    /// Seconds its set-up took.
    fn setup_s(&self) -> f64;
    /// Bytes it holds.
    fn bytes(&self) -> usize;
    /// B under `lights` (the scene's emitting edges on). `budget_s`: the time the move may
    /// take, for a method that runs to a time (the tracer); the others ignore it.
    fn relight(&mut self, lights: &[PointLight], budget_s: f64, stop: &Stop) -> Result<Moved<'_>>;
}

/// The exact re-solve ([`Relighter`]) at one tolerance.
pub struct ExactMover {
    relighter: Relighter,
}

impl ExactMover {
    /// The relighter of `kernel`'s scene on `mesh` at `params`.
    pub fn new(kernel: &Kernel, mesh: &Mesh, params: RelightParams, stop: &Stop) -> Result<Self> {
        let relighter = Relighter::new(kernel, mesh, params, stop)?;
        Ok(ExactMover { relighter })
    }

    /// The exact re-solve by `relighter`.
    pub fn of(relighter: Relighter) -> Self {
        ExactMover { relighter }
    }

    /// The same method on the same operator (shared) at `params`.
    pub fn with_params(&self, params: RelightParams) -> Result<Self> {
        let relighter = self.relighter.with_params(params)?;
        Ok(ExactMover { relighter })
    }

    /// The relighter (its operator, for a cold solve).
    pub fn relighter(&self) -> &Relighter {
        &self.relighter
    }
}

impl Mover for ExactMover {
    fn method(&self) -> Method {
        Method::Exact
    }

    fn setting(&self) -> String {
        format!("tolerance {:e}", self.relighter.params().tolerance)
    }

    fn setup_s(&self) -> f64 {
        self.relighter.setup_s()
    }

    fn bytes(&self) -> usize {
        self.relighter.memory_bytes()
    }

    fn relight(&mut self, lights: &[PointLight], _: f64, stop: &Stop) -> Result<Moved<'_>> {
        let relit = self.relighter.relight(lights, stop)?;
        Ok(Moved {
            radiosity: relit.radiosity,
            work: relit.cost.products as u64,
        })
    }
}

/// Clustered HR: its links built once; per move the exact direct light as the source (what
/// the links do not hold) and a re-solve with its operator from the last move's B.
pub struct ClusteredMover {
    mesh: Mesh,
    direct: DirectLight,
    op: Box<dyn TransferOperator>,
    links: usize,
    bytes: usize,
    setup_s: f64,
    last: Vec<f64>,
}

impl ClusteredMover {
    /// Clustered HR of `kernel`'s scene with `links` links, its operator on `mesh`.
    pub fn new(
        kernel: &Kernel,
        mesh: &Mesh,
        links: usize,
        params: &ClusteredParams,
        stop: &Stop,
    ) -> Result<Self> {
        let started = Instant::now();
        let run = run_clustered(kernel, links, 1, params)
            .with_context(|| format!("clustered HR at {links} links"))?;
        // Its oracle weighs a sender by E' (docs/ALGORITHM.md §2), the light it sends first:
        // 0 on every edge only of a scene nothing lights, where a row would pass off the
        // direct light alone as clustered HR's answer.
        anyhow::ensure!(
            run.basis_functions > 0,
            "clustered HR built no link: its refinement weighs senders by the light they send \
             first, and nothing lights this scene"
        );
        let op = run.approx.operator(mesh, &SolveParams::default(), stop)?;
        let direct = DirectLight::new(kernel, mesh)?;
        Ok(ClusteredMover {
            mesh: mesh.clone(),
            direct,
            op,
            links: run.basis_functions,
            bytes: run.memory_bytes,
            setup_s: started.elapsed().as_secs_f64(),
            last: Vec::new(),
        })
    }
}

impl Mover for ClusteredMover {
    fn method(&self) -> Method {
        Method::Clustered
    }

    fn setting(&self) -> String {
        format!("{} links", self.links)
    }

    fn setup_s(&self) -> f64 {
        self.setup_s
    }

    fn bytes(&self) -> usize {
        self.bytes
    }

    fn relight(&mut self, lights: &[PointLight], _: f64, stop: &Stop) -> Result<Moved<'_>> {
        let mesh = &self.mesh;
        let direct = self.direct.mean_irradiance(mesh, lights);
        let source: Vec<f64> = (0..mesh.len())
            .map(|i| mesh.edge_of(i).emission + mesh.edge_of(i).reflectance * direct[i])
            .collect();
        let start = if self.last.is_empty() {
            source.clone()
        } else {
            std::mem::take(&mut self.last)
        };
        let params = SolveParams {
            tolerance: RelightParams::default().tolerance,
            ..SolveParams::default()
        };
        let solved = solve_linear(self.op.as_ref(), &source, start, &params, stop)?;
        self.last = solved.radiosity;
        Ok(Moved {
            radiosity: &self.last,
            work: solved.iterations as u64,
        })
    }
}

/// The Monte Carlo tracer: each move traced from scratch for the time it is given.
pub struct TracerMover<'a> {
    tracer: LightTracer<'a>,
    seed: u64,
    setup_s: f64,
    bytes: usize,
    last: Vec<f64>,
}

impl<'a> TracerMover<'a> {
    /// The tracer of `kernel`'s scene on `mesh`; move `k` is traced with seed `seed + k`.
    pub fn new(kernel: &'a Kernel, mesh: &'a Mesh, seed: u64) -> Result<Self> {
        let started = Instant::now();
        let tracer = LightTracer::new(kernel, mesh)?;
        Ok(TracerMover {
            tracer,
            seed,
            setup_s: started.elapsed().as_secs_f64(),
            bytes: 0,
            last: Vec::new(),
        })
    }
}

impl Mover for TracerMover<'_> {
    fn method(&self) -> Method {
        Method::Tracer
    }

    fn setting(&self) -> String {
        "the exact re-solve's time per move".to_owned()
    }

    fn setup_s(&self) -> f64 {
        self.setup_s
    }

    fn bytes(&self) -> usize {
        self.bytes
    }

    fn relight(&mut self, lights: &[PointLight], budget_s: f64, stop: &Stop) -> Result<Moved<'_>> {
        let params = TraceParams {
            budget: TraceBudget::Seconds(budget_s.clamp(1e-6, 1e6)),
            seed: self.seed,
        };
        self.seed += 1;
        let lighting = Lighting::default().with_lights(lights.to_vec());
        let traced = self.tracer.trace(&lighting, &params, stop)?;
        self.bytes = self.bytes.max(traced.memory_bytes);
        self.last = traced.radiosity;
        Ok(Moved {
            radiosity: &self.last,
            work: traced.photons,
        })
    }
}

/// The learned transport of the later bounces ([`TransportRelighter`]): per move the exact
/// relighter's direct light and first bounce, the transport's `M₂ B₀`, no linear solve.
pub struct TransportMover {
    relit: TransportRelighter,
}

impl TransportMover {
    /// Builds the transport of `kernel`'s scene on `relighter`'s mesh and operator with
    /// `params` (the relighter is taken: a copy made by `Relighter::with_params` shares the
    /// operator).
    pub fn build(
        kernel: &Kernel,
        relighter: Relighter,
        params: &TransportParams,
        stop: &Stop,
    ) -> Result<Self> {
        let transport = Transport::build(kernel, relighter.mesh(), relighter.rows(), params, stop)
            .context("building the learned transport")?;
        TransportMover::new(kernel, relighter, transport, stop)
    }

    /// `transport` (built or loaded for `relighter`'s mesh: refused otherwise) on
    /// `relighter`.
    pub fn new(
        kernel: &Kernel,
        relighter: Relighter,
        transport: Transport,
        stop: &Stop,
    ) -> Result<Self> {
        let relit = TransportRelighter::new(kernel, relighter, transport, stop)?;
        Ok(TransportMover { relit })
    }

    /// The transport and the relighter it reads.
    pub fn relit(&self) -> &TransportRelighter {
        &self.relit
    }
}

impl Mover for TransportMover {
    fn method(&self) -> Method {
        Method::Transport
    }

    fn setting(&self) -> String {
        let t = self.relit.transport();
        let (clusters, rank, _) = t.shape();
        format!(
            "tolerance {}, {clusters} clusters of mean rank {rank:.1}",
            t.params().tolerance
        )
    }

    fn setup_s(&self) -> f64 {
        self.relit.setup_s()
    }

    fn bytes(&self) -> usize {
        self.relit.bytes()
    }

    fn relight(&mut self, lights: &[PointLight], _: f64, _: &Stop) -> Result<Moved<'_>> {
        let radiosity = self.relit.relight(lights)?;
        // No product with K: the work is the query's.
        Ok(Moved { radiosity, work: 0 })
    }
}

/// A uniform grid of light-position probes ([`LightProbes`], what game light-probe grids do) in
/// the place of the transport: per move the exact relighter's direct light and first bounce,
/// the probes' blend of `M₂ B₀` for the later bounces.
pub struct ProbeMover {
    relit: TransportRelighter<LightProbes>,
    budget: usize,
}

impl ProbeMover {
    /// Probes of `kernel`'s scene on `relighter`'s mesh and operator within `budget` bytes
    /// (the transport's, for a comparison at equal memory), placed on a uniform grid.
    pub fn build(
        kernel: &Arc<Kernel>,
        relighter: Relighter,
        budget: usize,
        stop: &Stop,
    ) -> Result<Self> {
        let params = ProbeParams::grid(budget);
        let probes = LightProbes::build(kernel, relighter.mesh(), relighter.rows(), &params, stop)
            .with_context(|| format!("building the probe grid of {budget} bytes"))?;
        let relit = TransportRelighter::with_form(kernel, relighter, probes, stop)?;
        Ok(ProbeMover { relit, budget })
    }
}

impl Mover for ProbeMover {
    fn method(&self) -> Method {
        Method::Probes
    }

    fn setting(&self) -> String {
        let probes = self.relit.transport();
        format!(
            "{} probes {:.2} apart in {:.1} MB",
            probes.len(),
            probes.spacing(),
            self.budget as f64 / 1e6
        )
    }

    fn setup_s(&self) -> f64 {
        self.relit.setup_s()
    }

    fn bytes(&self) -> usize {
        self.relit.bytes()
    }

    fn relight(&mut self, lights: &[PointLight], _: f64, _: &Stop) -> Result<Moved<'_>> {
        let radiosity = self.relit.relight(lights)?;
        Ok(Moved { radiosity, work: 0 })
    }
}
