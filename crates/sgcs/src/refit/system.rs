//! The assembled normal equations of a refit, and how well given weights fit them.

use faer::sparse::linalg::cholesky::SymbolicCholesky;

/// The normal equations of a refit for one sample set and one state of the centres and
/// widths: the lower triangle of `ΦᵀΦ` over all samples (in a fill-reducing order), `Φᵀz` and
/// `|z|²`, and the rows of the held-back samples, which are few (they score fits, and are
/// subtracted again to fit without them); plus the symbolic Cholesky factorisation. Build it
/// once with [`Network::refit_system`] (or [`Network::refit_system_split`]); then each ridge
/// costs one numeric factorisation ([`RefitSystem::solve`]) and no sample is visited again.
///
/// [`Network::refit_system`]: crate::Network::refit_system
/// [`Network::refit_system_split`]: crate::Network::refit_system_split
pub struct RefitSystem {
    /// `(steps, len, cutoff bits)` of the network it was built for.
    pub(super) fingerprint: (u64, usize, u64),
    pub(super) m: usize,
    pub(super) len: usize,
    /// Samples: all, held back.
    pub(super) samples: usize,
    /// Lower triangle of `ΦᵀΦ` in compressed columns, rows and columns in the fill-reducing
    /// order (`position[c]` is cell `c`'s place), rows ascending, diagonal first.
    pub(super) col_ptr: Vec<u32>,
    pub(super) row_idx: Vec<u32>,
    pub(super) values: Vec<f64>,
    pub(super) position: Vec<u32>,
    /// `Φᵀ z_j` over all samples, output-major in the fill-reducing order.
    pub(super) rhs: Vec<f64>,
    /// `|z_j|²` over all samples.
    pub(super) zz: Vec<f64>,
    /// The held-back samples' rows (cells ascending) and targets.
    pub(super) held_rows: Vec<(u32, f64)>,
    pub(super) held_start: Vec<usize>,
    pub(super) held_targets: Vec<f64>,
    pub(super) symbolic: SymbolicCholesky<u32>,
}

impl std::fmt::Debug for RefitSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RefitSystem")
            .field("cells", &self.len)
            .field("samples", &self.samples)
            .field("held_back", &self.held_back())
            .field("nonzeros", &self.row_idx.len())
            .finish()
    }
}

impl RefitSystem {
    /// Number of samples (held back included).
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Number of held-back samples.
    pub fn held_back(&self) -> usize {
        self.held_start.len() - 1
    }

    /// Nonzeros of the lower triangle of `ΦᵀΦ`.
    pub fn nonzeros(&self) -> usize {
        self.row_idx.len()
    }

    /// Nonzeros of the Cholesky factor.
    pub fn factor_nonzeros(&self) -> usize {
        self.symbolic.len_val()
    }

    /// The row of `Φ` of held-back sample `h`: `(cell, weight)`, cells ascending.
    pub(super) fn held_row(&self, h: usize) -> &[(u32, f64)] {
        &self.held_rows[self.held_start[h]..self.held_start[h + 1]]
    }

    /// `y = G x` for the symmetric `G` of which `values` is the lower triangle (permuted).
    pub(super) fn sym_matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for c in 0..self.len {
            let (a, b) = (self.col_ptr[c] as usize, self.col_ptr[c + 1] as usize);
            for k in a..b {
                let d = self.row_idx[k] as usize;
                let v = values[k];
                y[d] += v * x[c];
                if d != c {
                    y[c] += v * x[d];
                }
            }
        }
    }

    /// `Σ |Φ_h v − z_h|²` over the held-back samples, `v` cell-major.
    fn held_squared_error(&self, weights: &[f64]) -> f64 {
        let m = self.m;
        let mut total = 0.0;
        for h in 0..self.held_back() {
            for j in 0..m {
                let predicted: f64 = self
                    .held_row(h)
                    .iter()
                    .map(|&(c, a)| a * weights[c as usize * m + j])
                    .sum();
                total += (predicted - self.held_targets[h * m + j]).powi(2);
            }
        }
        total
    }

    /// `Σ_i |Φ_i v − z_i|²` over all samples from the normal equations:
    /// `vᵀ G v − 2 vᵀ b + |z|²` per output, `v` cell-major (as the network stores it).
    fn squared_error(&self, weights: &[f64]) -> f64 {
        let (len, m) = (self.len, self.m);
        let mut x = vec![0.0; len];
        let mut gx = vec![0.0; len];
        let mut total = 0.0;
        for j in 0..m {
            for c in 0..len {
                x[self.position[c] as usize] = weights[c * m + j];
            }
            self.sym_matvec(&self.values, &x, &mut gx);
            let b = &self.rhs[j * len..(j + 1) * len];
            let quadratic: f64 = x.iter().zip(&gx).map(|(a, b)| a * b).sum();
            let linear: f64 = x.iter().zip(b).map(|(a, b)| a * b).sum();
            total += quadratic - 2.0 * linear + self.zz[j];
        }
        // Rounding can leave a tiny negative for a near-perfect fit.
        total.max(0.0)
    }

    /// Relative L2 error `|Φ_h v − z_h| / |z_h|` of the weights `v` (cell-major, as
    /// [`Network::outputs`] stores them) on the held-back samples; `None` when none was held
    /// back.
    ///
    /// [`Network::outputs`]: crate::Network::outputs
    pub fn validation_error(&self, weights: &[f64]) -> Option<f64> {
        if self.held_back() == 0 {
            return None;
        }
        let zz: f64 = self.held_targets.iter().map(|z| z * z).sum();
        let e = self.held_squared_error(weights);
        Some(if zz > 0.0 { (e / zz).sqrt() } else { e.sqrt() })
    }

    /// The root mean square error of `weights` over all samples.
    pub(super) fn rms(&self, weights: &[f64]) -> f64 {
        (self.squared_error(weights) / (self.samples * self.m).max(1) as f64).sqrt()
    }
}
