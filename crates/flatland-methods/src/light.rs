//! A lit scene lit by a method: the one path from a kernel's name (or a model file) to a solved
//! radiosity scored against the exact reference — the exact solve already made, the tracer, a
//! model file, or a representation built here and solved on the lit scene's mesh.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flatland_baselines::{TraceBudget, TraceParams, trace};
use flatland_solve::{Comparison, LitScene, Reference, Representation, Solution, Stop};
use kernel_fit::ModelFile;

use crate::{Account, Ask, Method, MethodError, Progress, Recipes};

/// Photons the tracer traces when no count is asked for.
pub const TRACER_PHOTONS: u64 = 1_000_000;

/// What a command's `--kernel` names: a method, or a model file `flatland fit --out` wrote.
#[derive(Clone, Debug, PartialEq)]
pub enum KernelArg {
    /// A method by its one name.
    Method(Method),
    /// A model file (`.json`).
    Model(PathBuf),
}

impl KernelArg {
    /// A model file when `text` ends in `.json`, else a method's name ([`Method::parse`]).
    pub fn parse(text: &str) -> Result<KernelArg, MethodError> {
        let extension = Path::new(text).extension();
        if extension.is_some_and(|e| e.eq_ignore_ascii_case("json")) {
            return Ok(KernelArg::Model(PathBuf::from(text)));
        }
        Method::parse(text).map(KernelArg::Method)
    }

    /// How reports name it: the method's name or the file's path.
    #[must_use]
    pub fn label(&self) -> String {
        match self {
            KernelArg::Method(m) => m.name().to_owned(),
            KernelArg::Model(path) => path.display().to_string(),
        }
    }
}

/// A lit scene lit by a method: the solution scored, and what lighting it took.
pub struct Lit {
    /// The solution and its errors against the lit scene's reference.
    pub comparison: Comparison,
    /// Basis functions of the representation (`None`: the exact kernel, the tracer).
    pub basis: Option<usize>,
    /// Bytes the method held (the representation; the tracer's tallies).
    pub bytes: usize,
    /// Seconds building the representation took (0 for the exact solve already made).
    pub build_s: f64,
    /// Why it is not what was asked for, or how the tracer ran.
    pub note: Option<String>,
    /// What its learner says of it.
    pub account: Account,
}

impl Recipes {
    /// Lights `lit` with `kernel`: the exact kernel reuses the solve `lit` made; the tracer
    /// traces `ask.basis` photons ([`TRACER_PHOTONS`] by default); a model file is loaded;
    /// anything else is built ([`Recipes::build`]) and solved on `lit`'s mesh.
    pub fn light(
        &self,
        kernel: &KernelArg,
        ask: Ask,
        lit: &LitScene,
        zeta: Option<&Arc<Reference>>,
        stop: &Stop,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Lit, MethodError> {
        let method = match kernel {
            KernelArg::Model(path) => {
                let model = ModelFile::load(path)?.model;
                return Ok(plain(lit.score(&model, stop)?, &model));
            }
            KernelArg::Method(Method::Exact) => {
                if let Some(reused) = lit.exact_scored() {
                    return Ok(plain(reused, lit.kernel().as_ref()));
                }
                Method::Exact
            }
            KernelArg::Method(Method::Tracer) => return traced(ask, lit, stop),
            KernelArg::Method(method) => *method,
        };
        let ask = Ask { method, ..ask };
        let built = self.build(ask, lit.kernel(), lit.mesh(), zeta, stop, progress)?;
        let comparison = lit.score(built.rep.as_ref(), stop)?;
        Ok(Lit {
            comparison,
            basis: built.rep.basis_functions(),
            bytes: built.rep.memory_bytes(),
            build_s: built.build_s,
            note: built.note,
            account: with_mesh_error(built.account, lit),
        })
    }
}

/// The light-driven learner's estimate with the lit scene's mesh error as a function added,
/// when the lit scene estimated it on the learner's mesh: then it covers B as a function.
fn with_mesh_error(account: Account, lit: &LitScene) -> Account {
    let (Account::Light(light), Some(mesh)) = (&account, lit.estimate()) else {
        return account;
    };
    let mut light = *light;
    light.estimate = light
        .estimate
        .map(|e| e.with_discretization(mesh).unwrap_or(e));
    Account::Light(light)
}

/// A solution of a representation that was not built here.
fn plain(comparison: Comparison, rep: &dyn Representation) -> Lit {
    Lit {
        comparison,
        basis: rep.basis_functions(),
        bytes: rep.memory_bytes(),
        build_s: 0.0,
        note: None,
        account: Account::None,
    }
}

/// The Monte Carlo tracer on the lit scene's mesh: no kernel.
fn traced(ask: Ask, lit: &LitScene, stop: &Stop) -> Result<Lit, MethodError> {
    let photons = ask.basis.map_or(TRACER_PHOTONS, |n| n as u64);
    let params = TraceParams {
        budget: TraceBudget::Photons(photons),
        seed: ask.seed,
    };
    let traced = trace(lit.kernel(), lit.mesh(), &params, stop)?;
    if traced.stopped {
        return Err(MethodError::Interrupted);
    }
    let solution = Solution {
        radiosity: traced.radiosity,
        iterations: 0,
        residual: 0.0,
        assembly_s: 0.0,
        solve_s: traced.wall.as_secs_f64(),
    };
    Ok(Lit {
        comparison: lit.scored(solution),
        basis: None,
        bytes: traced.memory_bytes,
        build_s: 0.0,
        note: Some(format!("{} photons, {} rays", traced.photons, traced.rays)),
        account: Account::None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::{Kernel, bundled};
    use flatland_solve::{Elements, LitParams, never};

    fn lit() -> LitScene {
        let kernel = Arc::new(Kernel::new(bundled::scene("fig3").unwrap()));
        let params = LitParams {
            elements: Elements::Exactly(128),
            ..LitParams::default()
        };
        LitScene::new(kernel, &params, &never).unwrap()
    }

    #[test]
    fn the_exact_kernel_reuses_the_solve_and_the_others_are_scored_alike() {
        let lit = lit();
        let recipes = Recipes::default();
        let light = |k: KernelArg, basis| {
            let ask = Ask {
                basis,
                ..Ask::new(Method::Exact)
            };
            recipes
                .light(&k, ask, &lit, None, &never, &mut |_| {})
                .unwrap()
        };
        let exact = light(KernelArg::Method(Method::Exact), None);
        assert_eq!(
            exact.comparison.solution.radiosity,
            lit.exact().unwrap().solution().radiosity
        );
        let hr = light(KernelArg::Method(Method::Hr), Some(200));
        assert!(hr.basis.unwrap() > 0 && hr.build_s > 0.0);
        assert!(hr.comparison.errors.rel_l2_reflected > exact.comparison.errors.rel_l2_reflected);
        // The tracer: within its noise of the exact B at ten thousand photons.
        let traced = light(KernelArg::Method(Method::Tracer), Some(20_000));
        assert!(traced.note.unwrap().contains("20000 photons"));
        assert!(
            traced.comparison.errors.rel_l2_b < 0.2,
            "{:?}",
            traced.comparison.errors
        );
    }

    #[test]
    fn kernels_parse_as_methods_or_model_files() {
        assert_eq!(
            KernelArg::parse("light").unwrap(),
            KernelArg::Method(Method::Light)
        );
        let model = KernelArg::parse("runs/m.JSON").unwrap();
        assert_eq!(model, KernelArg::Model(PathBuf::from("runs/m.JSON")));
        assert_eq!(model.label(), "runs/m.JSON");
        let err = KernelArg::parse("first-shot").unwrap_err().to_string();
        assert!(err.contains("`visibility`"), "{err}");
    }
}
