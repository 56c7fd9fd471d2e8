//! Where a fit's samples come from, per learner: uniform `(s, t)` labelled with the exact ζ or
//! k (a ray only where geometry cannot decide visibility), or the visibility learner's draws
//! where visibility varies, labelled with `V` (one ray each) and weighted by importance.

use flatland_geom::Kernel;
use flatland_solve::InputFrame;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use crate::Head;
use crate::model::Sample;
use crate::visibility::Sampler;

/// A place a sample may be taken, with its importance weight.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub(crate) st: [f64; 2],
    pub(crate) weight: f64,
}

/// How a fit draws and labels its samples (built from its [`Head`]).
#[derive(Clone, Debug)]
pub(crate) enum Source {
    /// ζ at uniform `(s, t)` (the paper's network).
    Zeta,
    /// k at uniform `(s, t)` (the emission factored out).
    K,
    /// `V` where visibility varies, drawn by the sampler; no sampler when geometry decides
    /// every visibility (nothing to learn).
    Visibility {
        sampler: Option<Sampler>,
        /// Whether a sample's error counts with its importance weight.
        weighted: bool,
    },
}

impl Source {
    /// The source of `head`'s learner on `kernel`; the visibility learner's sampler draws its
    /// pilot and tiles from `rng`.
    pub(crate) fn start(head: &Head, kernel: &Kernel, rng: &mut ChaCha8Rng) -> Source {
        match head {
            Head::Zeta { .. } => Source::Zeta,
            Head::FactoredEmission { .. } => Source::K,
            Head::Visibility(v) => Source::Visibility {
                sampler: Sampler::new(kernel, v.importance, rng),
                weighted: v.weighted,
            },
        }
    }

    /// The source a checkpoint saved: `head`'s, with the visibility learner's saved sampler.
    pub(crate) fn resumed(head: &Head, sampler: Option<Sampler>) -> Result<Source, String> {
        match (head, sampler) {
            (Head::Visibility(v), sampler) => Ok(Source::Visibility {
                sampler,
                weighted: v.weighted,
            }),
            (Head::Zeta { .. }, None) => Ok(Source::Zeta),
            (Head::FactoredEmission { .. }, None) => Ok(Source::K),
            (_, Some(_)) => Err("`state.sampler` is set, but only the visibility learner \
                                 (target `visibility`) draws with a sampler"
                .to_owned()),
        }
    }

    /// Whether there is nothing to learn: geometry decides every visibility.
    pub(crate) fn nothing_to_learn(&self) -> bool {
        matches!(self, Source::Visibility { sampler: None, .. })
    }

    /// The visibility learner's sampler (what a checkpoint saves).
    pub(crate) fn sampler(&self) -> Option<&Sampler> {
        match self {
            Source::Visibility { sampler, .. } => sampler.as_ref(),
            Source::Zeta | Source::K => None,
        }
    }

    /// `n` candidates from `rng` (no ray): uniform `(s, t)`, or the sampler's draws (none when
    /// there is nothing to learn).
    pub(crate) fn draw(&self, kernel: &Kernel, n: usize, rng: &mut ChaCha8Rng) -> Vec<Candidate> {
        match self {
            Source::Zeta | Source::K => (0..n)
                .map(|_| Candidate {
                    st: [rng.random::<f64>(), rng.random::<f64>()],
                    weight: 1.0,
                })
                .collect(),
            Source::Visibility { sampler, .. } => {
                let Some(sampler) = sampler else {
                    return Vec::new();
                };
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
        }
    }

    /// The samples of `candidates`: one ray each where it is needed (in parallel, order kept),
    /// targets of ζ or k divided by `scale`, of `V` as they are.
    pub(crate) fn label(
        &self,
        kernel: &Kernel,
        frame: InputFrame,
        scale: f64,
        candidates: &[Candidate],
    ) -> Vec<Sample> {
        let points: Vec<[f64; 2]> = candidates.iter().map(|c| c.st).collect();
        let scene = kernel.scene();
        let sample = |c: &Candidate, target: f64, weight: f64| Sample {
            st: c.st,
            xi: frame.gamma(scene, c.st[0], c.st[1]),
            target,
            weight,
        };
        let values = match self {
            Source::Zeta => kernel.zeta_batch(&points),
            Source::K => kernel.k_batch(&points),
            Source::Visibility { weighted, .. } => {
                // Every candidate has a positive unoccluded ζ, so ζ > 0 exactly when x and y
                // see each other.
                let zeta = kernel.zeta_batch(&points);
                return candidates
                    .iter()
                    .zip(zeta)
                    .map(|(c, z)| {
                        let v = if z > 0.0 { 1.0 } else { 0.0 };
                        sample(c, v, if *weighted { c.weight } else { 1.0 })
                    })
                    .collect();
            }
        };
        candidates
            .iter()
            .zip(values)
            .map(|(c, value)| sample(c, value / scale, 1.0))
            .collect()
    }

    /// The scale the network's targets are divided by: the RMS of S₀'s targets for ζ or k,
    /// 1 for `V ∈ [0, 1]`.
    pub(crate) fn output_scale(&self, s0: &[Sample]) -> f64 {
        match self {
            Source::Zeta | Source::K => rms_scale(s0.iter().map(|s| s.target)),
            Source::Visibility { .. } => 1.0,
        }
    }
}

/// The rays the samples cost: those whose visibility geometry could not decide
/// ([`Kernel::casts_ray`]; every sample of a visibility model).
pub(crate) fn rays_of(kernel: &Kernel, samples: &[Sample]) -> u64 {
    samples
        .iter()
        .filter(|s| kernel.casts_ray(s.st[0], s.st[1]))
        .count() as u64
}

/// The root mean square of `values`, computed without overflow or underflow; 1 when it is 0 or
/// not finite (a scene that is dark everywhere S₀ looked).
fn rms_scale(values: impl Iterator<Item = f64> + Clone) -> f64 {
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

/// Three distinct samples' inputs as the initial triangle (distinct so no edge has length 0).
pub(crate) fn pick_simplex(samples: &[Sample], rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
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
