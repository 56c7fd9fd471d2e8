//! One view of a point light: everything around it, as two half-plane views of the sweep.
//!
//! A light looks in every direction, a receiving point into one half-plane. So a light's view
//! is two views of the sweep from the same point, above and below its horizontal line (the
//! line itself subtends nothing): the same envelope, culling and hierarchy as a row of the
//! operator, with no segment skipped (a light lies on none). What it gives is the envelope's
//! pieces that land on surfaces whose front faces the light; the angle an element subtends is
//! then `asin σ₂ − asin σ₁` over each piece, exact up to rounding (σ rounded to 1e-16 loses
//! `1e-16 / cos φ` of angle: digits go only for a boundary within about 1e-6 radians of the
//! horizontal line, never where one lies on it exactly).

use glam::DVec2;

use super::envelope::Piece;
use super::row::seen_part;
use super::view::View;
use super::{SweepBuffers, SweepScene};
use crate::Mesh;

/// The segment index no segment has: a light skips nothing.
const NO_SKIP: u32 = u32::MAX;

/// A stretch of a surface a light sees, front on: mesh edge `edge`, in the directions
/// `[lo, hi]` of the half-view above (`up`) or below the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LitPiece {
    pub edge: u32,
    pub up: bool,
    pub lo: f64,
    pub hi: f64,
}

/// The half-view from `at` (frame) above its horizontal line, or below it.
fn half_view(at: DVec2, up: bool) -> View {
    View::new(at, if up { DVec2::Y } else { DVec2::NEG_Y })
}

impl SweepScene {
    /// Appends to `out` what a light at frame point `at` sees of the surfaces facing it, by
    /// the two half-views (above first, each by σ).
    pub(crate) fn light_view(
        &self,
        mesh: &Mesh,
        at: DVec2,
        buffers: &mut SweepBuffers,
        out: &mut Vec<LitPiece>,
    ) {
        for up in [true, false] {
            let view = half_view(at, up);
            self.envelope(&view, NO_SKIP, true, buffers);
            for piece in buffers.envelope.pieces() {
                let Some(m) = self.mesh_edge[piece.segment as usize] else {
                    continue; // a blocker: it only hides
                };
                let edge = &mesh.edges()[m as usize];
                let first = mesh.local(edge.elements.start)[0];
                if edge.normal.dot(at - first) > 0.0 {
                    out.push(LitPiece {
                        edge: m,
                        up,
                        lo: piece.lo,
                        hi: piece.hi,
                    });
                }
            }
        }
    }
}

/// Appends `(element, Δφ)` for every element of `piece`'s edge that it overlaps: the angle the
/// element's part in the piece subtends from the light at `at` (frame).
pub(crate) fn element_angles(mesh: &Mesh, at: DVec2, piece: &LitPiece, out: &mut Vec<(u32, f64)>) {
    let view = half_view(at, piece.up);
    let directions = Piece {
        lo: piece.lo,
        hi: piece.hi,
        segment: NO_SKIP,
        far: 0.0,
    };
    seen_part(
        &view,
        mesh,
        piece.edge as usize,
        &directions,
        out,
        |lo, hi| hi.asin() - lo.asin(),
    );
}

/// Whether `piece` (of a light at `at`) holds the direction to frame point `y`. A point on
/// the light's horizontal line belongs to the view above, at its horizon σ = ±1 (where a
/// surface crossing the line is clipped), so it is counted once.
pub(crate) fn holds(at: DVec2, piece: &LitPiece, y: DVec2) -> bool {
    let view = half_view(at, piece.up);
    let height = view.height(y);
    let sigma = if height > 0.0 {
        view.sine(y)
    } else if height == 0.0 && piece.up {
        view.horizon(y)
    } else {
        return false;
    };
    piece.lo <= sigma && sigma <= piece.hi
}
