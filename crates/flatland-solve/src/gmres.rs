//! Restarted GMRES for `(I − K) B = E`.
//!
//! Why GMRES and not Jacobi or Gauss–Seidel: K's row sums are ρ in a closed room, so the Neumann
//! series converges like `(max ρ)^n` at best, slowly for white walls. GMRES needs only that
//! `I − K` be invertible, and on the bundled scenes reaches 1e-10 in 10–20 products with K.

use crate::{SolveError, Stop, TransferOperator};

/// Krylov vectors kept before a restart.
const RESTART: usize = 40;

/// What a converged solve reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Converged {
    /// Products with K (Krylov steps).
    pub iterations: usize,
    /// Final true relative residual `‖E − (I − K) B‖ / ‖E‖`.
    pub residual: f64,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    // Scaled, so a radiosity of 1e200 neither overflows nor loses the residual.
    let scale = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return scale;
    }
    scale * a.iter().map(|v| (v / scale).powi(2)).sum::<f64>().sqrt()
}

/// `out = x − K x`.
fn apply_system(op: &dyn TransferOperator, x: &[f64], out: &mut [f64]) {
    op.apply(x, out);
    for (o, xi) in out.iter_mut().zip(x) {
        *o = xi - *o;
    }
}

/// How a solve decides it has converged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Finish {
    /// Once the Arnoldi estimate meets the tolerance, one more product with K computes the
    /// true residual, and the solve goes on if it does not meet it: what every one-off solve
    /// reports.
    TrueResidual,
    /// The Arnoldi estimate is the residual (exact in exact arithmetic): one product with K
    /// less per solve, for the many small solves of a relighting.
    Estimate,
}

/// What a solve keeps between calls: the Krylov basis, the Hessenberg columns, the rotations
/// and two work vectors, allocated on the first solve of a size and reused after it.
#[derive(Clone, Debug, Default)]
pub(crate) struct Gmres {
    basis: Vec<Vec<f64>>,
    h: Vec<Vec<f64>>,
    rotations: Vec<(f64, f64)>,
    g: Vec<f64>,
    y: Vec<f64>,
    r: Vec<f64>,
    w: Vec<f64>,
}

/// Solves `x − K x = e` to relative residual `tolerance`, starting from `x`. Polls `stop`
/// before every product with K.
pub(crate) fn solve(
    op: &dyn TransferOperator,
    e: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
    stop: &Stop,
) -> Result<Converged, SolveError> {
    Gmres::default().solve(
        op,
        e,
        x,
        Limits {
            tolerance,
            max_iterations,
            finish: Finish::TrueResidual,
        },
        stop,
    )
}

/// When a solve stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Limits {
    /// The relative residual to reach.
    pub tolerance: f64,
    /// Most products with K in the Krylov steps.
    pub max_iterations: usize,
    /// How convergence is decided.
    pub finish: Finish,
}

impl Gmres {
    /// Bytes its vectors hold (as allocated).
    pub(crate) fn memory_bytes(&self) -> usize {
        let vectors = self.basis.iter().chain(&self.h).map(Vec::capacity);
        8 * (vectors.sum::<usize>()
            + self.g.capacity()
            + self.y.capacity()
            + self.r.capacity()
            + self.w.capacity())
            + 16 * self.rotations.capacity()
    }

    /// Sizes the work space for `n` elements and restarts of `m` steps (allocating only the
    /// first time, or when `n` grows). Nothing is cleared: every vector is written before it
    /// is read.
    fn prepare(&mut self, n: usize, m: usize) {
        let sized = |v: &mut Vec<f64>, len: usize| v.resize(len, 0.0);
        sized(&mut self.r, n);
        sized(&mut self.w, n);
        self.basis.resize_with(m + 1, Vec::new);
        for v in &mut self.basis {
            sized(v, n);
        }
        self.h.resize_with(m, Vec::new);
        for column in &mut self.h {
            sized(column, m + 1);
        }
        sized(&mut self.g, m + 1);
        sized(&mut self.y, m);
    }

    /// Solves `x − K x = e` within `limits`, starting from `x`. Polls `stop` before every
    /// product with K.
    pub(crate) fn solve(
        &mut self,
        op: &dyn TransferOperator,
        e: &[f64],
        x: &mut [f64],
        limits: Limits,
        stop: &Stop,
    ) -> Result<Converged, SolveError> {
        let n = e.len();
        let norm_e = norm(e);
        if norm_e == 0.0 {
            x.fill(0.0);
            return Ok(Converged {
                iterations: 0,
                residual: 0.0,
            });
        }
        let Limits {
            tolerance,
            max_iterations,
            finish,
        } = limits;
        let m = RESTART.min(n).max(1);
        self.prepare(n, m);
        let mut iterations = 0;
        loop {
            if stop() {
                return Err(SolveError::Interrupted);
            }
            apply_system(op, x, &mut self.r);
            for (ri, ei) in self.r.iter_mut().zip(e) {
                *ri = ei - *ri;
            }
            let beta = norm(&self.r);
            let residual = beta / norm_e;
            if !residual.is_finite() || (residual > tolerance && iterations >= max_iterations) {
                return Err(SolveError::NotConverged {
                    iterations,
                    residual,
                    tolerance,
                });
            }
            if residual <= tolerance {
                return Ok(Converged {
                    iterations,
                    residual,
                });
            }
            let (steps, estimate) = self.cycle(op, beta, norm_e, limits, iterations, stop)?;
            iterations += steps;
            let y = &mut self.y[..steps];
            back_substitute(&self.h, &self.g, y);
            for (yi, v) in y.iter().zip(&self.basis) {
                x.iter_mut().zip(v).for_each(|(xi, vi)| *xi += yi * vi);
            }
            if finish == Finish::Estimate && estimate <= tolerance {
                return Ok(Converged {
                    iterations,
                    residual: estimate,
                });
            }
        }
    }

    /// One cycle of Krylov steps from the residual in `self.r` (norm `beta`): the steps made
    /// and the estimated relative residual after them.
    fn cycle(
        &mut self,
        op: &dyn TransferOperator,
        beta: f64,
        norm_e: f64,
        limits: Limits,
        done: usize,
        stop: &Stop,
    ) -> Result<(usize, f64), SolveError> {
        let m = self.h.len();
        for (b, r) in self.basis[0].iter_mut().zip(&self.r) {
            *b = r / beta;
        }
        self.rotations.clear();
        self.g.fill(0.0);
        self.g[0] = beta;
        let mut steps = 0;
        let mut estimate = beta / norm_e;
        for k in 0..m {
            if stop() {
                return Err(SolveError::Interrupted);
            }
            apply_system(op, &self.basis[k], &mut self.w);
            let column = &mut self.h[k];
            column.fill(0.0);
            let next = orthogonalize(&mut self.w, &self.basis[..=k], column);
            column[k + 1] = next;
            let (c, s) = rotate(column, k, &mut self.rotations);
            self.g[k + 1] = -s * self.g[k];
            self.g[k] *= c;
            steps = k + 1;
            estimate = self.g[k + 1].abs() / norm_e;
            if estimate <= limits.tolerance || done + steps >= limits.max_iterations || next == 0.0
            {
                break;
            }
            let (w, basis) = (&self.w, &mut self.basis[k + 1]);
            basis.iter_mut().zip(w).for_each(|(b, wi)| *b = wi / next);
        }
        Ok((steps, estimate))
    }
}

/// Modified Gram–Schmidt of `w` against `basis`, twice where it cancelled badly (keeps V
/// orthonormal); the coefficients go into the Hessenberg column `h`. Returns `‖w‖` after.
fn orthogonalize(w: &mut [f64], basis: &[Vec<f64>], h: &mut [f64]) -> f64 {
    let before = norm(w);
    for (j, v) in basis.iter().enumerate() {
        let c = dot(w, v);
        h[j] = c;
        w.iter_mut().zip(v).for_each(|(wi, vi)| *wi -= c * vi);
    }
    if norm(w) < 0.5 * before {
        for (j, v) in basis.iter().enumerate() {
            let c = dot(w, v);
            h[j] += c;
            w.iter_mut().zip(v).for_each(|(wi, vi)| *wi -= c * vi);
        }
    }
    norm(w)
}

/// Applies the earlier Givens rotations to Hessenberg column `h` (step `k`), then the new one
/// that zeroes its subdiagonal, which it keeps and returns as `(cos, sin)`.
fn rotate(h: &mut [f64], k: usize, rotations: &mut Vec<(f64, f64)>) -> (f64, f64) {
    for (j, &(c, s)) in rotations.iter().enumerate() {
        let (a, b) = (h[j], h[j + 1]);
        h[j] = c * a + s * b;
        h[j + 1] = -s * a + c * b;
    }
    let (a, b) = (h[k], h[k + 1]);
    let rho = a.hypot(b);
    let (c, s) = if rho == 0.0 {
        (1.0, 0.0)
    } else {
        (a / rho, b / rho)
    };
    rotations.push((c, s));
    h[k] = rho;
    h[k + 1] = 0.0;
    (c, s)
}

/// The Krylov coefficients of the first `steps` columns: back substitution in the rotated
/// (upper-triangular) Hessenberg matrix, column-major in `h`.
fn back_substitute(h: &[Vec<f64>], g: &[f64], y: &mut [f64]) {
    let steps = y.len();
    for i in (0..steps).rev() {
        let sum: f64 = (i + 1..steps).map(|j| h[j][i] * y[j]).sum();
        y[i] = if h[i][i] == 0.0 {
            0.0
        } else {
            (g[i] - sum) / h[i][i]
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DenseOperator, never};
    use rand::RngExt;

    /// Gaussian elimination with partial pivoting: the independent answer.
    fn direct(k: &[f64], e: &[f64]) -> Vec<f64> {
        let n = e.len();
        let mut a: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let mut row: Vec<f64> = (0..n)
                    .map(|j| f64::from(u8::from(i == j)) - k[i * n + j])
                    .collect();
                row.push(e[i]);
                row
            })
            .collect();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
                .unwrap();
            a.swap(c, p);
            let pivot = a[c].clone();
            for row in a.iter_mut().skip(c + 1) {
                let f = row[c] / pivot[c];
                row.iter_mut()
                    .zip(&pivot)
                    .skip(c)
                    .for_each(|(v, p)| *v -= f * p);
            }
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
            x[i] = (a[i][n] - s) / a[i][i];
        }
        x
    }

    #[test]
    fn gmres_matches_elimination_on_random_systems_including_non_contractive_ones() {
        let mut rng = flatland_testkit::rng(9);
        for (n, scale) in [(1, 0.5), (5, 0.9), (60, 1.5), (130, 3.0)] {
            // Row sums up to `scale`: beyond 1 the Neumann series diverges, GMRES does not care.
            let k: Vec<f64> = (0..n * n)
                .map(|_| rng.random_range(0.0..1.0) * scale / n as f64 * 1.9)
                .collect();
            let e: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..1.0)).collect();
            let op = DenseOperator::assemble(
                n,
                |i, row| row.copy_from_slice(&k[i * n..(i + 1) * n]),
                &never,
            )
            .unwrap();
            let mut x = e.clone();
            let done = solve(&op, &e, &mut x, 1e-12, 1000, &never).unwrap();
            let expected = direct(&k, &e);
            for i in 0..n {
                assert!(
                    (x[i] - expected[i]).abs() <= 1e-9 * expected[i].abs().max(1.0),
                    "n = {n}: x[{i}] = {} vs {}",
                    x[i],
                    expected[i]
                );
            }
            assert!(done.residual <= 1e-12, "{done:?}");
        }
    }

    #[test]
    fn zero_emission_singular_systems_and_stops() {
        // Rows of ½ ½: every row sums to exactly 1 in floating point too.
        let op = DenseOperator::assemble(2, |_, row| row.fill(0.5), &never).unwrap();
        // E = 0: B = 0 without a product.
        let mut x = vec![5.0; 2];
        let done = solve(&op, &[0.0; 2], &mut x, 1e-10, 100, &never).unwrap();
        assert_eq!((x, done.iterations), (vec![0.0; 2], 0));
        // Rows summing to exactly 1 and light inside: I − K is singular, no finite answer.
        let mut x = vec![1.0; 2];
        let err = solve(&op, &[1.0, 0.0], &mut x, 1e-10, 50, &never).unwrap_err();
        assert!(matches!(err, SolveError::NotConverged { .. }), "{err}");
        assert!(x.iter().all(|v| v.is_finite()));
        let err = solve(&op, &[1.0, 0.0], &mut [1.0; 2], 1e-10, 50, &|| true).unwrap_err();
        assert!(matches!(err, SolveError::Interrupted));
    }
}
