//! One row of the sweep: the envelope of each side of a receiving point, turned into the
//! transfer to every element it sees.

use glam::DVec2;

use super::envelope::Piece;
use super::view::View;
use super::{SweepBuffers, SweepScene};
use crate::Mesh;

/// `∫_{element j} G(x, y) V(x, y) dl_x` for every element `j` of `mesh` that `y` (a frame
/// point on mesh edge `k`) sees, as `(j, transfer)` sorted by `j`, without ρ: what its front
/// half-plane holds. The slice lives in `buffers` until the next row.
pub(crate) fn transfers<'b>(
    scene: &SweepScene,
    mesh: &Mesh,
    k: usize,
    y: DVec2,
    cull: bool,
    buffers: &'b mut SweepBuffers,
) -> &'b [(u32, f64)] {
    let view = View::new(y, mesh.edges()[k].normal);
    scene.envelope(&view, scene.segment_of[k], cull, buffers);
    let mut out = std::mem::take(&mut buffers.transfers);
    collect(scene, &view, mesh, buffers, &mut out);
    buffers.transfers = out;
    &buffers.transfers
}

/// [`transfers`] at `y` to the elements of two meshes of the same scene (`mesh`, and `other`
/// into `other_out`) from one envelope: what `y` sees does not depend on how it is meshed.
pub(crate) fn transfers_to_both<'b>(
    scene: &SweepScene,
    mesh: &Mesh,
    other: &Mesh,
    k: usize,
    y: DVec2,
    buffers: &'b mut SweepBuffers,
    other_out: &mut Vec<(u32, f64)>,
) -> &'b [(u32, f64)] {
    transfers(scene, mesh, k, y, true, buffers);
    let view = View::new(y, mesh.edges()[k].normal);
    collect(scene, &view, other, buffers, other_out);
    &buffers.transfers
}

/// The transfer of the envelope in `buffers` (built from `view`) to every element of `mesh`,
/// into `out` (cleared first), sorted by element.
fn collect(
    scene: &SweepScene,
    view: &View,
    mesh: &Mesh,
    buffers: &SweepBuffers,
    out: &mut Vec<(u32, f64)>,
) {
    out.clear();
    for piece in buffers.envelope.pieces() {
        if let Some(m) = scene.mesh_edge[piece.segment as usize] {
            seen_part(view, mesh, m as usize, piece, out, |lo, hi| 0.5 * (hi - lo));
        }
    }
    // Pieces of one element seen in several places (between occluders) sum.
    out.sort_by_key(|&(j, _)| j);
    out.dedup_by(|later, kept| {
        let same = later.0 == kept.0;
        if same {
            kept.1 += later.1;
        }
        same
    });
}

/// Appends `measure(σ₁, σ₂)` of the part `[σ₁, σ₂]` of `piece` of surface `m` that each
/// element of `m` takes, when `m`'s front faces the viewpoint (a surface seen from behind
/// sends nothing, but still hides what lies beyond it): the transfer `(σ₂ − σ₁) / 2` for a
/// receiving point, the angle `asin σ₂ − asin σ₁` for a light.
pub(super) fn seen_part(
    view: &View,
    mesh: &Mesh,
    m: usize,
    piece: &Piece,
    out: &mut Vec<(u32, f64)>,
    measure: impl Fn(f64, f64) -> f64,
) {
    let edge = &mesh.edges()[m];
    let elements = edge.elements.clone();
    let (first, last) = (
        mesh.local(elements.start)[0],
        mesh.local(elements.end - 1)[1],
    );
    if edge.normal.dot(view.y - first) <= 0.0 {
        return;
    }
    // σ is monotone along the edge: increasing from `first` when `last` is counter-clockwise
    // of it. Boundary `b` (0 = `first`, count = `last`) of the edges' elements, in σ order.
    let count = elements.len();
    let increasing = (first - view.y).perp_dot(last - view.y) > 0.0;
    let point = |b: usize| {
        let b = if increasing { b } else { count - b };
        if b == count {
            last
        } else {
            mesh.local(elements.start + b)[0]
        }
    };
    let element = |b: usize| elements.start + if increasing { b } else { count - 1 - b };
    // Boundaries behind the horizon sit beyond the end where the edge leaves the view, where
    // σ is ±1: the low end if that is the first point in σ order, the high end otherwise.
    let behind_low = view.height(point(0)) <= 0.0;
    let sine = |b: usize| {
        let p = point(b);
        match (view.height(p) > 0.0, behind_low) {
            (true, _) => view.sine(p),
            (false, true) => -1.0,
            (false, false) => 1.0,
        }
    };
    // The first element whose upper boundary lies above the piece's start.
    let (mut lo, mut hi) = (0, count);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if sine(mid + 1) <= piece.lo {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    let mut below = sine(lo);
    for b in lo..count {
        if below >= piece.hi {
            break;
        }
        let above = sine(b + 1);
        let (lo, hi) = (below.max(piece.lo), above.min(piece.hi));
        if hi > lo {
            out.push((element(b) as u32, measure(lo, hi)));
        }
        below = above;
    }
}
