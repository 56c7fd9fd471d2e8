//! Validation of what a checkpoint file holds, field by field, before the reference it names is
//! built: the model and parameters as a model file's ([`crate::model::checks`]), then the
//! reference's size, the samples and the counters of the state. A file a user edited resumes
//! or fails with a one-line error naming the field and the valid range, never a panic.

use super::state::{Checkpoint, LoadedState};
use crate::model::checks::{Bad, MAX_ABS, bad, learned_kernel, params};
use crate::{Target, limits};

/// A checkpoint, before the reference it names is built: every field of the state.
pub(super) fn checkpoint(c: &Checkpoint<LoadedState>) -> Result<(), Bad> {
    reference_size(c)?;
    let s = &c.state;
    params(&s.params)?;
    learned_kernel(&s.model, s.params.target)?;
    samples(s)?;
    counters(s)
}

/// The size of the reference a checkpoint names (checked before it is built).
fn reference_size(c: &Checkpoint<LoadedState>) -> Result<(), Bad> {
    if !limits::GRID_RES.contains(&c.reference_res) {
        return Err(bad(
            "reference_res",
            format!(
                "is {}, but must be in [{}, {}]",
                c.reference_res,
                limits::GRID_RES.start(),
                limits::GRID_RES.end()
            ),
        ));
    }
    if !limits::HELDOUT.contains(&c.reference_heldout) {
        return Err(bad(
            "reference_heldout",
            format!(
                "is {}, but must be in [{}, {}]",
                c.reference_heldout,
                limits::HELDOUT.start(),
                limits::HELDOUT.end()
            ),
        ));
    }
    Ok(())
}

/// The samples and where they come from: S₀ at least, the sampler of a visibility fit, every
/// sample in range.
fn samples(s: &LoadedState) -> Result<(), Bad> {
    // Only a fit with nothing to learn (geometry decides every visibility) has no sample.
    if s.samples.is_empty() && s.stop != Some(super::StopReason::Exact) {
        return Err(bad(
            "state.samples",
            "is empty, but a fit has at least S₀ (unless it stopped as exact)",
        ));
    }
    // The visibility learner draws with its sampler; only a fit with nothing to learn has none.
    if s.params.target == Target::Visibility
        && s.sampler.is_none()
        && s.stop != Some(super::StopReason::Exact)
    {
        return Err(bad(
            "state.sampler",
            "is missing, but a visibility fit draws its samples with it (unless it stopped as \
             exact)",
        ));
    }
    for (i, sample) in s.samples.iter().enumerate() {
        let st_ok = sample.st.iter().all(|v| (0.0..=1.0).contains(v));
        let xi_ok = sample
            .xi
            .iter()
            .all(|v| v.is_finite() && v.abs() <= MAX_ABS);
        let target_ok = sample.target.is_finite() && sample.target.abs() <= MAX_ABS;
        if !(st_ok && xi_ok && target_ok) {
            return Err(bad(
                &format!("state.samples[{i}]"),
                "is out of range: st must be in [0, 1], xi and target finite and at most 1e100 \
                 in magnitude",
            ));
        }
    }
    Ok(())
}

/// The counters of the state: rays, cells' wins, growth, the learning curve and the times.
fn counters(s: &LoadedState) -> Result<(), Bad> {
    let steps = s.model.network.steps();
    if s.rays > limits::MAX_COUNT {
        return Err(bad(
            "state.rays",
            format!("is {}, but must be at most 2^50", s.rays),
        ));
    }
    for (i, stats) in s.cell_stats.iter().enumerate() {
        if !(stats.sum_s.is_finite() && stats.sum_t.is_finite() && stats.wins <= steps) {
            return Err(bad(
                &format!("state.cell_stats[{i}]"),
                format!("must have finite sums and at most {steps} wins (the steps)"),
            ));
        }
    }
    if s.steps_at_last_growth > steps {
        return Err(bad(
            "state.steps_at_last_growth",
            format!(
                "is {}, but the network has trained {steps} steps",
                s.steps_at_last_growth
            ),
        ));
    }
    if let Some(h) = s
        .history
        .iter()
        .find(|h| h.steps > steps || !(h.rel_l2_heldout.is_finite() && h.rel_l2_heldout >= 0.0))
    {
        return Err(bad(
            "state.history",
            format!(
                "has a point at step {} with error {}; points must not be later than the fit \
                 ({steps} steps) and errors finite and ≥ 0",
                h.steps, h.rel_l2_heldout
            ),
        ));
    }
    for (field, v) in [
        ("state.wall_s", s.wall_s),
        ("state.resample_s", s.resample_s),
        ("state.refit_s", s.refit_s),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(field, format!("is {v}, but must be finite and ≥ 0")));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;
    use std::path::{Path, PathBuf};
    use std::sync::Arc;

    use flatland_geom::{Kernel, KernelParams, Scene};
    use serde_json::{Value, json};

    use crate::{Fit, FitParams, ModelFile, Target};
    use flatland_solve::Reference;

    const FIG3: &str = flatland_geom::bundled::SCENES[0].2;

    /// A small finished fit of fig3 learning `target`.
    fn small_fit(target: Target) -> Fit {
        let kernel = Arc::new(Kernel::new(Scene::from_ron_str(FIG3).unwrap()));
        let reference = Arc::new(Reference::new(&kernel, 16, 64, crate::REFERENCE_SEED));
        let params = FitParams {
            target_cells: 12,
            initial_samples: 60,
            heldout: 64,
            refit: false,
            ..FitParams::default().learning(target)
        };
        let mut fit = Fit::new(kernel, reference, params).unwrap();
        fit.run(1000, |_| ControlFlow::Continue(())).unwrap();
        fit
    }

    fn temp(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("flatland-checks-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A hand edit of a file's JSON.
    type Edit = Box<dyn FnOnce(&mut Value)>;

    /// The file at `path` as JSON, edited by `edit`, written to `out`.
    fn edited(path: &Path, out: &Path, edit: impl FnOnce(&mut Value)) {
        let mut value: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
        edit(&mut value);
        std::fs::write(out, serde_json::to_vec(&value).unwrap()).unwrap();
    }

    fn expect_refused(result: Result<impl Sized, crate::FitError>, needles: &[&str]) {
        let message = result
            .err()
            .expect("an edited file must be refused")
            .to_string();
        assert!(!message.contains('\n'), "{message}");
        for needle in needles {
            assert!(
                message.contains(needle),
                "`{needle}` missing from: {message}"
            );
        }
    }

    #[test]
    fn edited_models_are_refused_naming_the_field() {
        let dir = temp("model");
        let factored = dir.join("factored.json");
        let fit = small_fit(Target::FactoredEmission);
        ModelFile::new(fit.model().clone(), *fit.params(), None)
            .save(&factored)
            .unwrap();
        ModelFile::load(&factored).unwrap();
        let zeta = dir.join("zeta.json");
        let fit = small_fit(Target::Zeta);
        ModelFile::new(fit.model().clone(), *fit.params(), None)
            .save(&zeta)
            .unwrap();
        let bad = dir.join("bad.json");
        // Each edit once panicked (an emission factor per edge indexed out of bounds in every
        // rayon worker) or was accepted and printed meaningless errors.
        let cases: Vec<(&Path, Edit, &[&str])> = vec![
            (
                &factored,
                Box::new(|v| v["model"]["emission_factor"] = json!([1.0, 0.5])),
                &["model.emission_factor", "one per edge", "(7)"],
            ),
            (
                &zeta,
                Box::new(|v| v["model"]["emission_factor"] = json!([1.0])),
                &["model.emission_factor", "has none"],
            ),
            (
                &zeta,
                Box::new(|v| v["model"]["network"]["outputs"][0] = json!(1e308)),
                &["model.network.outputs", "overflow"],
            ),
            (
                &zeta,
                Box::new(|v| v["model"]["output_scale"] = json!(-2.0)),
                &["model.output_scale", "-2", "> 0"],
            ),
            (
                &zeta,
                Box::new(|v| v["model"]["frame"]["inv_scale"] = json!(0.0)),
                &["model.frame", "inv_scale"],
            ),
            (
                &zeta,
                Box::new(|v| v["model"]["frame"]["inv_scale"] = json!(1e-9)),
                &["model.frame", "side in [0.001, 100]"],
            ),
            (
                &zeta,
                Box::new(|v| v["params"]["heldout"] = json!(1u64 << 40)),
                &["params.heldout", "must be in"],
            ),
            (
                &zeta,
                Box::new(|v| v["model"]["network"]["steps"] = json!(u64::MAX)),
                &["model.network.steps"],
            ),
        ];
        for (source, edit, needles) in cases {
            edited(source, &bad, edit);
            expect_refused(ModelFile::load(&bad), needles);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn edited_checkpoints_are_refused_before_the_reference_is_built() {
        let dir = temp("checkpoint");
        let good = dir.join("good.ckpt");
        small_fit(Target::Zeta).save_checkpoint(&good).unwrap();
        Fit::resume(&good, KernelParams::default()).unwrap();
        let bad = dir.join("bad.ckpt");
        let cases: Vec<(Edit, &[&str])> = vec![
            // Once an allocation abort: a 100 000² reference grid.
            (
                Box::new(|v| v["reference_res"] = json!(100_000)),
                &["reference_res", "100000", "[16, 4096]"],
            ),
            (
                Box::new(|v| v["reference_heldout"] = json!(0)),
                &["reference_heldout"],
            ),
            (
                Box::new(|v| v["state"]["params"]["min_set_size"] = json!(1u64 << 60)),
                &["params.min_set_size"],
            ),
            (
                Box::new(|v| v["state"]["samples"][3]["xi"][0] = json!(1e300)),
                &["state.samples[3]"],
            ),
            (
                Box::new(|v| v["state"]["steps_at_last_growth"] = json!(u64::MAX)),
                &["state.steps_at_last_growth"],
            ),
            (
                Box::new(|v| v["state"]["rays"] = json!(u64::MAX)),
                &["state.rays"],
            ),
            (
                Box::new(|v| v["state"]["samples"] = json!([])),
                &["state.samples", "empty"],
            ),
        ];
        for (edit, needles) in cases {
            edited(&good, &bad, edit);
            expect_refused(Fit::resume(&bad, KernelParams::default()), needles);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
