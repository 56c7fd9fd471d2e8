//! Four-wide BVH nodes and their conservative single-precision box tests, one SIMD lane a box.

use glam::{DVec2, Vec4};

/// Up to four children of a [`Bvh`](super::Bvh) node: their boxes (center `c`, half extent `h`,
/// in the BVH's unit frame, single precision) one SIMD lane each, so one node load brings all
/// four and one vector test checks them together.
#[derive(Clone, Copy, Debug)]
pub(super) struct Wide {
    pub(super) cx: Vec4,
    pub(super) cy: Vec4,
    pub(super) hx: Vec4,
    pub(super) hy: Vec4,
    /// Inner child: its index in `nodes` (`count` 0); leaf: its first item (`count` > 0).
    pub(super) child: [u32; 4],
    pub(super) count: [u32; 4],
    /// The one segment every piece below child `k` belongs to, or [`MIXED`](super::bvh::MIXED):
    /// a ray skips such a child when it skips that segment (a wall cut into pieces, seen from a
    /// point on it).
    pub(super) sole: [u32; 4],
    /// Bit `k` set iff slot `k` is used.
    pub(super) used: u32,
}

/// The rounding margin of the single-precision box tests, in units of the BVH's frame (where
/// the scene spans `[0, 1]`), per unit of the query's own magnitude: single precision rounds
/// a value of size `m` by at most `6e-8·m`, and a test sums about ten such errors.
const BOX_MARGIN: f32 = 4e-6;

impl Wide {
    /// Bit `k`: whether every piece below child `k` belongs to segment `a` or `b`.
    #[inline]
    pub(super) fn skipped(&self, a: usize, b: usize) -> u32 {
        (0..4).fold(0, |mask, k| {
            let sole = self.sole[k] as usize;
            mask | (u32::from(sole == a || sole == b) << k)
        })
    }
}

/// Distances along a ray's direction (unit frame): a lower bound for each box, an upper bound
/// for a point, each off by more than its rounding, so a box whose bound exceeds a contact's
/// can hold nothing that comes first or ties. They also order a closest-hit query's visits,
/// nearer boxes first.
pub(super) struct Along {
    ox: Vec4,
    oy: Vec4,
    ux: Vec4,
    uy: Vec4,
    ux_abs: Vec4,
    uy_abs: Vec4,
    o: DVec2,
    unit: DVec2,
    margin: f32,
}

impl Along {
    /// From `o` towards `f` (distinct points of the unit frame).
    pub(super) fn new(o: DVec2, f: DVec2) -> Along {
        let unit = (f - o).normalize_or_zero();
        Along {
            ox: Vec4::splat(o.x as f32),
            oy: Vec4::splat(o.y as f32),
            ux: Vec4::splat(unit.x as f32),
            uy: Vec4::splat(unit.y as f32),
            ux_abs: Vec4::splat(unit.x.abs() as f32),
            uy_abs: Vec4::splat(unit.y.abs() as f32),
            o,
            unit,
            margin: BOX_MARGIN * (2.0 + o.abs().element_sum() as f32),
        }
    }

    /// For each child of `node`, at most the distance along the ray of any point of its box.
    #[inline]
    pub(super) fn entries(&self, node: &Wide) -> Vec4 {
        (node.cx - self.ox) * self.ux + (node.cy - self.oy) * self.uy
            - (node.hx * self.ux_abs + node.hy * self.uy_abs)
            - Vec4::splat(self.margin)
    }

    /// At least the distance along the ray of `p`.
    pub(super) fn reach(&self, p: DVec2) -> f32 {
        (p - self.o).dot(self.unit) as f32 + self.margin
    }
}

/// The open half-plane beyond the first contact a closest-hit query has found so far (unit
/// frame): a box wholly inside it, by more than the margin, holds nothing that could come
/// first or tie, so the query skips it (conservative, like [`RayBox`]).
pub(super) struct Beyond {
    nx: Vec4,
    ny: Vec4,
    nx_abs: Vec4,
    ny_abs: Vec4,
    offset: Vec4,
    margin: Vec4,
}

impl Beyond {
    /// `{p : normal · (p − p0) > 0}` for a nonzero `normal` and `p0` in the scene's frame.
    pub(super) fn new(p0: DVec2, normal: DVec2) -> Beyond {
        let n = normal / normal.abs().max_element();
        Beyond {
            nx: Vec4::splat(n.x as f32),
            ny: Vec4::splat(n.y as f32),
            nx_abs: Vec4::splat(n.x.abs() as f32),
            ny_abs: Vec4::splat(n.y.abs() as f32),
            offset: Vec4::splat(n.dot(p0) as f32),
            margin: Vec4::splat(BOX_MARGIN * (1.0 + p0.abs().element_sum() as f32)),
        }
    }

    /// Bit `k`: whether child `k`'s box lies wholly beyond, by more than the margin. A NaN
    /// comparison keeps the box.
    #[inline]
    pub(super) fn holds(&self, node: &Wide) -> u32 {
        let nearest = self.nx * node.cx + self.ny * node.cy
            - self.offset
            - (self.nx_abs * node.hx + self.ny_abs * node.hy);
        nearest.cmpgt(self.margin).bitmask() & 0b1111
    }
}

/// An axis-aligned query box for [`Bvh::overlapping`](super::Bvh::overlapping), in the unit frame.
pub(super) struct Boxes {
    cx: Vec4,
    cy: Vec4,
    hx: Vec4,
    hy: Vec4,
    margin: Vec4,
}

impl Boxes {
    pub(super) fn new(lo: DVec2, hi: DVec2) -> Boxes {
        let (c, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        Boxes {
            cx: Vec4::splat(c.x as f32),
            cy: Vec4::splat(c.y as f32),
            hx: Vec4::splat(h.x as f32),
            hy: Vec4::splat(h.y as f32),
            margin: Vec4::splat(BOX_MARGIN * (1.0 + (c.abs() + h).element_sum() as f32)),
        }
    }

    /// Bit `k`: whether the box may overlap child `k`'s box (conservative).
    #[inline]
    pub(super) fn overlaps(&self, node: &Wide) -> u32 {
        let apart_x = (node.cx - self.cx).abs() - node.hx - self.hx;
        let apart_y = (node.cy - self.cy).abs() - node.hy - self.hy;
        !(apart_x.cmpgt(self.margin) | apart_y.cmpgt(self.margin)).bitmask() & 0b1111
    }
}

/// A conservative segment–box test for one ray (end points in the unit frame): never rejects a
/// closed box the closed segment `[x, y]` touches; it may accept a few it misses by the margin.
pub(super) struct RayBox {
    /// The ray's bounding box, as a query box (its margin serves both tests).
    bounds: Boxes,
    /// The normal of the ray's line, scaled so its larger component is ±1, and its absolute
    /// value: the line is `normal · p = offset`.
    nx: Vec4,
    ny: Vec4,
    nx_abs: Vec4,
    ny_abs: Vec4,
    offset: Vec4,
}

impl RayBox {
    #[inline]
    pub(super) fn new(x: DVec2, y: DVec2) -> RayBox {
        let d = y - x;
        let m = d.abs().max_element();
        let normal = if m > 0.0 { d.perp() / m } else { DVec2::ZERO };
        RayBox {
            bounds: Boxes::new(x.min(y), x.max(y)),
            nx: Vec4::splat(normal.x as f32),
            ny: Vec4::splat(normal.y as f32),
            nx_abs: Vec4::splat(normal.x.abs() as f32),
            ny_abs: Vec4::splat(normal.y.abs() as f32),
            offset: Vec4::splat(normal.dot(x) as f32),
        }
    }

    /// Bit `k`: the separating-axis test of the ray against child `k`'s box. The boxes overlap
    /// on both axes, and the box reaches the ray's line (`|n·c − n·x| ≤ |n|·h`), each within the
    /// margin. A NaN or infinite comparison (a query far outside single precision) accepts.
    #[inline]
    pub(super) fn may_meet(&self, node: &Wide) -> u32 {
        let b = &self.bounds;
        let apart_x = (node.cx - b.cx).abs() - node.hx - b.hx;
        let apart_y = (node.cy - b.cy).abs() - node.hy - b.hy;
        let off_line = (self.nx * node.cx + self.ny * node.cy - self.offset).abs()
            - (self.nx_abs * node.hx + self.ny_abs * node.hy);
        let rejected = apart_x.cmpgt(b.margin) | apart_y.cmpgt(b.margin) | off_line.cmpgt(b.margin);
        !rejected.bitmask() & 0b1111
    }
}
