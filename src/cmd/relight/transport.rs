//! `relight --kernel transport|MODEL`: the learned transport of the later bounces, built on the
//! spot from the exact relighter's operator (a bar over its clusters, Ctrl-C) and saved with
//! `--save-model`, or a saved model loaded and checked against the scene and mesh.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Result, anyhow, bail};
use flatland_geom::Kernel;
use flatland_lab::interrupt;
use flatland_lab::timed::walk::TransportMover;
use flatland_methods::Method;
use flatland_solve::{RelightParams, Relighter};
use flatland_transport::{Transport, TransportError, TransportParams};

/// What `--kernel` names.
pub enum Choice {
    /// The exact re-solve.
    Exact,
    /// The learned transport, built here.
    Transport,
    /// A saved model of the learned transport.
    Model(PathBuf),
}

/// Reads `--kernel`: exact, transport or a model file (a name with an extension or a folder).
pub fn choice(text: &str) -> Result<Choice> {
    if Path::new(text).extension().is_some() || text.contains(['/', '\\']) {
        return Ok(Choice::Model(PathBuf::from(text)));
    }
    match Method::parse(text) {
        Ok(Method::Exact) => Ok(Choice::Exact),
        Ok(Method::Transport) => Ok(Choice::Transport),
        Ok(other) => bail!(
            "--kernel {other}: relight re-solves with exact or transport (or a model file of the \
             transport), not {other}"
        ),
        Err(e) => bail!("--kernel: {e}"),
    }
}

/// The transport mover on a copy of `exact` (sharing its operator): the model built (and
/// saved to `save`) or loaded from `model`.
pub fn mover(
    kernel: &Kernel,
    exact: &Relighter,
    params: RelightParams,
    model: Option<&Path>,
    save: Option<&Path>,
) -> Result<TransportMover> {
    let transport = match model {
        Some(path) => Transport::load(path, exact.mesh())
            .map_err(|e| anyhow!("--kernel {}: {e}", path.display()))?,
        None => build(kernel, exact)?,
    };
    if let Some(path) = save {
        interrupt::writing(|| transport.save(path))
            .map_err(|e| anyhow!("--save-model {}: {e}", path.display()))?;
        eprintln!(
            "relight: the transport saved to {} ({:.1} MB; query it with --kernel {0})",
            path.display(),
            transport.bytes() as f64 / 1e6
        );
    }
    let copy = exact.with_params(params)?;
    TransportMover::new(kernel, copy, transport, &interrupt::requested)
}

/// The transport of `exact`'s mesh and operator, a bar over its clusters and validation lights.
fn build(kernel: &Kernel, exact: &Relighter) -> Result<Transport> {
    let params = TransportParams::default();
    let steps = Transport::set_up_steps(exact.mesh(), &params) as u64;
    let bar = super::super::progress_bar(
        steps,
        "the learned transport's blocks, then its validation lights",
    );
    let polled = AtomicU64::new(0);
    let ticking = bar.clone();
    // The build polls its stop once per cluster, then once per validation light: the bar
    // counts the polls.
    let stop = move || {
        let polls = polled.fetch_add(1, Ordering::Relaxed) + 1;
        ticking.set_position(polls.min(steps));
        interrupt::requested()
    };
    let built = Transport::build(kernel, exact.mesh(), exact.rows(), &params, &stop);
    bar.finish_and_clear();
    built.map_err(|e| match e {
        TransportError::Interrupted => interrupt::stopped().into(),
        other => anyhow::Error::from(other).context("building the learned transport"),
    })
}
