//! Where the panels go in the central area: the kernel plot (a square), the learned ζ and the
//! error beside it, the relit scene (the scene lit by its moving lights, the biggest panel) on
//! the right; below, the curves and the scene lit by the learned kernel.

use egui::{Pos2, Rect, Vec2};

use crate::views;

/// Where the panels go (see the module docs).
pub(super) struct Layout {
    pub(super) kernel: Rect,
    pub(super) approx: Rect,
    pub(super) error: Rect,
    pub(super) relit: Rect,
    pub(super) scene: Rect,
    pub(super) curves: Rect,
}

impl Layout {
    pub(super) fn of(full: Rect) -> Layout {
        let gap = 8.0;
        let bottom_h = (full.height() * 0.32).clamp(150.0, 300.0);
        let top_h = full.height() - bottom_h - gap;
        let big = top_h.min(full.width() * 0.30);
        let small = (big - views::TITLE_H) / 2.0 + views::TITLE_H / 2.0;
        let kernel = Rect::from_min_size(full.min, Vec2::splat(big));
        let approx =
            Rect::from_min_size(kernel.right_top() + Vec2::new(gap, 0.0), Vec2::splat(small));
        let error = Rect::from_min_size(
            approx.left_bottom() + Vec2::new(0.0, big - 2.0 * small),
            Vec2::splat(small),
        );
        let relit = Rect::from_min_max(
            Pos2::new(approx.right() + gap, full.top()),
            Pos2::new(full.right(), full.top() + top_h),
        );
        let bottom = Rect::from_min_max(Pos2::new(full.left(), full.top() + top_h + gap), full.max);
        let scene_w = (bottom.height() * 1.6).min(bottom.width() * 0.45);
        let curves = Rect::from_min_max(
            bottom.min,
            Pos2::new(bottom.right() - scene_w - gap, bottom.bottom()),
        );
        let scene = Rect::from_min_max(
            Pos2::new(bottom.right() - scene_w, bottom.top()),
            bottom.max,
        );
        Layout {
            kernel,
            approx,
            error,
            relit,
            scene,
            curves,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_relit_scene_is_the_biggest_panel_and_nothing_overlaps() {
        let full = Rect::from_min_size(Pos2::new(268.0, 48.0), Vec2::new(1010.0, 712.0));
        let l = Layout::of(full);
        let panels = [l.kernel, l.approx, l.error, l.relit, l.scene, l.curves];
        let area = |r: &Rect| r.width() * r.height();
        for (i, a) in panels.iter().enumerate() {
            assert!(full.contains_rect(*a), "{i}: {a:?}");
            assert!(area(a) <= area(&l.relit), "{i}: {a:?}");
            for b in &panels[i + 1..] {
                assert!(
                    !a.intersects(*b) || a.intersect(*b).area() < 1.0,
                    "{a:?} {b:?}"
                );
            }
        }
    }
}
