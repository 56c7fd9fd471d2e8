//! The envelope of one view: for every direction, the nearest segment inserted so far, as
//! sorted pieces of the σ range.

use super::view::{Segment, View};

/// Directions `[lo, hi]` in which segment `segment` is the nearest one, and an upper bound of
/// its depth there (`far`, what culling compares with).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Piece {
    /// First direction (σ).
    pub lo: f64,
    /// Last direction (σ).
    pub hi: f64,
    /// The segment seen (index into the sweep's segments).
    pub segment: u32,
    /// Its largest depth over `[lo, hi]`.
    pub far: f64,
}

/// The nearest segment per direction, as pieces sorted by σ that never overlap. Where two
/// pieces touch they share the very same σ (nothing leaks between them); gaps are directions
/// in which nothing was inserted yet.
#[derive(Clone, Debug, Default)]
pub(crate) struct Envelope {
    pieces: Vec<Piece>,
    /// Scratch: the pieces an insertion replaces a run with.
    replacement: Vec<Piece>,
}

impl Envelope {
    /// Forgets every piece (keeping the buffers).
    pub fn clear(&mut self) {
        self.pieces.clear();
    }

    /// The pieces, by σ.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// Adds segment `id` (of `segments`), seen in directions `span` ([`View::span`]): it
    /// takes every direction where nothing was seen and every direction where it is nearer.
    ///
    /// Two segments swap places at most once within the directions both cover, where they
    /// cross; so each overlap is cut at the crossing (if it lies inside) and each part goes to
    /// the segment nearer at its middle direction, which is never where they meet. Of two
    /// segments as near (back to back: a thin wall's two faces on one line, up to rounding) the
    /// surface facing `y` wins; other ties keep the piece already there.
    pub fn insert(&mut self, view: &View, segments: &[Segment], id: u32, span: [f64; 2]) {
        let [lo, hi] = span;
        let s = &segments[id as usize];
        let first = self.pieces.partition_point(|p| p.hi <= lo);
        let mut end = first;
        let mut out = std::mem::take(&mut self.replacement);
        out.clear();
        let mut covered_to = lo;
        while let Some(&p) = self.pieces.get(end).filter(|p| p.lo < hi) {
            if p.lo < lo {
                push(&mut out, Piece { hi: lo, ..p });
            }
            if p.lo > covered_to {
                push(&mut out, piece(view, s, id, covered_to, p.lo));
            }
            let (o0, o1) = (p.lo.max(lo), p.hi.min(hi));
            let q = &segments[p.segment as usize];
            let cut = crossing(view, s, q).filter(|&c| o0 < c && c < o1);
            for [u0, u1] in halves(o0, o1, cut) {
                if wins(view, s, q, 0.5 * (u0 + u1)) {
                    push(&mut out, piece(view, s, id, u0, u1));
                } else {
                    push(&mut out, piece(view, q, p.segment, u0, u1));
                }
            }
            if p.hi > hi {
                push(&mut out, Piece { lo: hi, ..p });
            }
            covered_to = o1;
            end += 1;
        }
        if covered_to < hi {
            push(&mut out, piece(view, s, id, covered_to, hi));
        }
        self.pieces.splice(first..end, out.drain(..));
        self.replacement = out;
    }

    /// Whether every direction of `span` is already covered by pieces no farther than
    /// `nearest`: then nothing at distance `nearest` or more can be seen there.
    pub fn hides(&self, span: [f64; 2], nearest: f64) -> bool {
        let [lo, hi] = span;
        let mut k = self.pieces.partition_point(|p| p.hi <= lo);
        let mut covered_to = lo;
        while covered_to < hi {
            match self.pieces.get(k) {
                Some(p) if p.lo <= covered_to && p.far <= nearest => covered_to = p.hi,
                _ => return false,
            }
            k += 1;
        }
        true
    }
}

/// Depths this close (relative) are a tie: back-to-back segments, up to rounding (grazing
/// views lose digits to cancellation, hence far above one ulp).
const TIE: f64 = 1e-9;

/// Whether `s` wins over `q` in direction σ: nearer, or as near and a surface facing `y` where `q`
/// is not. Without this a thin wall seen from one side would show its back face half the time
/// (whichever was inserted first) and send nothing.
#[inline]
fn wins(view: &View, s: &Segment, q: &Segment, sigma: f64) -> bool {
    let (ds, dq) = (view.depth(s, sigma), view.depth(q, sigma));
    if (ds - dq).abs() <= TIE * ds.max(dq) {
        view.faced_by(s) && !view.faced_by(q)
    } else {
        ds < dq
    }
}

/// `[u0, u1]` cut at `cut`, or whole.
fn halves(u0: f64, u1: f64, cut: Option<f64>) -> impl Iterator<Item = [f64; 2]> {
    let (first, second) = match cut {
        Some(c) => ([u0, c], Some([c, u1])),
        None => ([u0, u1], None),
    };
    std::iter::once(first).chain(second)
}

/// The piece of `s` over `[lo, hi]`; its depth along a line is largest at an end of any range
/// of directions.
fn piece(view: &View, s: &Segment, id: u32, lo: f64, hi: f64) -> Piece {
    Piece {
        lo,
        hi,
        segment: id,
        far: view.depth(s, lo).max(view.depth(s, hi)),
    }
}

/// Appends `p`, merged into the last piece when it continues the same segment.
fn push(out: &mut Vec<Piece>, p: Piece) {
    if p.hi <= p.lo {
        return;
    }
    match out.last_mut() {
        Some(last) if last.segment == p.segment && last.hi == p.lo => {
            last.hi = p.hi;
            last.far = last.far.max(p.far);
        }
        _ => out.push(p),
    }
}

/// The direction in which the lines of `s` and `q` meet, when they meet in front of `y`.
fn crossing(view: &View, s: &Segment, q: &Segment) -> Option<f64> {
    let (d, e) = (s.b - s.a, q.b - q.a);
    let den = d.perp_dot(e);
    if den == 0.0 {
        return None;
    }
    let x = s.a + d * ((q.a - s.a).perp_dot(e) / den);
    (x.is_finite() && view.height(x) > 0.0).then(|| view.sine(x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn view() -> View {
        View::new(v(0.0, 0.0), v(0.0, 1.0))
    }

    fn build(segments: &[Segment]) -> Envelope {
        let view = view();
        let mut env = Envelope::default();
        for (id, s) in segments.iter().enumerate() {
            if let Some(span) = view.span(s) {
                env.insert(&view, segments, id as u32, span);
            }
        }
        env
    }

    /// The nearest segment in direction σ, by brute force.
    fn nearest(segments: &[Segment], sigma: f64) -> Option<usize> {
        let view = view();
        let d = view.direction(sigma);
        segments
            .iter()
            .enumerate()
            .filter_map(|(i, s)| {
                // Ray–segment intersection: y + r d = a + u (b − a).
                let e = s.b - s.a;
                let den = d.perp_dot(e);
                if den == 0.0 {
                    return None;
                }
                let w = s.a - view.y;
                let (r, u) = (w.perp_dot(e) / den, w.perp_dot(d) / den);
                (r > 0.0 && (0.0..=1.0).contains(&u)).then_some((r, i))
            })
            .min_by(|p, q| p.0.total_cmp(&q.0))
            .map(|(_, i)| i)
    }

    fn check_against_rays(segments: &[Segment], env: &Envelope, rays: usize) {
        let pieces = env.pieces();
        for w in pieces.windows(2) {
            assert!(w[0].hi <= w[1].lo, "pieces overlap: {w:?}");
        }
        for k in 0..rays {
            let sigma = -1.0 + 2.0 * (k as f64 + 0.5) / rays as f64;
            let found = pieces
                .iter()
                .find(|p| p.lo < sigma && sigma < p.hi)
                .map(|p| p.segment as usize);
            let at_boundary = pieces
                .iter()
                .any(|p| (p.lo - sigma).abs() < 1e-9 || (p.hi - sigma).abs() < 1e-9);
            if !at_boundary {
                assert_eq!(found, nearest(segments, sigma), "σ = {sigma}");
            }
        }
    }

    #[test]
    fn crossing_segments_swap_at_the_crossing() {
        let segments = [
            Segment {
                a: v(-2.0, 1.0),
                b: v(2.0, 3.0),
                front: false,
            },
            Segment {
                a: v(-2.0, 3.0),
                b: v(2.0, 1.0),
                front: false,
            },
        ];
        let env = build(&segments);
        let pieces = env.pieces();
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        // They cross straight above y (σ = 0): segment 1 is nearer on the right (σ < 0).
        assert_eq!((pieces[0].segment, pieces[1].segment), (1, 0));
        assert!(pieces[0].hi.abs() < 1e-15);
        check_against_rays(&segments, &env, 1000);
    }

    #[test]
    fn corners_and_t_junctions_leave_no_gap() {
        // A box seen from below (corners shared) and a wall ending on another's face.
        let segments = [
            Segment {
                a: v(1.0, 1.0),
                b: v(-1.0, 1.0),
                front: false,
            },
            Segment {
                a: v(-1.0, 1.0),
                b: v(-1.0, 2.0),
                front: false,
            },
            Segment {
                a: v(1.0, 2.0),
                b: v(1.0, 1.0),
                front: false,
            },
            Segment {
                a: v(-10.0, 4.0),
                b: v(10.0, 4.0),
                front: false,
            },
            Segment {
                a: v(6.0, 4.0),
                b: v(6.0, 2.5),
                front: false,
            },
        ];
        let env = build(&segments);
        let pieces = env.pieces();
        for w in pieces.windows(2) {
            assert_eq!(w[0].hi, w[1].lo, "a gap between {w:?}");
        }
        check_against_rays(&segments, &env, 2000);
        // The box's front in the middle hides its sides; the far wall is seen on both sides
        // of it and on both sides of the post standing on it.
        let seen = |id: u32| pieces.iter().filter(|p| p.segment == id).count();
        assert_eq!(
            [seen(0), seen(1), seen(2), seen(3), seen(4)],
            [1, 0, 0, 3, 1]
        );
    }

    #[test]
    fn random_segments_match_ray_casting_in_any_insertion_order() {
        let mut rng = flatland_testkit::rng(7);
        for case in 0..60 {
            let mut p = || v(rng.random_range(-3.0..3.0), rng.random_range(-1.0..3.0));
            let mut segments: Vec<Segment> = (0..2 + case % 12)
                .map(|_| Segment {
                    a: p(),
                    b: p(),
                    front: false,
                })
                .collect();
            let env = build(&segments);
            check_against_rays(&segments, &env, 997);
            segments.reverse();
            let reversed = build(&segments);
            check_against_rays(&segments, &reversed, 997);
        }
    }

    /// A thin wall as two one-sided faces back to back, on one line: from either side, in either
    /// insertion order, the face towards the point owns every direction the wall covers, also
    /// when the faces' end points went through the frame's rounding (an oblique wall).
    #[test]
    fn back_to_back_faces_show_the_one_facing_the_point() {
        let mut rng = ChaCha8Rng::seed_from_u64(19);
        let thin = |p: DVec2, q: DVec2| {
            [
                Segment {
                    a: p,
                    b: q,
                    front: true,
                },
                Segment {
                    a: q,
                    b: p,
                    front: true,
                },
            ]
        };
        let mut walls = vec![
            thin(v(1.5, 1.0), v(-1.5, 1.0)),
            thin(v(-2.0, 3.0), v(2.0, 0.5)),
        ];
        for _ in 0..40 {
            let mut p = || v(rng.random_range(-3.0..3.0), rng.random_range(0.3..3.0));
            walls.push(thin(p(), p()));
        }
        for (w, pair) in walls.iter().enumerate() {
            for order in [[0, 1], [1, 0]] {
                let segments = [pair[order[0]], pair[order[1]]];
                for (y, n) in [(v(0.0, 0.0), v(0.0, 1.0)), (v(0.3, 4.0), v(0.0, -1.0))] {
                    let view = View::new(y, n);
                    let facing = segments.iter().position(|s| view.faced_by(s));
                    let mut env = Envelope::default();
                    for (id, s) in segments.iter().enumerate() {
                        if let Some(span) = view.span(s) {
                            env.insert(&view, &segments, id as u32, span);
                        }
                    }
                    let Some(facing) = facing else {
                        continue; // y on the wall's line: it is seen edge-on
                    };
                    assert!(!env.pieces().is_empty(), "wall {w}: nothing seen");
                    for piece in env.pieces() {
                        assert_eq!(
                            piece.segment as usize, facing,
                            "wall {w}, order {order:?}, from {y}: the back face owns {piece:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn hiding_needs_full_cover_no_farther_than_the_distance() {
        let segments = [Segment {
            a: v(1.0, 1.0),
            b: v(-1.0, 1.0),
            front: false,
        }];
        let env = build(&segments);
        assert!(env.hides([-0.5, 0.5], 1.5));
        assert!(
            !env.hides([-0.5, 0.5], 1.2),
            "the cover reaches depth √2 at its ends"
        );
        assert!(!env.hides([-0.9, 0.5], 10.0), "a gap below −1/√2");
        assert!(env.hides([-0.7, 0.7], 10.0));
    }
}
