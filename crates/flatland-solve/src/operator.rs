//! Discrete transfer operators: `(K b)_i = Σ_j K_ij b_j`, the light element `j` sends to the
//! collocation point of element `i` (reflectance included), for B constant per element.

use rayon::prelude::*;

use crate::{MAX_ELEMENTS, Mesh, SolveError, Stop};

/// The discrete operator K of `B = E + K B` on a [`Mesh`]: what a solver iterates with.
pub trait TransferOperator: Send + Sync {
    /// Number of elements N.
    fn len(&self) -> usize;

    /// Whether N = 0.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `out = K b` (both of length N).
    fn apply(&self, b: &[f64], out: &mut [f64]);
}

/// A dense N × N operator, row-major, row = receiver element.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseOperator {
    n: usize,
    k: Vec<f64>,
}

/// Rows per rayon task: long enough that scheduling is noise, short enough to balance 2 cores.
const ROWS_PER_TASK: usize = 8;

impl DenseOperator {
    /// Fills row `i` (receiver element `i`, all N senders) with `row(i, &mut row)`, rows in
    /// parallel. `stop` is polled once per row; when it says so the assembly ends with
    /// [`SolveError::Interrupted`]. Entries that are not finite are an error (they would poison
    /// the solve), naming the row and column. More than [`MAX_ELEMENTS`] rows are refused
    /// before anything is allocated.
    pub fn assemble(
        n: usize,
        row: impl Fn(usize, &mut [f64]) + Sync,
        stop: &Stop,
    ) -> Result<DenseOperator, SolveError> {
        check_dense(n)?;
        let mut k = vec![0.0; n * n];
        if n > 0 {
            k.par_chunks_mut(n)
                .with_min_len(ROWS_PER_TASK)
                .enumerate()
                .try_for_each(|(i, out)| {
                    if stop() {
                        return Err(SolveError::Interrupted);
                    }
                    row(i, out);
                    match out.iter().position(|v| !v.is_finite()) {
                        Some(j) => Err(SolveError::NonFiniteOperator { row: i, column: j }),
                        None => Ok(()),
                    }
                })?;
        }
        Ok(DenseOperator { n, k })
    }

    /// Entry `K_ij`.
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.k[i * self.n + j]
    }

    /// Row `i`.
    #[must_use]
    pub fn row(&self, i: usize) -> &[f64] {
        &self.k[i * self.n..(i + 1) * self.n]
    }

    /// Bytes the operator holds in memory (its N² numbers).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<DenseOperator>() + 8 * self.k.capacity()
    }
}

/// Refuses a dense operator of more than [`MAX_ELEMENTS`] elements; the error names the limit.
pub(crate) fn check_dense(n: usize) -> Result<(), SolveError> {
    if n > MAX_ELEMENTS {
        return Err(SolveError::InvalidParameter {
            name: "elements",
            value: n.to_string(),
            valid: "at most 8192 where the operator is dense (N² numbers)",
        });
    }
    Ok(())
}

impl TransferOperator for DenseOperator {
    fn len(&self) -> usize {
        self.n
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        let n = self.n;
        out.par_iter_mut()
            .with_min_len(4 * ROWS_PER_TASK)
            .enumerate()
            .for_each(|(i, o)| {
                let row = &self.k[i * n..(i + 1) * n];
                // Four accumulators: independent chains the CPU can overlap.
                let mut acc = [0.0; 4];
                let (rows, rest) = row.as_chunks::<4>();
                let (bs, brest) = b.as_chunks::<4>();
                for (r, x) in rows.iter().zip(bs) {
                    for l in 0..4 {
                        acc[l] += r[l] * x[l];
                    }
                }
                let tail: f64 = rest.iter().zip(brest).map(|(r, x)| r * x).sum();
                *o = (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail;
            });
    }
}

/// A kernel that is constant on rectangles of the `(s, t)` square: `k̃(s, t) = k` for
/// `s ∈ [s0, s1)`, `t ∈ [t0, t1)` (HR's links, the uniform grid's blocks).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelRectangle {
    /// Sender interval `[s0, s1)`.
    pub s: [f64; 2],
    /// Receiver interval `[t0, t1)`.
    pub t: [f64; 2],
    /// The value of k̃ on it.
    pub k: f64,
}

/// The operator of a piecewise-constant kernel, applied as hierarchical radiosity applies its
/// links, with the mesh as the leaf level:
///
/// - **pull**: the mean B over each rectangle's sender interval (any interval, not only whole
///   elements) from prefix sums of the element values: `∫_{s0}^{s1} B L ds`;
/// - **gather**: each rectangle carries `k · ∫ B L ds` to its receiver interval;
/// - **push**: what a receiver interval gathered reaches every collocation point under it (a
///   difference array over the points, summed once).
///
/// One application costs O(rectangles + N), and it is exact for the rectangles (no quadrature):
/// the same numbers as integrating k̃ against the piecewise-constant B.
#[derive(Clone, Debug, PartialEq)]
pub struct RectangleOperator {
    /// Element start parameters and lengths, for the prefix sums.
    starts: Vec<f64>,
    lengths: Vec<f64>,
    total_length: f64,
    /// Per rectangle: sender interval as (element, offset in arc length) at both ends,
    /// receiver point range, value.
    links: Vec<Link>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Link {
    from: (usize, f64),
    to: (usize, f64),
    receivers: (usize, usize),
    k: f64,
}

impl RectangleOperator {
    /// The operator of `rectangles` on `mesh`. Rectangles whose receiver interval holds no
    /// collocation point, or whose value is 0, are dropped.
    #[must_use]
    pub fn new(mesh: &Mesh, rectangles: impl IntoIterator<Item = KernelRectangle>) -> Self {
        let els = mesh.elements();
        let l = mesh.total_length();
        let mids: Vec<f64> = els.iter().map(|e| e.s_mid).collect();
        let starts: Vec<f64> = els.iter().map(|e| e.s[0]).collect();
        let locate = |s: f64| {
            let s = s.clamp(0.0, 1.0);
            let e = starts.partition_point(|&s0| s0 <= s).saturating_sub(1);
            // The arc length into element e, at most its length.
            (e, ((s - starts[e]) * l).clamp(0.0, els[e].length))
        };
        let links = rectangles
            .into_iter()
            .filter(|r| r.k != 0.0 && r.s[1] > r.s[0])
            .filter_map(|r| {
                let lo = mids.partition_point(|&m| m < r.t[0]);
                let hi = mids.partition_point(|&m| m < r.t[1]);
                (hi > lo).then(|| Link {
                    from: locate(r.s[0]),
                    to: locate(r.s[1]),
                    receivers: (lo, hi),
                    k: r.k,
                })
            })
            .collect();
        RectangleOperator {
            starts,
            lengths: els.iter().map(|e| e.length).collect(),
            total_length: l,
            links,
        }
    }

    /// Rectangles kept (with a value and a collocation point).
    #[must_use]
    pub fn rectangles(&self) -> usize {
        self.links.len()
    }
}

impl TransferOperator for RectangleOperator {
    fn len(&self) -> usize {
        self.starts.len()
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        let n = self.len();
        // Pull: F(e, offset) = ∫ B from s = 0 to that point = prefix[e] + b[e] · offset.
        let mut prefix = Vec::with_capacity(n + 1);
        prefix.push(0.0);
        for (bi, li) in b.iter().zip(&self.lengths) {
            prefix.push(prefix.last().copied().unwrap_or(0.0) + bi * li);
        }
        let integral = |(e, offset): (usize, f64)| prefix[e] + b[e] * offset;
        // Gather into a difference array over the receivers, then push.
        let mut diff = vec![0.0; n + 1];
        for link in &self.links {
            let gathered = link.k * (integral(link.to) - integral(link.from));
            diff[link.receivers.0] += gathered;
            diff[link.receivers.1] -= gathered;
        }
        let mut running = 0.0;
        for (o, d) in out.iter_mut().zip(&diff) {
            running += d;
            *o = running;
        }
        debug_assert!(self.total_length > 0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::never;
    use crate::test_support::bundled;
    use flatland_geom::Kernel;
    use flatland_testkit::assert_close;
    use rand::RngExt;

    #[test]
    fn dense_apply_is_the_matrix_product() {
        let mut rng = flatland_testkit::rng(3);
        for n in [1, 3, 7, 64, 101] {
            let values: Vec<f64> = (0..n * n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let op = DenseOperator::assemble(
                n,
                |i, row| row.copy_from_slice(&values[i * n..(i + 1) * n]),
                &never,
            )
            .unwrap();
            let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut out = vec![0.0; n];
            op.apply(&b, &mut out);
            for i in 0..n {
                let expected: f64 = (0..n).map(|j| values[i * n + j] * b[j]).sum();
                assert_close!(out[i], expected, 1e-12, "n = {n}, row {i}");
            }
        }
    }

    #[test]
    fn dense_assembly_stops_and_refuses_non_finite_entries() {
        let err = DenseOperator::assemble(50, |_, row| row.fill(1.0), &|| true).unwrap_err();
        assert!(matches!(err, SolveError::Interrupted), "{err}");
        let err = DenseOperator::assemble(
            4,
            |i, row| {
                row.fill(0.5);
                if i == 2 {
                    row[3] = f64::NAN;
                }
            },
            &never,
        )
        .unwrap_err();
        assert!(err.to_string().contains("row 2, column 3"), "{err}");
    }

    #[test]
    fn rectangles_match_brute_force_integration() {
        // Random rectangles on a real mesh: the gathered value at each collocation point equals
        // Σ over rectangles holding it of k · ∫ B L ds over the sender interval, integrated
        // element by element by hand.
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 37).unwrap();
        let mut rng = flatland_testkit::rng(5);
        let rects: Vec<KernelRectangle> = (0..200)
            .map(|_| {
                let (a, b): (f64, f64) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
                let (c, d): (f64, f64) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
                KernelRectangle {
                    s: [a.min(b), a.max(b)],
                    t: [c.min(d), c.max(d)],
                    k: rng.random_range(-1.0..1.0),
                }
            })
            .collect();
        let op = RectangleOperator::new(&mesh, rects.clone());
        let b: Vec<f64> = (0..mesh.len())
            .map(|_| rng.random_range(0.0..2.0))
            .collect();
        let mut out = vec![0.0; mesh.len()];
        op.apply(&b, &mut out);
        let l = mesh.total_length();
        for (i, e) in mesh.elements().iter().enumerate() {
            let t = e.s_mid;
            let expected: f64 = rects
                .iter()
                .filter(|r| r.t[0] <= t && t < r.t[1])
                .map(|r| {
                    let integral: f64 = mesh
                        .elements()
                        .iter()
                        .zip(&b)
                        .map(|(f, bf)| {
                            let overlap = (r.s[1].min(f.s[1]) - r.s[0].max(f.s[0])).max(0.0);
                            bf * overlap * l
                        })
                        .sum();
                    r.k * integral
                })
                .sum();
            assert!(
                (out[i] - expected).abs() < 1e-9,
                "point {i}: {} vs {expected}",
                out[i]
            );
        }
    }
}
