//! Making samples: seed streams, candidate points, labels (the rays), and what they cost.

use super::*;

/// The rays the samples cost: those whose visibility geometry could not decide
/// ([`Kernel::casts_ray`]; every sample of a visibility model).
pub(super) fn rays_of(kernel: &Kernel, samples: &[Sample]) -> u64 {
    samples
        .iter()
        .filter(|s| kernel.casts_ray(s.st[0], s.st[1]))
        .count() as u64
}

/// A place a sample may be taken, with its importance weight.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate {
    pub(super) st: [f64; 2],
    pub(super) weight: f64,
}

/// `n` draws of a visibility model's sampler (no ray).
pub(super) fn draw_points(
    sampler: &Sampler,
    kernel: &Kernel,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Candidate> {
    (0..n)
        .map(|_| {
            let d = sampler.draw(kernel, rng);
            Candidate {
                st: d.st,
                weight: d.weight,
            }
        })
        .collect()
}

/// Visibility samples: one ray per candidate (in parallel, order kept); the target is `V`.
pub(super) fn visibility_samples(
    kernel: &Kernel,
    frame: InputFrame,
    params: &FitParams,
    candidates: &[Candidate],
) -> Vec<Sample> {
    let points: Vec<[f64; 2]> = candidates.iter().map(|c| c.st).collect();
    // Every candidate has a positive unoccluded ζ, so ζ > 0 exactly when x and y see each other.
    let zeta = kernel.zeta_batch(&points);
    candidates
        .iter()
        .zip(zeta)
        .map(|(c, z)| Sample {
            st: c.st,
            xi: frame.gamma(kernel.scene(), c.st[0], c.st[1]),
            target: if z > 0.0 { 1.0 } else { 0.0 },
            weight: if params.weighted { c.weight } else { 1.0 },
        })
        .collect()
}

/// Casts one ray per point (in parallel, order kept) and builds the samples.
pub(super) fn make_samples(
    kernel: &Kernel,
    scene: &Scene,
    frame: InputFrame,
    target: Target,
    scale: f64,
    points: &[[f64; 2]],
) -> Vec<Sample> {
    let values = match target {
        Target::Zeta | Target::Visibility => kernel.zeta_batch(points),
        Target::FactoredEmission => kernel.k_batch(points),
    };
    points
        .iter()
        .zip(values)
        .map(|(&[s, t], target)| Sample {
            st: [s, t],
            xi: frame.gamma(scene, s, t),
            target: target / scale,
            weight: 1.0,
        })
        .collect()
}

/// The root mean square of `values`, computed without overflow or underflow; 1 when it is 0 or
/// not finite (a scene that is dark everywhere S₀ looked).
pub(super) fn rms_scale(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let max = values.clone().fold(
        0.0_f64,
        |m, v| if v.is_finite() { m.max(v.abs()) } else { m },
    );
    if max == 0.0 {
        return 1.0;
    }
    let (sum, n) = values.fold((0.0, 0usize), |(sum, n), v| {
        (sum + (v / max).powi(2), n + 1)
    });
    let rms = max * (sum / n as f64).sqrt();
    if rms.is_finite() && rms > 0.0 {
        rms
    } else {
        1.0
    }
}

/// E' per edge when the emission is factored out of the target, empty otherwise.
pub(super) fn emission_factor(kernel: &Kernel, target: Target) -> Vec<f64> {
    match target {
        Target::Zeta | Target::Visibility => Vec::new(),
        Target::FactoredEmission => (0..kernel.scene().edges().len())
            .map(|e| kernel.source_weight(e))
            .collect(),
    }
}

/// Three distinct samples' inputs as the initial triangle (distinct so no edge has length 0).
pub(super) fn pick_simplex(samples: &[Sample], rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut chosen: Vec<Vec<f64>> = Vec::with_capacity(3);
    let mut tries = 0;
    while chosen.len() < 3 {
        let candidate = samples[rng.random_range(0..samples.len())].xi.to_vec();
        tries += 1;
        if tries > 1000 || !chosen.contains(&candidate) {
            chosen.push(candidate);
        }
    }
    chosen
}
