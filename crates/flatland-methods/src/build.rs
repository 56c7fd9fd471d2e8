//! The one place each method's representation is built: what every command, experiment and the
//! viewer call, so a method is the same thing wherever its name appears.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

use flatland_baselines::{
    BaselineRun, BlockValue, ClusteredParams, DEFAULT_LINKS_PER_EDGE, HrParams, UniformParams,
    run_clustered, run_hr_at_budget, run_uniform,
};
use flatland_geom::Kernel;
use flatland_light::{LightEstimate, LightFit, LightParams, LightStop};
use flatland_solve::{Errors, Mesh, Reference, Representation, Stop};
use kernel_fit::{Fit, FitParams, FitSummary, LearnedKernel, REFERENCE_SEED};

use crate::{Method, MethodError};

/// Basis functions of the budgeted methods when none are asked for (clustered HR excepted: it
/// follows the scene, [`DEFAULT_LINKS_PER_EDGE`] links per edge).
pub const DEFAULT_BASIS: usize = 400;

/// Resolution of the ζ grid a network is measured on when the caller gives no reference: its
/// errors of ζ are then only a by-product (the lit scene is what is measured), so a small one.
const SMALL_ZETA_GRID: usize = 16;

/// How each method is built: its parameters, beside the knob a caller sets per build
/// ([`Ask`]). `Recipes::default()` is what `flatland solve` builds.
#[derive(Clone, Debug, PartialEq)]
pub struct Recipes {
    /// The light-driven learner (its tolerance and cell budget come from the [`Ask`]).
    pub light: LightParams,
    /// The visibility network (cells and seed come from the [`Ask`]).
    pub visibility: FitParams,
    /// The paper's network, refit included (cells and seed come from the [`Ask`]).
    pub paper: FitParams,
    /// Hierarchical radiosity.
    pub hr: HrParams,
    /// Hierarchical radiosity with clustering.
    pub clustered: ClusteredParams,
    /// The uniform grid (the block value follows the method: rays or exact means).
    pub uniform: UniformParams,
}

impl Default for Recipes {
    fn default() -> Self {
        Recipes {
            light: LightParams::default(),
            visibility: FitParams::default(),
            paper: FitParams::paper(),
            hr: HrParams::default(),
            clustered: ClusteredParams::default(),
            uniform: UniformParams::default(),
        }
    }
}

/// One build asked for: the method's knob and seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ask {
    /// The method.
    pub method: Method,
    /// Basis functions (cells, links, blocks); for the light-driven learner the most cells it
    /// may grow. `None`: [`DEFAULT_BASIS`], clustered HR's per-edge default, or no bound.
    pub basis: Option<usize>,
    /// The light-driven learner's tolerance on its estimated error of `B − E` (`None`: its
    /// default).
    pub tolerance: Option<f64>,
    /// The seed of a random method.
    pub seed: u64,
}

impl Ask {
    /// `method` with its defaults and seed 1.
    #[must_use]
    pub fn new(method: Method) -> Ask {
        Ask {
            method,
            basis: None,
            tolerance: None,
            seed: 1,
        }
    }
}

/// What a build reports as it goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// A network has this many cells of its target.
    Cells {
        /// Cells now.
        cells: usize,
        /// Cells it grows to.
        target: usize,
    },
    /// The light-driven learner has this many probes and, after its first round, an estimate.
    Probes {
        /// Probes (cells) placed.
        cells: usize,
        /// Its estimated error of `B − E`.
        estimate: Option<f64>,
    },
}

/// A representation built, what it cost, and what its learner says of it.
pub struct Built {
    /// The method built.
    pub method: Method,
    /// The representation.
    pub rep: Box<dyn Representation + Send>,
    /// Seconds the build took (learning, linking).
    pub build_s: f64,
    /// Rays cast building it (kernel evaluations; the light-driven learner's probes cast none).
    pub rays: u64,
    /// Why it is not what was asked for (a baseline below its initial linking, a grid that is
    /// not square).
    pub note: Option<String>,
    /// What its learner says of it.
    pub account: Account,
}

/// What a learner says of what it built.
#[derive(Clone, Debug)]
pub enum Account {
    /// A baseline or the exact kernel: nothing beyond the representation.
    None,
    /// The light-driven learner's own account.
    Light(LightAccount),
    /// A network's fit: its summary, and for the paper's network the model before its refit.
    Network(Box<NetworkAccount>),
}

/// The light-driven learner's account of its fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightAccount {
    /// Its estimate of the relative L2 error of the solved `B − E` (against the exact kernel on
    /// the same elements).
    pub estimated_error: Option<f64>,
    /// That estimate with what it covers, and the mesh's own error as a function added where
    /// the lit scene has it ([`Recipes::light`](crate::Recipes::light) adds it).
    pub estimate: Option<LightEstimate>,
    /// Rounds run.
    pub rounds: usize,
    /// Probes placed (exact views swept: its cells).
    pub probes: usize,
    /// Why it stopped.
    pub stopped: LightStop,
}

/// A network's account of its fit.
#[derive(Clone, Debug)]
pub struct NetworkAccount {
    /// How the fit ended.
    pub summary: FitSummary,
    /// The paper's network before its refit, with its errors of ζ then (`None` without a
    /// refit).
    pub before_refit: Option<(LearnedKernel, Errors)>,
}

impl Recipes {
    /// Builds what `ask` names on `kernel`; the light-driven learner learns on `mesh` (the
    /// solve's). Networks are measured on `zeta` (a small reference when `None`). `stop` is
    /// polled in the long loops; `progress` hears how a learner grows. The tracer is not a
    /// kernel and is refused ([`MethodError::NotAKernel`]).
    pub fn build(
        &self,
        ask: Ask,
        kernel: &Arc<Kernel>,
        mesh: &Mesh,
        zeta: Option<&Arc<Reference>>,
        stop: &Stop,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Built, MethodError> {
        if ask.basis == Some(0) {
            return Err(MethodError::InvalidParameter {
                name: "basis",
                value: "0".into(),
                valid: "at least 1",
            });
        }
        let started = Instant::now();
        let basis = ask.basis.unwrap_or(DEFAULT_BASIS);
        let seed = ask.seed;
        let mut built = match ask.method {
            Method::Exact => plain(ask.method, Arc::clone(kernel)),
            Method::Light => self.light_driven(ask, kernel, mesh, stop, progress)?,
            Method::Visibility | Method::Paper | Method::PaperNorefit => {
                self.network(ask, kernel, zeta, stop, progress)?
            }
            Method::Hr => baseline(ask.method, run_hr_at_budget(kernel, basis, seed, &self.hr)?),
            Method::Clustered => {
                // No initial linking sets its floor: the default follows the scene, as HR's
                // does through that linking.
                let links = ask
                    .basis
                    .unwrap_or(DEFAULT_LINKS_PER_EDGE * kernel.scene().edges().len());
                let run = run_clustered(kernel, links, seed, &self.clustered)?;
                baseline(ask.method, run)
            }
            Method::Uniform | Method::UniformExact => {
                let params = UniformParams {
                    block_value: if ask.method == Method::Uniform {
                        BlockValue::Rays
                    } else {
                        BlockValue::ExactKernelMean
                    },
                    ..self.uniform
                };
                baseline(ask.method, run_uniform(kernel, basis, seed, &params)?)
            }
            Method::Tracer => return Err(MethodError::NotAKernel(Method::Tracer.name())),
            Method::Transport | Method::Probes => return Err(ask.method.relight_only()),
        };
        if built.build_s == 0.0 {
            built.build_s = started.elapsed().as_secs_f64();
        }
        Ok(built)
    }

    /// The light-driven learner on `mesh`, to the tolerance or the cell budget asked.
    fn light_driven(
        &self,
        ask: Ask,
        kernel: &Arc<Kernel>,
        mesh: &Mesh,
        stop: &Stop,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Built, MethodError> {
        let params = LightParams {
            tolerance: ask.tolerance.unwrap_or(self.light.tolerance),
            max_cells: ask.basis.unwrap_or(self.light.max_cells),
            ..self.light
        };
        params.check()?;
        let started = Instant::now();
        let mut fit = LightFit::new(Arc::clone(kernel), mesh.clone(), params)?;
        let stopped = fit.run(stop, |f| {
            progress(Progress::Probes {
                cells: f.cells().len(),
                estimate: f.estimated_error(),
            });
        })?;
        let account = LightAccount {
            estimated_error: fit.estimated_error(),
            estimate: fit.error_estimate(),
            rounds: fit.history().len(),
            probes: fit.cells().len(),
            stopped,
        };
        Ok(Built {
            method: Method::Light,
            rep: Box::new(fit),
            build_s: started.elapsed().as_secs_f64(),
            rays: 0,
            note: None,
            account: Account::Light(account),
        })
    }

    /// A network trained to the cells asked, then finished (its refit, if it has one).
    fn network(
        &self,
        ask: Ask,
        kernel: &Arc<Kernel>,
        zeta: Option<&Arc<Reference>>,
        stop: &Stop,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Built, MethodError> {
        let recipe = if ask.method == Method::Visibility {
            self.visibility
        } else {
            self.paper
        };
        let params = FitParams {
            target_cells: ask.basis.unwrap_or(DEFAULT_BASIS),
            seed: ask.seed,
            ..recipe
        };
        params.validate()?;
        let zeta = match zeta {
            Some(zeta) => Arc::clone(zeta),
            None => Arc::new(Reference::new(
                kernel,
                SMALL_ZETA_GRID,
                params.heldout,
                REFERENCE_SEED,
            )),
        };
        let mut fit = Fit::new(Arc::clone(kernel), zeta, params)?;
        let target = params.target_cells;
        // Every thousand steps: the bar moves and Ctrl-C is heard (the fit is the same).
        fit.train(1000, |f| {
            progress(Progress::Cells {
                cells: f.network().len(),
                target,
            });
            if stop() {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        if stop() {
            return Err(MethodError::Interrupted);
        }
        let before = fit.model().clone();
        let summary = fit.finish()?;
        let rays = summary.rays;
        let before_refit = summary.errors_before_refit.map(|errors| (before, errors));
        // The paper's network without its refit is the same fit, read before the refit.
        let (rep, build_s) = match (ask.method, &before_refit) {
            (Method::PaperNorefit, Some((model, _))) => {
                (model.clone(), summary.wall_s - summary.refit_s)
            }
            _ => (fit.model().clone(), summary.wall_s),
        };
        Ok(Built {
            method: ask.method,
            rep: Box::new(rep),
            build_s,
            rays,
            note: None,
            account: Account::Network(Box::new(NetworkAccount {
                summary,
                before_refit,
            })),
        })
    }
}

/// A representation with nothing to account for.
fn plain(method: Method, rep: impl Representation + Send + 'static) -> Built {
    Built {
        method,
        rep: Box::new(rep),
        build_s: 0.0,
        rays: 0,
        note: None,
        account: Account::None,
    }
}

/// A baseline's run as a build.
fn baseline<A: Representation + Send + 'static>(method: Method, run: BaselineRun<A>) -> Built {
    Built {
        method,
        build_s: run.wall.as_secs_f64(),
        rays: run.rays,
        note: run.note.map(|n| n.to_string()),
        rep: Box::new(run.approx),
        account: Account::None,
    }
}
