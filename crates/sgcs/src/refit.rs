//! Refitting all output weights at once: ridge least squares for fixed centres and widths.
//!
//! Minimises `Σ_i |κ(ξ_i) − ζ_i|² + μ Σ_c |v_c|²` over every `v_c`, with the positions and
//! widths frozen. The design matrix `Φ_ic = M_c(ξ_i)` is sparse thanks to the activation cutoff;
//! the normal equations `(ΦᵀΦ + μ I) V = Φᵀ Z` are assembled sparsely (rows of `ΦᵀΦ` only hold
//! cells whose supports overlap) and solved by Jacobi-preconditioned conjugate gradients, one
//! output column at a time, warm-started from the current weights. The penalty is relative:
//! `μ = ridge · mean(diag ΦᵀΦ)`, so `ridge` is dimensionless (`1e-6` is a gentle choice).

use serde::{Deserialize, Serialize};

use crate::{Network, SgcsError};

/// What [`Network::refit_outputs`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefitReport {
    /// Number of samples used.
    pub samples: usize,
    /// Conjugate-gradient iterations (summed over output columns).
    pub iterations: usize,
    /// Largest final relative residual `|r| / |b|` over the output columns.
    pub relative_residual: f64,
    /// Root mean square training error before the refit.
    pub rms_before: f64,
    /// Root mean square training error after the refit.
    pub rms_after: f64,
}

/// Relative residual at which CG stops.
const TOLERANCE: f64 = 1e-10;

impl Network {
    /// Ridge least-squares refit of every output weight over the samples `inputs` (flat,
    /// `N · input_dim`) and `targets` (flat, `N · output_dim`), centres and widths fixed.
    /// `ridge > 0` is relative to the mean diagonal of `ΦᵀΦ` (see the module docs). Keeps the
    /// old weights, and reports so, when the refit would not lower the training error.
    pub fn refit_outputs(
        &mut self,
        inputs: &[f64],
        targets: &[f64],
        ridge: f64,
    ) -> Result<RefitReport, SgcsError> {
        let (n, m, len) = (self.input_dim(), self.output_dim(), self.len());
        if !(ridge > 0.0 && ridge.is_finite()) {
            return Err(SgcsError::InvalidParam {
                name: "ridge",
                range: "(0, inf)",
                value: ridge.to_string(),
            });
        }
        if !inputs.len().is_multiple_of(n) || inputs.is_empty() {
            return Err(SgcsError::Refit(format!(
                "inputs has length {}, not a positive multiple of input_dim {n}",
                inputs.len()
            )));
        }
        let samples = inputs.len() / n;
        if targets.len() != samples * m {
            return Err(SgcsError::Refit(format!(
                "targets has length {}, expected {samples} samples x output_dim {m}",
                targets.len()
            )));
        }
        if let Some(x) = inputs.iter().chain(targets).find(|x| !x.is_finite()) {
            return Err(SgcsError::Refit(format!("non-finite sample value {x}")));
        }

        // Φ in compressed rows (cells ascending within a row), and its transpose's pattern.
        let mut row_start = vec![0usize];
        let mut phi: Vec<(u32, f64)> = Vec::new();
        let mut found = Vec::new();
        let mut stack = Vec::new();
        let mut ids = Vec::new();
        for i in 0..samples {
            self.active_into(
                &inputs[i * n..(i + 1) * n],
                &mut stack,
                &mut ids,
                &mut found,
            );
            phi.extend_from_slice(&found);
            row_start.push(phi.len());
        }
        let mut col_rows: Vec<Vec<u32>> = vec![Vec::new(); len];
        for i in 0..samples {
            for &(c, _) in &phi[row_start[i]..row_start[i + 1]] {
                col_rows[c as usize].push(i as u32);
            }
        }

        // G = ΦᵀΦ, sparse rows, columns ascending.
        let mut g_start = vec![0usize];
        let mut g: Vec<(u32, f64)> = Vec::new();
        let mut acc = vec![0.0f64; len];
        let mut mark = vec![false; len];
        let mut touched: Vec<u32> = Vec::new();
        let mut diag = vec![0.0f64; len];
        for c in 0..len {
            touched.clear();
            for &i in &col_rows[c] {
                let i = i as usize;
                let row = &phi[row_start[i]..row_start[i + 1]];
                let mc = row.iter().find(|e| e.0 as usize == c).map_or(0.0, |e| e.1);
                for &(d, md) in row {
                    if !mark[d as usize] {
                        mark[d as usize] = true;
                        touched.push(d);
                    }
                    acc[d as usize] += mc * md;
                }
            }
            touched.sort_unstable();
            for &d in &touched {
                g.push((d, acc[d as usize]));
                if d as usize == c {
                    diag[c] = acc[d as usize];
                }
                acc[d as usize] = 0.0;
                mark[d as usize] = false;
            }
            g_start.push(g.len());
        }
        let mean_diag = diag.iter().sum::<f64>() / len as f64;
        let mu = ridge * mean_diag.max(f64::MIN_POSITIVE);

        let rms = |net: &Network| -> f64 {
            let mut s = 0.0;
            let mut out = vec![0.0; m];
            for i in 0..samples {
                let row = &phi[row_start[i]..row_start[i + 1]];
                out.fill(0.0);
                for &(c, a) in row {
                    for j in 0..m {
                        out[j] += net.output(c as usize)[j] * a;
                    }
                }
                for j in 0..m {
                    let e = out[j] - targets[i * m + j];
                    s += e * e;
                }
            }
            (s / (samples * m) as f64).sqrt()
        };
        let rms_before = rms(self);

        let matvec = |x: &[f64], y: &mut [f64]| {
            for c in 0..len {
                let mut s = mu * x[c];
                for &(d, v) in &g[g_start[c]..g_start[c + 1]] {
                    s += v * x[d as usize];
                }
                y[c] = s;
            }
        };
        let precond: Vec<f64> = diag.iter().map(|&d| 1.0 / (d + mu)).collect();
        let mut iterations = 0;
        let mut worst = 0.0f64;
        let old = self.out_flat_mut().clone();
        let mut new = old.clone();
        for j in 0..m {
            // b = Φᵀ z_j
            let mut b = vec![0.0; len];
            for i in 0..samples {
                let z = targets[i * m + j];
                for &(c, a) in &phi[row_start[i]..row_start[i + 1]] {
                    b[c as usize] += a * z;
                }
            }
            let mut x: Vec<f64> = (0..len).map(|c| old[c * m + j]).collect();
            let (it, res) = conjugate_gradient(&matvec, &precond, &b, &mut x, 20 * len + 100);
            iterations += it;
            worst = worst.max(res);
            if x.iter().all(|v| v.is_finite()) {
                for c in 0..len {
                    new[c * m + j] = x[c];
                }
            }
        }
        *self.out_flat_mut() = new;
        let rms_after = rms(self);
        if rms_after.is_nan() || rms_after > rms_before {
            *self.out_flat_mut() = old;
            return Ok(RefitReport {
                samples,
                iterations,
                relative_residual: worst,
                rms_before,
                rms_after: rms_before,
            });
        }
        Ok(RefitReport {
            samples,
            iterations,
            relative_residual: worst,
            rms_before,
            rms_after,
        })
    }
}

/// Preconditioned CG on an SPD operator; returns (iterations, relative residual).
fn conjugate_gradient(
    a: &dyn Fn(&[f64], &mut [f64]),
    precond: &[f64],
    b: &[f64],
    x: &mut [f64],
    max_iter: usize,
) -> (usize, f64) {
    let len = b.len();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    let b_norm = norm(b);
    if b_norm == 0.0 {
        x.fill(0.0);
        return (0, 0.0);
    }
    let mut ax = vec![0.0; len];
    a(x, &mut ax);
    let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let mut z: Vec<f64> = r.iter().zip(precond).map(|(r, p)| r * p).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; len];
    for it in 0..max_iter {
        let res = norm(&r) / b_norm;
        if res <= TOLERANCE {
            return (it, res);
        }
        a(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            return (it, res);
        }
        let alpha = rz / pap;
        for i in 0..len {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        for i in 0..len {
            z[i] = r[i] * precond[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..len {
            p[i] = z[i] + beta * p[i];
        }
    }
    (max_iter, norm(&r) / b_norm)
}
