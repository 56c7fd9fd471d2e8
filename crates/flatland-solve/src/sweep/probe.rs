//! What one collocation point sees, kept so that other receivers on its edge can borrow it.
//!
//! A *probe* is the sweep of one element's midpoint `y_p`, kept twice: as its exact row and as
//! the stretches of surfaces it sees ([`SeenSpan`], positions along the sending edge, not
//! directions, so they mean the same from any point). A receiver `y` on the same section of
//! the same edge can then be given the row it would have if it saw exactly what `y_p` sees
//! ([`Sweep::row_through`]): the closed-form transfer from `y` over each borrowed stretch,
//! split among the sending elements — no hierarchy walked, no ray. Where nothing stands
//! between the two points' views this is the exact row; the light-driven learner decides
//! where it is not.

use glam::DVec2;

use super::envelope::Piece;
use super::row::seen_part;
use super::view::View;
use super::{SweepBuffers, SweepScene};
use crate::exact::check_scene;
use crate::{Mesh, SolveError};
use flatland_geom::Kernel;

/// A stretch of a sending surface seen from a point: mesh edge `edge` from `u[0]` to `u[1]`,
/// fractions of its length from its start `a` (so `s = s₀ + u (s₁ − s₀)` in the scene's
/// parameter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeenSpan {
    /// The mesh edge seen.
    pub edge: u32,
    /// Where along it, `0 ≤ u[0] < u[1] ≤ 1`.
    pub u: [f64; 2],
}

/// The visibility sweep of one scene on one mesh, kept for many probes and borrowed rows.
#[derive(Clone, Debug)]
pub struct Sweep {
    scene: SweepScene,
}

/// What one thread reuses between probes (the sweep's heap and envelope), so a probe
/// allocates nothing once warm.
#[derive(Debug, Default)]
pub struct ProbeBuffers {
    sweep: SweepBuffers,
}

impl Sweep {
    /// The sweep of `kernel`'s scene on `mesh` (a mesh of that scene).
    pub fn new(kernel: &Kernel, mesh: &Mesh) -> Result<Sweep, SolveError> {
        check_scene(kernel, mesh)?;
        Ok(Sweep {
            scene: SweepScene::new(kernel.scene(), mesh),
        })
    }

    /// Probes element `i`: its exact row (`(j, K_ij)`, ρ included, columns ascending — the
    /// numbers of [`sweep_operator`](crate::sweep_operator)) into `row`, and the stretches
    /// of surfaces its midpoint sees into `spans`, sorted by edge and position.
    pub fn probe(
        &self,
        mesh: &Mesh,
        i: usize,
        buffers: &mut ProbeBuffers,
        row: &mut Vec<(u32, f64)>,
        spans: &mut Vec<SeenSpan>,
    ) {
        row.clear();
        spans.clear();
        let rho = mesh.edge_of(i).reflectance;
        let k = mesh.elements()[i].mesh_edge;
        let y = mesh.local(i)[2];
        let transfers = super::transfers(&self.scene, mesh, k, y, true, &mut buffers.sweep);
        if rho > 0.0 {
            row.extend(transfers.iter().map(|&(j, t)| (j, rho * t)));
        }
        let receiver = &mesh.edges()[k];
        // The envelope of the receiver's view is still in the buffers.
        let view = View::new(y, receiver.normal);
        for piece in buffers.sweep.envelope.pieces() {
            if let Some(m) = self.scene.mesh_edge[piece.segment as usize]
                && let Some(u) = self.along(&view, piece)
            {
                spans.push(SeenSpan { edge: m, u });
            }
        }
        spans.sort_by(|a, b| a.edge.cmp(&b.edge).then(a.u[0].total_cmp(&b.u[0])));
    }

    /// Row `i` (`(j, K_ij)`, ρ included, columns ascending) as if its midpoint saw exactly
    /// `spans` (what a probe on the same side of the same edge saw): the closed-form transfer
    /// over each stretch from `y_i`, where the stretch faces `y_i`. Stretches seen in the
    /// same direction from `y_i` (parallax between the two points) are all counted, so the
    /// row may gather a little more than the half-plane holds: the caller bounds it.
    pub fn row_through(
        &self,
        mesh: &Mesh,
        i: usize,
        spans: &[SeenSpan],
        row: &mut Vec<(u32, f64)>,
    ) {
        row.clear();
        let receiver = mesh.edge_of(i);
        let rho = receiver.reflectance;
        if rho == 0.0 {
            return;
        }
        let view = View::new(mesh.local(i)[2], receiver.normal);
        for span in spans {
            let m = span.edge as usize;
            let segment = &self.scene.segments[self.scene.segment_of[m] as usize];
            let at = |u: f64| segment.a + (segment.b - segment.a) * u;
            let (sa, sb) = (
                direction(&view, at(span.u[0])),
                direction(&view, at(span.u[1])),
            );
            let (lo, hi) = (sa.min(sb), sa.max(sb));
            if hi > lo {
                let piece = Piece {
                    lo,
                    hi,
                    segment: self.scene.segment_of[m],
                    far: 0.0,
                };
                seen_part(&view, mesh, m, &piece, row, |lo, hi| 0.5 * (hi - lo));
            }
        }
        row.sort_by_key(|&(j, _)| j);
        row.dedup_by(|later, kept| {
            let same = later.0 == kept.0;
            if same {
                kept.1 += later.1;
            }
            same
        });
        for entry in row.iter_mut() {
            entry.1 *= rho;
        }
    }

    /// The stretch of `piece`'s segment it covers, as fractions of the segment's length.
    fn along(&self, view: &View, piece: &Piece) -> Option<[f64; 2]> {
        let segment = &self.scene.segments[piece.segment as usize];
        let d = segment.b - segment.a;
        let length2 = d.length_squared();
        let u = |sigma: f64| -> Option<f64> {
            let depth = view.depth(segment, sigma);
            depth.is_finite().then(|| {
                let p = view.y + view.direction(sigma) * depth;
                ((p - segment.a).dot(d) / length2).clamp(0.0, 1.0)
            })
        };
        let (u0, u1) = (u(piece.lo)?, u(piece.hi)?);
        let (lo, hi) = (u0.min(u1), u0.max(u1));
        (hi > lo).then_some([lo, hi])
    }
}

/// σ of `p` from `view`: its direction when it lies in front, the horizon on its side when
/// rounding puts it on the receiver's own line (a borrowed stretch always lies in front of
/// the edge both points are on, up to rounding).
fn direction(view: &View, p: DVec2) -> f64 {
    if view.height(p) > 0.0 {
        view.sine(p)
    } else {
        view.horizon(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, floor_plan};
    use crate::{never, sweep_operator};

    /// A probe's row is the sweep operator's row, bit for bit.
    #[test]
    fn a_probe_row_is_the_sweep_row() {
        let kernel = Kernel::new(floor_plan(200));
        let mesh = Mesh::new(&kernel, 400).unwrap();
        let sweep = Sweep::new(&kernel, &mesh).unwrap();
        let exact = sweep_operator(&kernel, &mesh, &never).unwrap();
        let (mut buffers, mut row, mut spans) = Default::default();
        for i in 0..mesh.len() {
            sweep.probe(&mesh, i, &mut buffers, &mut row, &mut spans);
            let (columns, values) = exact.row(i);
            let expected: Vec<(u32, f64)> = columns
                .iter()
                .copied()
                .zip(values.iter().copied())
                .collect();
            assert_eq!(row, expected, "row {i}");
        }
    }

    /// Through its own stretches a probe's row comes back to rounding.
    #[test]
    fn a_row_through_its_own_spans_is_the_probe_row() {
        for kernel in [Kernel::new(floor_plan(200)), Kernel::new(bundled("fig3"))] {
            let mesh = Mesh::new(&kernel, 300).unwrap();
            let sweep = Sweep::new(&kernel, &mesh).unwrap();
            let (mut buffers, mut row, mut spans, mut again) = Default::default();
            for i in 0..mesh.len() {
                sweep.probe(&mesh, i, &mut buffers, &mut row, &mut spans);
                sweep.row_through(&mesh, i, &spans, &mut again);
                let sum = |r: &Vec<(u32, f64)>| r.iter().map(|e| e.1).sum::<f64>();
                assert!(
                    (sum(&row) - sum(&again)).abs() <= 1e-9,
                    "row {i}: {} vs {}",
                    sum(&row),
                    sum(&again)
                );
                for (&(j, a), &(k, b)) in row.iter().zip(&again) {
                    assert_eq!(j, k, "row {i}");
                    assert!(
                        (a - b).abs() <= 1e-9 * a.max(b) + 1e-14,
                        "K[{i}][{j}] {a} vs {b}"
                    );
                }
            }
        }
    }

    /// Spans are sorted, inside [0, 1], and cover what the row gathers from.
    #[test]
    fn spans_are_sorted_and_in_range() {
        let kernel = Kernel::new(floor_plan(200));
        let mesh = Mesh::new(&kernel, 200).unwrap();
        let sweep = Sweep::new(&kernel, &mesh).unwrap();
        let (mut buffers, mut row, mut spans) = Default::default();
        let mut seen = 0;
        for i in 0..mesh.len() {
            sweep.probe(&mesh, i, &mut buffers, &mut row, &mut spans);
            seen += spans.len();
            for pair in spans.windows(2) {
                assert!((pair[0].edge, pair[0].u[0]) <= (pair[1].edge, pair[1].u[0]));
            }
            for s in &spans {
                assert!(0.0 <= s.u[0] && s.u[0] < s.u[1] && s.u[1] <= 1.0, "{s:?}");
            }
        }
        assert!(seen > mesh.len(), "{seen} spans");
    }
}
