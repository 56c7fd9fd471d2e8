//! θ-resampling: new sample sets where the network is poor (critical cells) or absent.

use std::time::Instant;

use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::source::Candidate;
use super::{Fit, rays_of};
use crate::{LearnedKernel, Resampling};

impl Fit {
    /// A new sample set chosen by θ(ξ) = ρ_ACC(ξ) ∨ ¬ρ_A(ξ) (the printed ∧ is an erratum: a
    /// sample is wanted in a critical zone *or* outside the network): candidates are scanned in
    /// parallel without casting a ray, the next chunk drawn while one is tested; only accepted
    /// ones cost a ray. A visibility model draws its candidates where visibility varies and
    /// measures θ with its gated activations, so a face no cell covers counts as outside the
    /// network.
    pub(super) fn resample(&mut self) {
        let started = Instant::now();
        self.resample_inner();
        self.state.resample_s += started.elapsed().as_secs_f64();
    }

    fn resample_inner(&mut self) {
        let p = self.valid.live;
        let cells = self.state.model.network.len() as f64;
        let wanted = ((cells / p.psi).ceil() as usize)
            .saturating_sub(self.state.samples.len())
            .max(p.min_set_size);
        let wanted =
            wanted.min(usize::try_from(p.ray_budget - self.state.rays).unwrap_or(usize::MAX));
        let critical = self.state.model.network.critical_cells(p.omega);
        let scan_limit = wanted.saturating_mul(p.scan_factor);
        let chunk = (wanted * 4).clamp(256, 1 << 16);
        let mut accepted: Vec<Candidate> = Vec::with_capacity(wanted);
        let mut scanned = 0;
        // The next chunk, drawn from a copy of the stream while the current one is tested; it
        // and the copy's state are taken only if the scan goes on, so the stream advances
        // exactly as a serial scan would (the same samples for a seed).
        let mut ahead: Option<(Vec<Candidate>, ChaCha8Rng)> = None;
        while accepted.len() < wanted && scanned < scan_limit {
            let n = chunk.min(scan_limit - scanned);
            let candidates = match ahead.take() {
                Some((candidates, rng)) => {
                    self.state.resample_rng = rng;
                    candidates
                }
                None => self.candidates(n),
            };
            scanned += n;
            if p.resampling == Resampling::Uniform {
                accepted.extend(candidates);
                continue;
            }
            let next = chunk.min(scan_limit - scanned);
            let (source, kernel) = (&self.state.source, &self.kernel);
            let mut rng: ChaCha8Rng = self.state.resample_rng.clone();
            let model = &self.state.model;
            let (keep, drawn) = rayon::join(
                || theta_keeps(model, &critical, p.phi, &candidates),
                || (next > 0).then(|| source.draw(kernel, next, &mut rng)),
            );
            ahead = drawn.map(|candidates| (candidates, rng));
            accepted.extend(
                candidates
                    .into_iter()
                    .zip(keep)
                    .filter(|(_, k)| *k)
                    .map(|(c, _)| c),
            );
        }
        accepted.truncate(wanted);
        if accepted.len() < wanted {
            // θ found too few places worth a ray; do not rescan every step.
            self.state.resample_not_before = self.steps() + u64::from(p.rates.lambda);
        }
        if accepted.is_empty() {
            return;
        }
        let new = self.state.source.label(
            &self.kernel,
            self.state.model.frame,
            self.state.model.output_scale,
            &accepted,
        );
        self.state.rays += rays_of(&self.kernel, &new);
        self.state.set_starts.push(self.state.samples.len());
        self.state.samples.extend(new);
        self.index_sample_faces();
    }

    /// `n` θ candidates from the resampling stream.
    fn candidates(&mut self, n: usize) -> Vec<Candidate> {
        self.state
            .source
            .draw(&self.kernel, n, &mut self.state.resample_rng)
    }
}

/// θ(ξ) = ρ_ACC(ξ) ∨ ¬ρ_A(ξ) for each candidate, in parallel: a visibility model measures the
/// activations gated to the candidate's face.
fn theta_keeps(
    model: &LearnedKernel,
    critical: &[bool],
    phi: f64,
    candidates: &[Candidate],
) -> Vec<bool> {
    // A θ test takes a few µs: tasks of 64 keep rayon's overhead off the scan.
    candidates
        .par_iter()
        .with_min_len(64)
        .map(|c| {
            let [s, t] = c.st;
            let xi = model.input(s, t);
            let gate = model.gate_at(s, t);
            let (d_a, d_acc) = match &gate {
                Some(gate) => model.network.activation_sums_gated(&xi, critical, gate),
                None => model.network.activation_sums(&xi, critical),
            };
            d_acc > phi || d_a <= phi
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use crate::{FitParams, Resampling};

    #[test]
    fn theta_resampling_beats_uniform_at_the_same_ray_budget_on_fig3() {
        let kernel = fig3();
        let (mut theta, mut uniform) = ((0.0, 0), (0.0, 0));
        for seed in 1..=3 {
            let t = run(&mut fit_with(&kernel, FitParams { seed, ..paper(200) }));
            let u = run(&mut fit_with(
                &kernel,
                FitParams {
                    seed,
                    resampling: Resampling::Uniform,
                    ..paper(200)
                },
            ));
            theta = (theta.0 + t.errors.heldout, theta.1 + t.rays);
            uniform = (uniform.0 + u.errors.heldout, uniform.1 + u.rays);
        }
        // Both stop at 200 cells with ≈ 20 samples per cell; θ's short scans may top a set up
        // later, so allow it 2 % more rays.
        assert!(
            theta.1 as f64 <= 1.02 * uniform.1 as f64,
            "{theta:?} vs {uniform:?} rays"
        );
        // Measured: summed held-out errors 1.29 vs 1.58 over seeds 1-3; demand a 10 % margin.
        assert!(
            theta.0 < 0.9 * uniform.0,
            "θ {theta:?} vs uniform {uniform:?}"
        );
    }
}
