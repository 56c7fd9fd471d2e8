//! Where the panels go in the central area: the kernel plot (a big square), the learned ζ and
//! the error beside it, the scene (and the exact lit scene) on the right, the curves below.

use egui::{Pos2, Rect, Vec2};

use crate::views;

/// Where the panels go: the kernel plot (a big square), ζ̃ and the error beside it, the scene
/// (and the exact lit scene) on the right, the curves below.
pub(super) struct Layout {
    pub(super) kernel: Rect,
    pub(super) approx: Rect,
    pub(super) error: Rect,
    pub(super) scene: Rect,
    pub(super) exact: Option<Rect>,
    pub(super) curves: Rect,
}

impl Layout {
    pub(super) fn of(full: Rect, lit: bool) -> Layout {
        let gap = 8.0;
        let curves_h = (full.height() * 0.32).clamp(150.0, 300.0);
        let top_h = full.height() - curves_h - gap;
        let big = top_h.min(full.width() * 0.42);
        let small = (big - views::TITLE_H) / 2.0 + views::TITLE_H / 2.0;
        let kernel = Rect::from_min_size(full.min, Vec2::splat(big));
        let approx =
            Rect::from_min_size(kernel.right_top() + Vec2::new(gap, 0.0), Vec2::splat(small));
        let error = Rect::from_min_size(
            approx.left_bottom() + Vec2::new(0.0, big - 2.0 * small),
            Vec2::splat(small),
        );
        let right = Rect::from_min_max(
            Pos2::new(approx.right() + gap, full.top()),
            Pos2::new(full.right(), full.top() + top_h),
        );
        let (scene, exact) = if !lit {
            (right, None)
        } else if right.width() >= 1.6 * right.height() {
            // Wide: side by side.
            let mid = right.center().x;
            (
                Rect::from_min_max(right.min, Pos2::new(mid - gap / 2.0, right.bottom())),
                Some(Rect::from_min_max(
                    Pos2::new(mid + gap / 2.0, right.top()),
                    right.max,
                )),
            )
        } else {
            let split = right.top() + right.height() * 0.56;
            (
                Rect::from_min_max(right.min, Pos2::new(right.right(), split - gap / 2.0)),
                Some(Rect::from_min_max(
                    Pos2::new(right.left(), split + gap / 2.0),
                    right.max,
                )),
            )
        };
        let curves = Rect::from_min_max(Pos2::new(full.left(), full.top() + top_h + gap), full.max);
        Layout {
            kernel,
            approx,
            error,
            scene,
            exact,
            curves,
        }
    }
}
