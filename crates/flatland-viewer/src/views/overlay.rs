//! What is drawn over the `(s, t)` heatmaps, rastered on the CPU into transparent images of one
//! pixel per screen pixel of the plot: the cells and the network's edges within faces
//! ([`overlay_image`], made again when a moment is shown), the surface edges' boundaries
//! ([`boundaries_image`], made once per scene and plot size).
//!
//! A frame then draws one textured square whatever the cell or edge count, instead of tens of
//! thousands of triangles: that keeps software GL fast at thousands of cells and edges.

use std::time::Duration;

use egui::{Color32, ColorImage};
use flatland_geom::Scene;

use super::raster::blend;
use super::{BOUNDARY, CELL, CRITICAL, FACE_VISIBLE, NET_EDGE, NEW_CELL, SEEN};
use crate::worker::CellMark;

/// A cell inserted less than this much training time before the moment shown is "new".
pub const NEW_FOR: Duration = Duration::from_secs(1);
/// Boundaries closer than this many pixels to the last one drawn are left out: past that the
/// lines merge into a grey sheet that hides the kernel.
const MIN_BOUNDARY_GAP: f32 = 8.0;

/// The marks of one moment.
#[derive(Clone, Copy, Debug)]
pub struct Marks<'a> {
    /// The cells, by id.
    pub cells: &'a [CellMark],
    /// The network's edges within faces.
    pub edges: &'a [[u32; 2]],
    /// Cells with this id or more are new ([`NEW_FOR`]).
    pub new_from: usize,
    /// Draw the cells.
    pub show_cells: bool,
    /// Draw the edges.
    pub show_edges: bool,
}

/// Radius in points of a cell of width δ_c on a plot of `side_pt` points holding `cells`
/// cells: δ_c (which lives in the 4-D input frame, not in (s, t)) is a relative cue, capped
/// by the room each cell has, so thousands of cells stay apart.
fn cell_radius(width: f32, side_pt: f32, cells: usize) -> f32 {
    let room = 0.3 * side_pt / (cells.max(1) as f32).sqrt();
    (width * side_pt * 0.05).clamp(1.5, 4.5).min(room.max(1.0))
}

/// The network's edges within faces (a light-driven learner's probes: the column of `s` each
/// sees, at its `t`), then its cells: discs sized by δ_c, white, cyan when critical (probes
/// light blue), with a black rim, or a lime ring when new; drawn into a transparent
/// `side × side` image (`t` to the right, `s` upwards). `px_per_point` scales the marks with
/// the display's pixel density.
#[must_use]
pub fn overlay_image(side: usize, px_per_point: f32, marks: &Marks<'_>) -> ColorImage {
    let mut img = ColorImage::filled([side, side], Color32::TRANSPARENT);
    let n = side as f32;
    let pos: Vec<Option<[f32; 2]>> = marks
        .cells
        .iter()
        .map(|c| c.st.map(|[s, t]| [t * n, (1.0 - s) * n]))
        .collect();
    if marks.show_edges {
        for (c, p) in marks.cells.iter().zip(&pos) {
            let Some([x, _]) = p else { continue };
            for &[s0, s1] in c.seen.iter() {
                draw_line(&mut img, [*x, (1.0 - s0) * n], [*x, (1.0 - s1) * n], SEEN);
            }
        }
        for &[a, b] in marks.edges {
            if let (Some(Some(pa)), Some(Some(pb))) = (pos.get(a as usize), pos.get(b as usize)) {
                draw_line(&mut img, *pa, *pb, NET_EDGE);
            }
        }
    }
    if marks.show_cells {
        let side_pt = n / px_per_point;
        let shown = pos.iter().filter(|p| p.is_some()).count();
        // Old cells first, so new ones are drawn on top.
        for (id, (c, p)) in marks.cells.iter().zip(&pos).enumerate() {
            let Some(p) = p else { continue };
            let fresh = id >= marks.new_from;
            let r = cell_radius(c.width, side_pt, shown) * px_per_point;
            let fill = if !c.seen.is_empty() {
                FACE_VISIBLE
            } else if c.critical {
                CRITICAL
            } else {
                CELL
            };
            let (rim, rim_w) = if fresh {
                (NEW_CELL, 1.5 * px_per_point)
            } else {
                (Color32::BLACK, px_per_point)
            };
            draw_disc(&mut img, *p, r, fill, rim, rim_w);
        }
    }
    img
}

/// The surface edges' boundaries on both axes as faint lines in a transparent `side × side`
/// image; a boundary closer than [`MIN_BOUNDARY_GAP`] pixels to the last drawn is left out.
/// Returns the image and where the drawn boundaries are (as parameters, for the axis ticks).
#[must_use]
pub fn boundaries_image(side: usize, scene: &Scene) -> (ColorImage, Vec<f64>) {
    let mut img = ColorImage::filled([side, side], Color32::TRANSPARENT);
    let drawn = thinned_boundaries(scene, side as f32);
    for &s in &drawn {
        let x = ((s * side as f64) as usize).min(side - 1);
        let y = side - 1 - x;
        for k in 0..side {
            let v = &mut img.pixels[k * side + x];
            *v = blend(*v, BOUNDARY);
            if k != x {
                let h = &mut img.pixels[y * side + k];
                *h = blend(*h, BOUNDARY);
            }
        }
    }
    (img, drawn)
}

/// The parameters where surface edges start (after 0), each at least [`MIN_BOUNDARY_GAP`]
/// pixels after the previous kept one on a plot `side` pixels wide.
fn thinned_boundaries(scene: &Scene, side: f32) -> Vec<f64> {
    let mut starts: Vec<f64> = scene
        .surface_edges()
        .iter()
        .filter_map(|&e| scene.edge_param_range(e).map(|(s0, _)| s0))
        .filter(|s0| *s0 > 0.0)
        .collect();
    starts.sort_by(f64::total_cmp);
    let mut kept: Vec<f64> = Vec::new();
    for s in starts {
        if kept
            .last()
            .is_none_or(|last| (s - last) as f32 * side >= MIN_BOUNDARY_GAP)
        {
            kept.push(s);
        }
    }
    kept
}

fn draw_line(img: &mut ColorImage, a: [f32; 2], b: [f32; 2], color: Color32) {
    let [w, h] = img.size;
    let steps = (b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil().max(1.0) as usize;
    for k in 0..=steps {
        let u = k as f32 / steps as f32;
        let x = (a[0] + (b[0] - a[0]) * u) as usize;
        let y = (a[1] + (b[1] - a[1]) * u) as usize;
        if x < w && y < h {
            let px = &mut img.pixels[y * w + x];
            *px = blend(*px, color);
        }
    }
}

/// A disc of radius `r` around `c` filled with `fill`, in a ring `rim_w` wide of `rim`.
fn draw_disc(img: &mut ColorImage, c: [f32; 2], r: f32, fill: Color32, rim: Color32, rim_w: f32) {
    let [w, h] = img.size;
    let outer = r + rim_w;
    let (x0, x1) = (
        (c[0] - outer).floor().max(0.0) as usize,
        ((c[0] + outer).ceil() as usize).min(w),
    );
    let (y0, y1) = (
        (c[1] - outer).floor().max(0.0) as usize,
        ((c[1] + outer).ceil() as usize).min(h),
    );
    for y in y0..y1 {
        for x in x0..x1 {
            let d = ((x as f32 + 0.5 - c[0]).powi(2) + (y as f32 + 0.5 - c[1]).powi(2)).sqrt();
            if d <= r {
                img.pixels[y * w + x] = fill;
            } else if d <= outer {
                img.pixels[y * w + x] = rim;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(st: [f32; 2], critical: bool) -> CellMark {
        CellMark {
            st: Some(st),
            width: 0.1,
            critical,
            seen: Default::default(),
        }
    }

    #[test]
    fn overlay_draws_cells_and_edges_where_they_are() {
        let cells = [mark([0.25, 0.75], true), mark([0.75, 0.25], false)];
        let marks = Marks {
            cells: &cells,
            edges: &[[0, 1]],
            new_from: 2,
            show_cells: true,
            show_edges: true,
        };
        let img = overlay_image(100, 1.0, &marks);
        // Cell 0: t = 0.75 → column 75, s = 0.25 → row 75 (s upwards).
        assert_eq!(img.pixels[75 * 100 + 75], CRITICAL);
        assert_eq!(img.pixels[25 * 100 + 25], CELL);
        assert_ne!(img.pixels[50 * 100 + 50], Color32::TRANSPARENT, "the edge");
        assert_eq!(img.pixels[0], Color32::TRANSPARENT);
        let bare = overlay_image(
            100,
            1.0,
            &Marks {
                show_cells: false,
                show_edges: false,
                ..marks
            },
        );
        assert!(bare.pixels.iter().all(|p| *p == Color32::TRANSPARENT));
        let cells_only = overlay_image(
            100,
            1.0,
            &Marks {
                show_edges: false,
                ..marks
            },
        );
        assert_eq!(
            cells_only.pixels[50 * 100 + 50],
            Color32::TRANSPARENT,
            "no edge"
        );
    }

    #[test]
    fn new_cells_have_a_ring_and_old_ones_a_black_rim() {
        let cells = [mark([0.5, 0.2], false), mark([0.5, 0.8], false)];
        let marks = Marks {
            cells: &cells,
            edges: &[],
            new_from: 1,
            show_cells: true,
            show_edges: false,
        };
        let img = overlay_image(200, 1.0, &marks);
        let ring_of = |t: f32| {
            let (x, y) = ((t * 200.0) as usize, 100);
            (0..12)
                .map(|dx| img.pixels[y * 200 + x + dx])
                .filter(|p| *p != CELL && *p != Color32::TRANSPARENT)
                .collect::<Vec<_>>()
        };
        assert!(ring_of(0.2).iter().all(|p| *p == Color32::BLACK));
        assert!(ring_of(0.8).contains(&NEW_CELL));
    }

    #[test]
    fn thousands_of_cells_stay_apart() {
        // 6400 cells on a 500-point plot: 6 points apart; discs of at most 2 points.
        assert!(cell_radius(0.5, 500.0, 6400) <= 2.0);
        assert!(
            cell_radius(0.5, 500.0, 10) >= 4.5 - 1e-6,
            "few cells: sized by δ_c"
        );
        assert!(cell_radius(0.001, 500.0, 10) >= 1.5, "never invisible");
    }

    #[test]
    fn boundaries_are_thinned_to_a_few_pixels_apart() {
        let fig3 = flatland_geom::bundled::scene("fig3").unwrap();
        let (img, drawn) = boundaries_image(512, &fig3);
        assert_eq!(img.size, [512, 512]);
        let surfaces = fig3.surface_edges().len();
        assert_eq!(drawn.len(), surfaces - 1, "fig3's edges are far apart");
        let big = flatland_geom::generate::floor_plan(1000, 1).unwrap();
        let drawn = thinned_boundaries(&big, 400.0);
        assert!(
            drawn.len() < big.surface_edges().len() / 2,
            "{}",
            drawn.len()
        );
        assert!(
            drawn
                .windows(2)
                .all(|w| (w[1] - w[0]) * 400.0 >= f64::from(MIN_BOUNDARY_GAP) - 1e-9)
        );
    }
}
