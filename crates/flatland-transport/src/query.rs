//! What every form of the later bounces answers: a move of the lights in, `M₂ B₀` out.

use flatland_geom::PointLight;

use serde::{Deserialize, Serialize};

use crate::TransportError;

/// One position of the moving lights: the lights and the direct light B₀ they give, as its
/// non-zero entries `(element, value)` ascending ([`lit_source`](crate::lit_source)). A form
/// of the transport reads whichever it needs: the low-rank form B₀, the probes the lights.
#[derive(Clone, Copy, Debug)]
pub struct Move<'a> {
    /// The lights.
    pub lights: &'a [PointLight],
    /// B₀'s non-zero entries.
    pub lit: &'a [(u32, f64)],
}

/// A representation of the later bounces `M₂ B₀` of one scene and mesh.
pub trait LaterBounces: Sync {
    /// Adds its `M₂ B₀` for `lights` to `out` (length N). Never negative where B₀ is not.
    fn add_later_bounces(
        &self,
        lights: Move<'_>,
        out: &mut [f64],
        buffers: &mut QueryBuffers,
    ) -> Result<(), TransportError>;

    /// Bytes it holds.
    fn bytes(&self) -> usize;

    /// Its own error estimate, from lights it drew itself.
    fn estimated_error(&self) -> ErrorEstimate;

    /// Seconds its set-up took.
    fn setup_s(&self) -> f64;
}

/// A sparse accumulator of one answer, reused from query to query so a query allocates
/// nothing once warm and costs what it touches, not N.
#[derive(Debug, Default)]
pub struct QueryBuffers {
    /// Per element: its slot, or `u32::MAX` (grown to N on first use).
    slot: Vec<u32>,
    rows: Vec<u32>,
    values: Vec<f64>,
    /// The form's own scratch (cluster coefficients).
    pub(crate) scratch: Vec<f64>,
    pub(crate) pairs: Vec<(u32, u32, f64)>,
}

impl QueryBuffers {
    /// Starts an answer on a mesh of `n` elements.
    pub(crate) fn start(&mut self, n: usize) {
        if self.slot.len() != n {
            self.slot = vec![u32::MAX; n];
        }
        for &r in &self.rows {
            self.slot[r as usize] = u32::MAX;
        }
        self.rows.clear();
        self.values.clear();
    }

    /// Adds `value` to row `row` of the answer.
    #[inline]
    pub(crate) fn add(&mut self, row: u32, value: f64) {
        let s = self.slot[row as usize];
        if s == u32::MAX {
            self.slot[row as usize] = self.rows.len() as u32;
            self.rows.push(row);
            self.values.push(value);
        } else {
            self.values[s as usize] += value;
        }
    }

    /// Adds the answer to `out`, each value raised to 0 first when `clamp`: the later bounces
    /// of a source that is nowhere negative are nowhere negative (`M₂ ≥ 0` entry by entry),
    /// so raising an approximation to 0 only moves it towards the exact answer.
    pub(crate) fn finish(&self, out: &mut [f64], clamp: bool) {
        for (&r, &v) in self.rows.iter().zip(&self.values) {
            out[r as usize] += if clamp { v.max(0.0) } else { v };
        }
    }
}

/// Relative L2 errors (element lengths as weights) of a transport's answers on lights it was
/// not built from: of the later bounces `M₂ B₀`, of the indirect part `K B₀ + M₂ B₀` and of
/// `B = B₀ + K B₀ + M₂ B₀` (the first bounce and B₀ being exact, only `M₂ B₀` errs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorEstimate {
    /// Validation lights measured.
    pub lights: usize,
    /// Of `M₂ B₀`: mean and largest over the lights.
    pub later_mean: f64,
    /// Largest.
    pub later_max: f64,
    /// Of the indirect part: mean.
    pub indirect_mean: f64,
    /// Of B: mean.
    pub b_mean: f64,
    /// Of B: largest.
    pub b_max: f64,
}
