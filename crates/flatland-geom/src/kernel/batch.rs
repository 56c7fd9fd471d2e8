//! Batch evaluation: `k` and `ζ` at many `(s, t)` and on grids, in parallel chunks (rayon).

use rayon::prelude::*;

use super::Kernel;

/// Evaluations per rayon task in the batch and grid paths: a plain loop over a chunk keeps the
/// kernel inlined, and 1024 evaluations outweigh a task's overhead.
const BATCH_CHUNK: usize = 1024;

impl Kernel {
    /// `k` for many `(s, t)` in parallel (rayon); the result does not depend on the thread count.
    #[must_use]
    pub fn k_batch(&self, st: &[[f64; 2]]) -> Vec<f64> {
        self.batch(st.len(), |i| st[i], |s, t| self.k(s, t))
    }

    /// `ζ` for many `(s, t)` in parallel (rayon); deterministic.
    #[must_use]
    pub fn zeta_batch(&self, st: &[[f64; 2]]) -> Vec<f64> {
        self.batch(st.len(), |i| st[i], |s, t| self.zeta(s, t))
    }

    /// `k` (or `ζ` if `weighted`) on a `res × res` grid of cell centres, row-major: row `i` is
    /// `s = (i + 0.5) / res`, column `j` is `t = (j + 0.5) / res`. Parallel, deterministic.
    #[must_use]
    pub fn grid(&self, res: usize, weighted: bool) -> Vec<f64> {
        let n = res as f64;
        let at = |idx: usize| {
            [
                ((idx / res) as f64 + 0.5) / n,
                ((idx % res) as f64 + 0.5) / n,
            ]
        };
        if weighted {
            self.batch(res * res, at, |s, t| self.zeta(s, t))
        } else {
            self.batch(res * res, at, |s, t| self.k(s, t))
        }
    }

    /// `f` at the `len` points `at(0..len)`, in chunks, each a plain loop: a per-item rayon
    /// closure kept the kernel from being inlined, 14 % slower per sample on one thread than a
    /// loop over [`Kernel::k`].
    fn batch(
        &self,
        len: usize,
        at: impl Fn(usize) -> [f64; 2] + Sync,
        f: impl Fn(f64, f64) -> f64 + Sync,
    ) -> Vec<f64> {
        let mut out = vec![0.0; len];
        out.par_chunks_mut(BATCH_CHUNK)
            .enumerate()
            .for_each(|(chunk, out)| {
                for (j, o) in out.iter_mut().enumerate() {
                    let [s, t] = at(chunk * BATCH_CHUNK + j);
                    *o = f(s, t);
                }
            });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, rng};
    use rand::RngExt;

    #[test]
    fn batch_and_grid_match_single_evaluation() {
        let kernel = Kernel::new(bundled("fig3"));
        let mut r = rng(7);
        let st: Vec<[f64; 2]> = (0..5000)
            .map(|_| [r.random_range(0.0..1.0), r.random_range(0.0..1.0)])
            .collect();
        let k = kernel.k_batch(&st);
        let z = kernel.zeta_batch(&st);
        for (i, &[s, t]) in st.iter().enumerate() {
            assert_eq!(k[i], kernel.k(s, t));
            assert_eq!(z[i], kernel.zeta(s, t));
        }
        let res = 7;
        let g = kernel.grid(res, true);
        assert_eq!(g.len(), res * res);
        assert_eq!(g[2 * res + 5], kernel.zeta(2.5 / 7.0, 5.5 / 7.0));
        assert_eq!(
            kernel.grid(res, false)[3 * res + 1],
            kernel.k(3.5 / 7.0, 1.5 / 7.0)
        );
    }
}
