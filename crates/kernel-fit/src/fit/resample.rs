//! θ-resampling: new sample sets where the network is poor (critical cells) or absent.

use super::*;

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
        let p = self.state.params;
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
            let (sampler, kernel) = (&self.state.sampler, &self.kernel);
            let mut rng = self.state.resample_rng.clone();
            let model = &self.state.model;
            let (keep, drawn) = rayon::join(
                || theta_keeps(model, &critical, p.phi, &candidates),
                || (next > 0).then(|| draw_candidates(sampler.as_ref(), kernel, next, &mut rng)),
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
            self.state.resample_not_before = self.steps() + u64::from(p.network.lambda);
        }
        if accepted.is_empty() {
            return;
        }
        let new = if self.state.sampler.is_some() {
            visibility_samples(
                &self.kernel,
                self.state.model.frame,
                &self.state.params,
                &accepted,
            )
        } else {
            let points: Vec<[f64; 2]> = accepted.iter().map(|c| c.st).collect();
            make_samples(
                &self.kernel,
                &self.state.model.scene,
                self.state.model.frame,
                p.target,
                self.state.model.output_scale,
                &points,
            )
        };
        self.state.rays += rays_of(&self.kernel, &new);
        self.state.set_starts.push(self.state.samples.len());
        self.state.samples.extend(new);
        self.index_sample_faces();
    }

    /// `n` θ candidates from the resampling stream.
    fn candidates(&mut self, n: usize) -> Vec<Candidate> {
        draw_candidates(
            self.state.sampler.as_ref(),
            &self.kernel,
            n,
            &mut self.state.resample_rng,
        )
    }
}

/// `n` θ candidates: uniform `(s, t)`, or a visibility model's sampler draws.
fn draw_candidates(
    sampler: Option<&Sampler>,
    kernel: &Kernel,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Candidate> {
    match sampler {
        Some(sampler) => draw_points(sampler, kernel, n, rng),
        None => (0..n)
            .map(|_| Candidate {
                st: [rng.random::<f64>(), rng.random::<f64>()],
                weight: 1.0,
            })
            .collect(),
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
            let key = model
                .geometry
                .as_ref()
                .and_then(|g| FaceKey::at(&g.kernel, &g.kernel.unoccluded(s, t)));
            let gate = key.as_ref().and_then(|key| model.gate(key));
            let (d_a, d_acc) = match &gate {
                Some(gate) => model.network.activation_sums_gated(&xi, critical, gate),
                None => model.network.activation_sums(&xi, critical),
            };
            d_acc > phi || d_a <= phi
        })
        .collect()
}
