//! Heatmaps of a function of `(s, t)` as a reader needs them: `t` (receiver) to the right and
//! `s` (sender) upwards, as in the viewer; the surface edges' boundaries marked and their indices
//! on both axes; a colour bar with values; a title.

use flatland_geom::{EdgeId, Scene};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{register_font, short_number};
use crate::PictureError;
use crate::colormap::{LOG_DECADES, Scale, inferno};

/// Smallest side of the plotted square in pixels: small grids are scaled up (nearest
/// neighbour), so labels fit and a cell stays a crisp square.
const MIN_SIDE: usize = 480;
const LEFT: u32 = 78;
const TOP: u32 = 46;
const BOTTOM: u32 = 62;
const BAR_GAP: u32 = 22;
const BAR_WIDTH: u32 = 22;
const RIGHT: u32 = BAR_GAP + BAR_WIDTH + 86;
/// Edge boundaries are drawn only while at least this many pixels apart on average.
const MIN_BOUNDARY_GAP: f64 = 4.0;

/// The network drawn over a heatmap: cells at their re-projected `(s, t)`, and its edges.
#[derive(Clone, Copy)]
pub struct Overlay<'a> {
    /// Per cell, its mean `(s, t)`, if it has won a sample.
    pub cells: &'a [Option<[f64; 2]>],
    /// The network's edges, as cell ids.
    pub edges: &'a [(usize, usize)],
}

/// What a heatmap shows besides its values.
pub struct Heatmap<'a> {
    /// The title above the plot.
    pub title: String,
    /// The colour bar's label (what the values are).
    pub quantity: &'a str,
    /// The scene whose surface edges lay out `s` and `t`.
    pub scene: &'a Scene,
    /// Colour by log10 over [`LOG_DECADES`] decades below `top`.
    pub log: bool,
    /// The value of the top colour (larger values are clamped to it).
    pub top: f64,
    /// Cells and network edges to draw over the values (which are then dimmed).
    pub overlay: Option<Overlay<'a>>,
}

/// A heatmap of `grid` over `scene`, scaled by the project's one rule ([`Scale::fit`]).
pub fn heatmap<'a>(
    title: String,
    quantity: &'a str,
    scene: &'a Scene,
    grid: &[f64],
    log: bool,
) -> Heatmap<'a> {
    Heatmap {
        title,
        quantity,
        scene,
        log,
        top: Scale::fit(grid, log).top,
        overlay: None,
    }
}

impl Heatmap<'_> {
    fn scale(&self) -> Scale {
        Scale {
            top: self.top,
            log: self.log,
        }
    }
}

/// The heatmap of an `res × res` grid (row `i` ↔ `s = (i + ½)/res`, column `j` ↔ `t`), PNG-encoded.
pub fn heatmap_png(grid: &[f64], res: usize, map: &Heatmap<'_>) -> Result<Vec<u8>, PictureError> {
    if res == 0 || Some(grid.len()) != res.checked_mul(res) {
        return Err(PictureError::GridSize {
            values: grid.len(),
            res,
        });
    }
    register_font();
    let zoom = MIN_SIDE.div_ceil(res).max(1);
    let side = res * zoom;
    let side_px = u32::try_from(side).map_err(|_| PictureError::TooLarge {
        what: "heatmap",
        side,
    })?;
    let (width, height) = (LEFT + side_px + RIGHT, TOP + side_px + BOTTOM);
    let mut rgb = vec![255u8; width as usize * height as usize * 3];

    // The values, s upwards: pixel row y shows grid row res − 1 − y / zoom.
    let dim = if map.overlay.is_some() { 0.55 } else { 1.0 };
    let scale = map.scale();
    let colours: Vec<[u8; 3]> = grid
        .iter()
        .map(|&v| scale.colour(v).map(|c| (f64::from(c) * dim) as u8))
        .collect();
    for y in 0..side {
        let row = res - 1 - y / zoom;
        let line = (TOP as usize + y) * width as usize + LEFT as usize;
        for x in 0..side {
            let at = (line + x) * 3;
            rgb[at..at + 3].copy_from_slice(&colours[row * res + x / zoom]);
        }
    }
    // The colour bar: bottom to top, 0 to 1.
    let bar_left = (LEFT + side_px + BAR_GAP) as usize;
    for y in 0..side {
        let colour = inferno(1.0 - y as f64 / (side - 1).max(1) as f64);
        let line = (TOP as usize + y) * width as usize + bar_left;
        for x in 0..BAR_WIDTH as usize {
            let at = (line + x) * 3;
            rgb[at..at + 3].copy_from_slice(&colour);
        }
    }

    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        let err = PictureError::draw("the heatmap");
        draw_labels(&root, map, side_px).map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    super::encode_png(&rgb, width, height)
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// `(s, t)` → pixel of a plot `side` pixels wide: `t` to the right, `s` upwards.
fn pixel(side: u32) -> impl Fn(f64, f64) -> (i32, i32) + Copy {
    let (left, top, side_i) = (LEFT as i32, TOP as i32, side as i32);
    let fside = f64::from(side);
    move |s: f64, t: f64| {
        (
            left + (t * fside).round() as i32,
            top + side_i - (s * fside).round() as i32,
        )
    }
}

/// The labels' text: black, `size` pixels.
fn text(size: f64) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", size).into_font()).color(&BLACK)
}

/// Everything drawn on top of the pixels: boundaries, overlay, frame, axes, colour bar, title.
fn draw_labels(root: &Area<'_>, map: &Heatmap<'_>, side: u32) -> DrawResult {
    let (left, top, side_i) = (LEFT as i32, TOP as i32, side as i32);
    let px = pixel(side);

    // Surface edge boundaries (parameter starts) and where each edge's label goes.
    let surfaces = map.scene.surface_edges();
    let ranges: Vec<(EdgeId, f64, f64)> = surfaces
        .iter()
        .filter_map(|&e| map.scene.edge_param_range(e).map(|(a, b)| (e, a, b)))
        .collect();
    let show_boundaries = f64::from(side) / ranges.len().max(1) as f64 >= MIN_BOUNDARY_GAP;
    if show_boundaries {
        let line = WHITE.mix(0.35);
        for &(_, s0, _) in ranges.iter().filter(|r| r.1 > 0.0) {
            root.draw(&PathElement::new([px(s0, 0.0), px(s0, 1.0)], line))?;
            root.draw(&PathElement::new([px(0.0, s0), px(1.0, s0)], line))?;
        }
    }
    if let Some(Overlay { cells, edges }) = map.overlay {
        let at = |c: usize| cells.get(c).copied().flatten().map(|[s, t]| px(s, t));
        for &(a, b) in edges {
            if let (Some(p), Some(q)) = (at(a), at(b)) {
                root.draw(&PathElement::new([p, q], RGBColor(230, 230, 230).mix(0.8)))?;
            }
        }
        for c in 0..cells.len() {
            if let Some(p) = at(c) {
                root.draw(&Circle::new(p, 3, RGBColor(60, 220, 255).filled()))?;
            }
        }
    }
    root.draw(&Rectangle::new(
        [(left - 1, top - 1), (left + side_i, top + side_i)],
        BLACK.stroke_width(1),
    ))?;
    let boundaries = if show_boundaries { &ranges[..] } else { &[] };
    draw_axes(root, &ranges, boundaries, side)?;
    draw_colour_bar(root, map, side)?;

    // Title.
    root.draw(&Text::new(
        map.title.clone(),
        (left + side_i / 2, 8),
        text(17.0).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    Ok(())
}

/// The axes: a tick at both ends and at every boundary drawn (`boundaries`), each edge's index
/// mid-interval where it fits (`ranges`: every surface edge's parameter range), the axes' names.
fn draw_axes(
    root: &Area<'_>,
    ranges: &[(EdgeId, f64, f64)],
    boundaries: &[(EdgeId, f64, f64)],
    side: u32,
) -> DrawResult {
    let (left, top, side_i) = (LEFT as i32, TOP as i32, side as i32);
    let px = pixel(side);
    let tick = 6;
    let ticks = [0.0, 1.0].into_iter().chain(boundaries.iter().map(|r| r.1));
    for u in ticks {
        let (x, _) = px(0.0, u);
        let (_, y) = px(u, 0.0);
        let (bottom, l) = (top + side_i, left - 1);
        root.draw(&PathElement::new([(x, bottom), (x, bottom + tick)], BLACK))?;
        root.draw(&PathElement::new([(l - tick, y), (l, y)], BLACK))?;
    }
    let label = text(14.0);
    let centred = label.pos(Pos::new(HPos::Center, VPos::Top));
    let right = label.pos(Pos::new(HPos::Right, VPos::Center));
    for &(edge, a, b) in ranges {
        if (b - a) * f64::from(side) < 16.0 {
            continue;
        }
        let mid = 0.5 * (a + b);
        let name = edge.to_string();
        let (x, _) = px(0.0, mid);
        let (_, y) = px(mid, 0.0);
        root.draw(&Text::new(
            name.clone(),
            (x, top + side_i + tick + 2),
            centred.clone(),
        ))?;
        root.draw(&Text::new(name, (left - tick - 4, y), right.clone()))?;
    }
    let axis = text(15.0);
    root.draw(&Text::new(
        "t: receiver in [0, 1), by surface edge",
        (left + side_i / 2, top + side_i + 32),
        axis.pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    root.draw(&Text::new(
        "s: sender in [0, 1), by surface edge",
        (18, top + side_i / 2),
        axis.transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))?;
    Ok(())
}

/// The colour bar right of the plot: frame, ticks with values, the quantity's name.
fn draw_colour_bar(root: &Area<'_>, map: &Heatmap<'_>, side: u32) -> DrawResult {
    let (left, top, side_i) = (LEFT as i32, TOP as i32, side as i32);
    let fside = f64::from(side);
    let bar_left = left + side_i + BAR_GAP as i32;
    let bar_right = bar_left + BAR_WIDTH as i32;
    root.draw(&Rectangle::new(
        [(bar_left - 1, top - 1), (bar_right, top + side_i)],
        BLACK.stroke_width(1),
    ))?;
    let value_at = |x: f64| map.scale().value_at(x);
    let steps = if map.log { LOG_DECADES as i32 } else { 4 };
    let value_label = text(13.0).pos(Pos::new(HPos::Left, VPos::Center));
    for k in 0..=steps {
        let x = f64::from(k) / f64::from(steps);
        let y = top + side_i - (x * fside).round() as i32;
        root.draw(&PathElement::new(
            [(bar_right, y), (bar_right + 5, y)],
            BLACK,
        ))?;
        let v = short_number(value_at(x));
        let v = match (k, map.log) {
            (k, _) if k == steps => format!("≥ {v}"),
            (0, true) => format!("≤ {v}"),
            _ => v,
        };
        root.draw(&Text::new(v, (bar_right + 8, y), value_label.clone()))?;
    }
    root.draw(&Text::new(
        format!(
            "{}{}",
            map.quantity,
            if map.log { " (log scale)" } else { "" }
        ),
        (bar_left + BAR_WIDTH as i32 / 2, top - 8),
        text(13.0).pos(Pos::new(HPos::Center, VPos::Bottom)),
    ))?;

    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The heatmaps of `kernel`, `eval` and `figure` were bare R×R pictures: no axes, labels,
    /// colour bar or title. Checks the layout: s upwards, t to the right, the bar's colours,
    /// and text in the margins.
    #[test]
    fn heatmaps_have_axes_a_colour_bar_and_a_title() {
        let scene = flatland_geom::bundled::scene("fig3").unwrap();
        // 16 × 16, 1 in row 0 (s smallest) and column 15 (t largest) only.
        let res = 16;
        let grid: Vec<f64> = (0..res * res)
            .map(|k| {
                if k / res == 0 && k % res == res - 1 {
                    1.0
                } else {
                    0.0
                }
            })
            .collect();
        let map = Heatmap {
            title: "a title".into(),
            quantity: "k",
            scene: &scene,
            log: false,
            top: 1.0,
            overlay: None,
        };
        let png = heatmap_png(&grid, res, &map).unwrap();
        let image = image::load_from_memory(&png).unwrap().to_rgb8();
        let side = (MIN_SIDE.div_ceil(res) * res) as u32;
        assert_eq!(
            image.dimensions(),
            (LEFT + side + RIGHT, TOP + side + BOTTOM)
        );
        let at = |x: u32, y: u32| image.get_pixel(x, y).0;
        let cell = side / res as u32;
        // The bright cell is at the bottom right: s = 0 at the bottom, t = 1 at the right.
        let (right, bottom) = (LEFT + side - cell / 2, TOP + side - cell / 2);
        assert_eq!(at(right, bottom), inferno(1.0));
        assert_eq!(at(LEFT + cell / 2, TOP + cell / 2), inferno(0.0));
        // The colour bar runs from the bottom colour to the top colour.
        let bar_x = LEFT + side + BAR_GAP + BAR_WIDTH / 2;
        assert_eq!(at(bar_x, TOP), inferno(1.0));
        assert_eq!(at(bar_x, TOP + side - 1), inferno(0.0));
        // Text: dark pixels in the title band, left of the plot (s labels), under it (t labels)
        // and right of the bar (values).
        let dark = |x0: u32, x1: u32, y0: u32, y1: u32| {
            (x0..x1).any(|x| (y0..y1).any(|y| at(x, y).iter().all(|&c| c < 100)))
        };
        assert!(dark(LEFT, LEFT + side, 0, TOP - 10), "title");
        assert!(dark(0, LEFT - 8, TOP, TOP + side), "s axis");
        assert!(
            dark(LEFT, LEFT + side, TOP + side + 8, TOP + side + BOTTOM),
            "t axis"
        );
        assert!(
            dark(bar_x + BAR_WIDTH, LEFT + side + RIGHT, TOP, TOP + side),
            "bar values"
        );
    }
}
