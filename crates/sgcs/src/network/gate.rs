//! Gates: which cells may respond to, and learn from, one input.

use super::CellId;

/// Which cells may respond to, and learn from, one input.
///
/// A caller that knows where its target jumps (a discontinuity it can compute without a sample)
/// gives each query a gate that admits only the cells on the input's side of every such jump;
/// then no cell straddles one, and [`OutputMode::Normalized`] reproduces a piecewise constant
/// target exactly up to the jumps. A gated query uses only admitted cells: output, best
/// matching unit, weight updates and movement. When no admitted cell is active, the output
/// falls back to the ungated one (the network's best guess), the sample's error is booked on
/// the nearest cell (so growth goes there) and nothing moves or learns.
///
/// A gate may also **name** its cells ([`Gate::region`]): all the cells of the input's region,
/// ascending. Then exactly those respond, however far away — no spatial search and no
/// activation cutoff; with [`OutputMode::Normalized`] their weights are computed relative to
/// the nearest one (in `|ξ − w_c|² / δ_c²`), so the output never underflows to 0: a region
/// with one cell anywhere in it has that cell's value. Where the region has no cell, the
/// output is the normalised blend of [`Gate::fallback`] (if it names any cells) or the ungated
/// output.
///
/// [`OutputMode::Normalized`]: crate::OutputMode::Normalized
pub trait Gate {
    /// Whether `cell` may respond to the input.
    fn admits(&self, cell: CellId) -> bool;
    /// True only for a gate that admits every cell (the paper's network, [`Open`]).
    fn is_open(&self) -> bool {
        false
    }
    /// Every admitted cell, ascending, when the caller keeps them by region.
    fn region(&self) -> Option<&[CellId]> {
        None
    }
    /// With [`Gate::region`]: the cells to blend when the region has none (ascending).
    fn fallback(&self) -> Option<&[CellId]> {
        None
    }
}

/// The gate that admits every cell: the ungated network.
#[derive(Clone, Copy, Debug, Default)]
pub struct Open;

impl Gate for Open {
    #[inline]
    fn admits(&self, _: CellId) -> bool {
        true
    }
    #[inline]
    fn is_open(&self) -> bool {
        true
    }
}

impl<F: Fn(CellId) -> bool> Gate for F {
    #[inline]
    fn admits(&self, cell: CellId) -> bool {
        self(cell)
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::Network;
    use crate::test_support::{Halves, gated_params, rng, unit_square_points, unit_triangle};

    /// A step target with its jump known to the caller: gated cells never straddle it, so a
    /// normalised network reproduces it exactly on both sides; the same network ungated blurs
    /// the jump.
    #[test]
    fn gated_normalized_cells_reproduce_a_known_jump_exactly() {
        let step = |x: f64| if x > 0.5 { 1.0 } else { 0.25 };
        let train = |gated: bool| {
            let mut net = Network::new(gated_params(), 2, 1, &unit_triangle()).unwrap();
            // The initial cells start from the target at their centres (as inserted ones do).
            for c in 0..3 {
                let x = net.position(c)[0];
                net.set_output(c, &[step(x)]).unwrap();
            }
            let mut halves = Halves::default();
            halves.update(&net);
            let mut r = rng(11);
            for _ in 0..4_000 {
                let (x, y) = (r.random::<f64>(), r.random::<f64>());
                if gated {
                    net.try_step_gated(&[x, y], &[step(x)], 1.0, &halves.gate(x))
                        .unwrap();
                } else {
                    net.step(&[x, y], &[step(x)]);
                }
                halves.update(&net);
                if net.steps().is_multiple_of(500) {
                    net.check_invariants().unwrap();
                }
            }
            (net, halves)
        };
        let (net, halves) = train(true);
        let (open, _) = train(false);
        let (mut gated_worst, mut open_worst) = (0.0f64, 0.0f64);
        for p in unit_square_points(12, 2_000) {
            let gated = net.predict1_gated(&p, &halves.gate(p[0]));
            gated_worst = gated_worst.max((gated - step(p[0])).abs());
            open_worst = open_worst.max((open.predict1(&p) - step(p[0])).abs());
        }
        assert!(gated_worst < 1e-9, "gated: worst error {gated_worst}");
        assert!(
            open_worst > 0.2,
            "ungated blurs the jump: worst error {open_worst}"
        );
    }

    /// A gate naming a region with one far cell gives that cell's value (no underflow), and an
    /// empty region books the error on the nearest cell, moves and teaches nothing.
    #[test]
    fn region_gates_reach_far_cells_and_uncovered_inputs_only_book_error() {
        let mut net = Network::new(gated_params(), 2, 1, &unit_triangle()).unwrap();
        net.cells.out.copy_from_slice(&[0.5, 2.0, 3.0]);
        let far = [1e3, 1e3];
        let one: &[CellId] = &[1];
        struct Named<'a>(&'a [CellId]);
        impl Gate for Named<'_> {
            fn admits(&self, c: CellId) -> bool {
                self.0.contains(&c)
            }
            fn region(&self) -> Option<&[CellId]> {
                Some(self.0)
            }
        }
        assert_eq!(net.predict1_gated(&far, &Named(one)), 2.0);
        assert_eq!(
            net.predict1(&far),
            0.0,
            "ungated: every activation underflows"
        );
        let before = net.to_json();
        let (pos, out) = (net.cells.pos.to_vec(), net.cells.out.to_vec());
        let outcome = net
            .try_step_gated(&[0.1, 0.1], &[9.0], 2.0, &Named(&[]))
            .unwrap();
        assert!(!outcome.covered);
        assert_eq!(outcome.bmu, 0, "the nearest cell takes the error");
        assert_eq!((net.cells.pos.to_vec(), net.cells.out.to_vec()), (pos, out));
        assert!(net.resource(0) > 0.0 && net.resource(1) == 0.0);
        assert_ne!(net.to_json(), before);
    }
}
