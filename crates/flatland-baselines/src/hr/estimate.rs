//! A link's value from its rays: the exact unoccluded mean times a G-weighted visible fraction
//! over `rays_per_link` Latin-hypercube points (or their plain mean of ζ), none where geometry
//! decides the pair's visibility.

use super::elements::Surfaces;
use super::refine::Pending;
use super::{HrParams, LinkEstimate};
use flatland_geom::{Kernel, PairClass};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One link's mean ζ from its rays, and the rays cast.
pub(super) fn estimate(
    kernel: &Kernel,
    surfaces: &Surfaces,
    link: &Pending,
    params: &HrParams,
    seed: u64,
) -> (f64, u64) {
    let (p, q) = (&link.p, &link.q);
    let weight = surfaces.source_weight[p.ord] * surfaces.reflectance[q.ord];
    let unoccluded_mean = weight * link.transfer / (p.length() * q.length());
    if params.estimate == LinkEstimate::FormFactorVisibility {
        // Where geometry decides the visibility of the whole edge pair, V̂ needs no ray.
        let mid = kernel.unoccluded((p.s0 + p.s1) / 2.0, (q.s0 + q.s1) / 2.0);
        match kernel.pair_class(mid.sender, mid.receiver) {
            PairClass::Visible => return (unoccluded_mean, 0),
            PairClass::Hidden | PairClass::Zero => return (0.0, 0),
            PairClass::Varies => {}
        }
    }
    let n = params.rays_per_link;
    let sums = latin_hypercube_rays(kernel, [p.s0, p.s1], [q.s0, q.s1], n, seed);
    let value = match params.estimate {
        LinkEstimate::SampleMean => sums.zeta / n as f64,
        LinkEstimate::FormFactorVisibility => {
            let visible = if sums.g > 0.0 {
                sums.visible_g / sums.g
            } else {
                1.0
            };
            unoccluded_mean * visible
        }
    };
    (value, sums.rays)
}

/// What a link's rays add up to.
struct RaySums {
    /// `Σ G` over the rays.
    g: f64,
    /// `Σ G V`: G of the rays that reach the receiver.
    visible_g: f64,
    /// `Σ ζ`.
    zeta: f64,
    /// Evaluations that needed a ray traced ([`Kernel::casts_ray`]).
    rays: u64,
}

/// `n` kernel evaluations at Latin-hypercube points of `[s0, s1) × [t0, t1)`: one point per
/// s-stratum and per t-stratum, from the link's own seed stream.
fn latin_hypercube_rays(
    kernel: &Kernel,
    [s0, s1]: [f64; 2],
    [t0, t1]: [f64; 2],
    n: usize,
    seed: u64,
) -> RaySums {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut perm: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        perm.swap(k, rng.random_range(0..=k));
    }
    let inside =
        |lo: f64, hi: f64, u: f64| (lo + (hi - lo) * u).clamp(lo, f64::from_bits(hi.to_bits() - 1));
    let mut sums = RaySums {
        g: 0.0,
        visible_g: 0.0,
        zeta: 0.0,
        rays: 0,
    };
    for (k, &pk) in perm.iter().enumerate() {
        let s = inside(s0, s1, (k as f64 + rng.random::<f64>()) / n as f64);
        let t = inside(t0, t1, (pk as f64 + rng.random::<f64>()) / n as f64);
        sums.rays += u64::from(kernel.casts_ray(s, t));
        let sample = kernel.eval(s, t);
        sums.g += sample.geometry;
        if sample.visible {
            sums.visible_g += sample.geometry;
        }
        sums.zeta += sample.zeta;
    }
    sums
}

#[cfg(test)]
mod tests {
    use super::super::elements::Elem;
    use super::*;
    use crate::test_support::{blocker_kernel, box_kernel};
    use crate::{HierarchicalRadiosity, run_hr};
    use flatland_geom::EdgeId;

    #[test]
    fn rays_are_counted_and_values_finite() {
        let kernel = blocker_kernel();
        for estimate in [LinkEstimate::FormFactorVisibility, LinkEstimate::SampleMean] {
            let params = HrParams {
                f_eps: 0.02,
                rays_per_link: 7,
                estimate,
                ..HrParams::default()
            };
            let run = run_hr(&kernel, &params, 9).unwrap();
            let stats = *run.approx.stats();
            assert_eq!(run.rays, stats.rays);
            assert_eq!(stats.rays, 7 * stats.links as u64);
            assert_eq!(run.basis_functions, stats.links);
            assert!(
                stats.zero_links > 0,
                "the blocker must hide some links entirely"
            );
            assert!(run.memory_bytes > 0);
            for link in run.approx.links() {
                assert!(link.value.is_finite() && link.value >= 0.0, "{link:?}");
            }
        }
    }

    #[test]
    fn unoccluded_links_are_exact_in_the_default_estimate() {
        // In the empty box no ray is blocked: every link holds exactly E'ρ I / (L_p L_q).
        let kernel = box_kernel();
        let hr = HierarchicalRadiosity::build(&kernel, &HrParams::default(), 1).unwrap();
        let surfaces = Surfaces::new(&kernel);
        for link in hr.links() {
            let ord = |e: EdgeId| surfaces.edge.iter().position(|&x| x == e.index()).unwrap();
            let (i, j) = (ord(link.sender), ord(link.receiver));
            let elem = |o: usize, [u0, u1]: [f64; 2]| {
                let f = |u| {
                    surfaces.a[o]
                        + (surfaces.b[o] - surfaces.a[o])
                            * ((u - surfaces.s0[o]) / (surfaces.s1[o] - surfaces.s0[o]))
                };
                Elem {
                    ord: o,
                    s0: u0,
                    s1: u1,
                    a: f(u0),
                    b: f(u1),
                }
            };
            let (p, q) = (elem(i, link.s), elem(j, link.t));
            let exact =
                surfaces.source_weight[i] * surfaces.reflectance[j] * surfaces.transfer(&p, &q)
                    / (p.length() * q.length());
            assert!(
                (link.value - exact).abs() <= 1e-9 * exact,
                "{link:?} vs {exact}"
            );
        }
    }
}
