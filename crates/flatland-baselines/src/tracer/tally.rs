//! Tallies: one batch's deposits, and the batches merged in order into B and its standard error.

use flatland_solve::Mesh;

use super::PowerBalance;
use super::emitters::Emitters;

/// What one batch's photons left behind, in units of one photon's power.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct BatchTally {
    /// Power landed on each element (on its front).
    pub deposits: Vec<f64>,
    /// Power absorbed at the end of a path (reflectance, blocker, back side, bounce limit).
    pub absorbed: f64,
    /// Power that left the scene.
    pub escaped: f64,
    /// Rays cast.
    pub rays: u64,
}

impl BatchTally {
    pub(super) fn new(elements: usize) -> BatchTally {
        BatchTally {
            deposits: vec![0.0; elements],
            absorbed: 0.0,
            escaped: 0.0,
            rays: 0,
        }
    }
}

/// The batches so far, merged in batch order (so a seed's result never depends on the thread
/// count): per element, the mean and the sum of squared deviations (Welford) of the batches'
/// deposits per photon.
#[derive(Clone, Debug)]
pub(super) struct Tallies {
    size: u64,
    mean: Vec<f64>,
    m2: Vec<f64>,
    batches: u64,
    absorbed: f64,
    escaped: f64,
    rays: u64,
}

impl Tallies {
    /// No batches yet, of `size` photons each, over `elements` elements.
    pub(super) fn new(elements: usize, size: u64) -> Tallies {
        Tallies {
            size,
            mean: vec![0.0; elements],
            m2: vec![0.0; elements],
            batches: 0,
            absorbed: 0.0,
            escaped: 0.0,
            rays: 0,
        }
    }

    /// Merges the next batch.
    pub(super) fn add(&mut self, batch: &BatchTally) {
        self.batches += 1;
        let (n, size) = (self.batches as f64, self.size as f64);
        for ((mean, m2), &deposit) in self.mean.iter_mut().zip(&mut self.m2).zip(&batch.deposits) {
            let x = deposit / size;
            let delta = x - *mean;
            *mean += delta / n;
            *m2 += delta * (x - *mean);
        }
        self.absorbed += batch.absorbed;
        self.escaped += batch.escaped;
        self.rays += batch.rays;
    }

    /// Batches merged.
    pub(super) fn batches(&self) -> u64 {
        self.batches
    }

    /// Rays the merged batches cast.
    pub(super) fn rays(&self) -> u64 {
        self.rays
    }

    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        (self.mean.len() + self.m2.len()) * size_of::<f64>()
    }

    /// `B` per element, its standard error, and where the power went. A photon carries
    /// `Φ / photons` of the emitters' power `Φ`, so `H_i = mean_i · Φ / length_i`.
    pub(super) fn estimate(
        &self,
        mesh: &Mesh,
        emitters: &Emitters,
    ) -> (Vec<f64>, Vec<f64>, PowerBalance) {
        let power = emitters.power();
        let nb = self.batches as f64;
        let (mut radiosity, mut std_error) = (Vec::new(), Vec::new());
        for (i, element) in mesh.elements().iter().enumerate() {
            let edge = &mesh.edges()[element.mesh_edge];
            let per_length = power / element.length;
            let spread = (self.m2[i] / (nb - 1.0) / nb).sqrt();
            let error = if self.batches >= 2 { spread } else { f64::NAN };
            radiosity.push(
                emitters.emission(element.mesh_edge) + edge.reflectance * self.mean[i] * per_length,
            );
            std_error.push(edge.reflectance * error * per_length);
        }
        let photons = (self.batches * self.size) as f64;
        let share = |p: f64| {
            if photons > 0.0 {
                power * p / photons
            } else {
                0.0
            }
        };
        let balance = PowerBalance {
            emitted: if photons > 0.0 { power } else { 0.0 },
            absorbed: share(self.absorbed),
            escaped: share(self.escaped),
        };
        (radiosity, std_error, balance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn batches_merge_into_the_mean_and_spread_of_their_means() {
        let mut tallies = Tallies::new(2, 4);
        let deposits = [[4.0, 0.0], [8.0, 2.0], [0.0, 4.0], [4.0, 2.0]];
        for d in deposits {
            let mut batch = BatchTally::new(2);
            batch.deposits = d.to_vec();
            batch.absorbed = 4.0;
            batch.rays = 6;
            tallies.add(&batch);
        }
        // Per photon: element 0 sees 1, 2, 0, 1 (mean 1, variance 2/3); element 1 sees 0,
        // 0.5, 1, 0.5 (mean 0.5, variance 1/6).
        assert_eq!((tallies.batches(), tallies.rays()), (4, 24));
        assert!((tallies.mean[0] - 1.0).abs() < 1e-15 && (tallies.mean[1] - 0.5).abs() < 1e-15);
        assert_close!(tallies.m2[0] / 3.0, 2.0 / 3.0, 1e-15);
        assert_close!(tallies.m2[1] / 3.0, 1.0 / 6.0, 1e-15);
        assert_eq!(tallies.absorbed, 16.0);
    }
}
