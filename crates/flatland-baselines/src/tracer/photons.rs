//! One batch of photons: stratified starts, cosine directions, bounces until absorbed or gone.

use flatland_geom::{DVec2, Kernel};
use flatland_solve::Mesh;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::emitters::{Emitters, Leaving, Start};
use super::tally::BatchTally;

/// Bounces after which a photon is counted absorbed: it would carry `ρ^1000` of its power.
const MAX_BOUNCES: usize = 1000;

/// A batch: `size` photons stratified over the emitters, drawn from `rng` (its own stream).
pub(super) struct Batch<'t> {
    pub kernel: &'t Kernel,
    pub mesh: &'t Mesh,
    /// The mesh edge of each scene edge (`None` for a blocker).
    pub surface_of: &'t [Option<u32>],
    pub emitters: &'t Emitters,
    pub rng: ChaCha8Rng,
    pub size: u64,
}

impl Batch<'_> {
    /// Traces every photon of the batch; power in units of one photon's.
    pub(super) fn trace(mut self) -> BatchTally {
        let mut tally = BatchTally::new(self.mesh.len());
        let below_one = 1.0 - f64::EPSILON / 2.0;
        for k in 0..self.size {
            let u = (k as f64 + self.rng.random::<f64>()) / self.size as f64;
            let start = self.emitters.start(u.min(below_one));
            self.photon(start, &mut tally);
        }
        tally
    }

    /// One photon from `start` until it is absorbed or leaves.
    fn photon(&mut self, start: Start, tally: &mut BatchTally) {
        let (mut x, mut skip, mut leaving, power) = (start.point, start.skip, start.leaving, 1.0);
        for _ in 0..MAX_BOUNCES {
            let d = match leaving {
                Leaving::About(normal) => cosine_direction(normal, self.rng.random::<f64>()),
                Leaving::Along(d) => d,
            };
            tally.rays += 1;
            let Some(hit) = self.kernel.first_hit(x, d, skip) else {
                tally.escaped += power;
                return;
            };
            let Some(m) = self.surface_of[hit.edge.index()] else {
                tally.absorbed += power; // a blocker
                return;
            };
            let edge = &self.mesh.edges()[m as usize];
            if d.dot(edge.normal) >= 0.0 {
                tally.absorbed += power; // the back of a surface (or edge-on)
                return;
            }
            let s = self
                .kernel
                .scene()
                .param_of(hit.edge, hit.point)
                .expect("a surface edge has a parameter");
            tally.deposits[self.mesh.element_at(s)] += power;
            // Russian roulette on ρ: the power goes on unchanged or not at all (no draw for
            // ρ = 1, which always goes on).
            if edge.reflectance < 1.0 && self.rng.random::<f64>() >= edge.reflectance {
                tally.absorbed += power;
                return;
            }
            (x, skip) = (hit.point, Some(hit.edge));
            leaving = Leaving::About(edge.normal);
        }
        tally.absorbed += power;
    }
}

/// A direction of density `cos θ / 2` about `normal` from a uniform `xi ∈ [0, 1)`:
/// `sin θ = 2 xi − 1`, towards `perp(normal)` for positive `sin θ`.
pub(super) fn cosine_direction(normal: DVec2, xi: f64) -> DVec2 {
    let sin = 2.0 * xi - 1.0;
    let cos = (1.0 - sin * sin).max(0.0).sqrt();
    normal * cos + normal.perp() * sin
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn directions_are_cosine_distributed_about_the_normal() {
        // Under density cos θ / 2 on (−π/2, π/2): E[cos θ] = π/4, E[sin² θ] = 1/3, and no
        // direction points behind.
        let normal = DVec2::new(0.6, 0.8);
        let n = 100_000;
        let (mut cos_sum, mut sin2_sum) = (0.0, 0.0);
        for k in 0..n {
            let d = cosine_direction(normal, (k as f64 + 0.5) / n as f64);
            assert!((d.length() - 1.0).abs() < 1e-12 && d.dot(normal) >= 0.0);
            cos_sum += d.dot(normal);
            sin2_sum += d.perp_dot(normal).powi(2);
        }
        assert_close!(cos_sum / n as f64, std::f64::consts::FRAC_PI_4, 1e-6);
        assert_close!(sin2_sum / n as f64, 1.0 / 3.0, 1e-6);
        let tangent = cosine_direction(normal, 1.0);
        assert!((tangent - normal.perp()).length() < 1e-12);
    }
}
