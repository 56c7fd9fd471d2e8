//! The picture of `flatland solve`: the scene lit by a solved radiosity (each element coloured
//! by B as it runs along it, emitters and point lights marked, a colour bar) beside B(s)
//! against the exact solution; and the lit scene alone ([`panel_png`]), one picture per
//! position of `flatland relight`. B along an element is what the caller gives: the final
//! gather where it has one (`FinalGather::along`), else the line through the element
//! midpoints (`flatland_solve::line_along`) — never a flat step.

use flatland_geom::{PointLight, Role, Scene};
use flatland_solve::{ExactReference, Mesh};
use plotters::prelude::*;

use crate::PictureError;
use crate::plot::{encode_png, register_font};

/// What the PNG shows.
pub struct Picture<'a> {
    /// The scene lit.
    pub scene: &'a Scene,
    /// The scene's name in the title.
    pub label: &'a str,
    /// The kernel it was solved with, in words.
    pub kernel: &'a str,
    /// The mesh `b` is on.
    pub mesh: &'a Mesh,
    /// The solved B per element of `mesh`.
    pub b: &'a [f64],
    /// B at the start, middle and end of every element of `mesh`
    /// ([`ALONG`](flatland_solve::ALONG)).
    pub along: &'a [[f64; 3]],
    /// The exact solution B(s) is drawn against.
    pub reference: &'a ExactReference,
    /// The relative L2 error of the reflected part, for the title.
    pub rel_l2_reflected: f64,
}

const WIDTH: u32 = 1600;
const HEIGHT: u32 = 760;
const SCENE_WIDTH: u32 = 760;

fn inferno(x: f64) -> RGBColor {
    let [r, g, b] = crate::colormap::inferno(x);
    RGBColor(r, g, b)
}

/// The lit scene alone: what one position of a relighting shows.
pub struct Panel<'a> {
    /// The scene lit.
    pub scene: &'a Scene,
    /// The caption above it.
    pub caption: String,
    /// The mesh `b` is on.
    pub mesh: &'a Mesh,
    /// B per element of `mesh`.
    pub b: &'a [f64],
    /// B at the start, middle and end of every element of `mesh`
    /// ([`ALONG`](flatland_solve::ALONG)).
    pub along: &'a [[f64; 3]],
    /// The point lights, each marked where it stands.
    pub lights: &'a [PointLight],
    /// The top of the colour scale ([`crate::colormap::radiosity_top`] of this B, or one kept
    /// for a series of pictures so that they compare).
    pub top: f64,
}

/// The picture `p`, PNG-encoded.
pub fn lit_scene_png(p: &Picture<'_>) -> Result<Vec<u8>, PictureError> {
    register_font();
    let panel = Panel {
        scene: p.scene,
        caption: format!("{}: lit by the {} kernel", p.label, p.kernel),
        mesh: p.mesh,
        b: p.b,
        along: p.along,
        lights: p.mesh.lights(),
        top: crate::colormap::radiosity_top(p.mesh, p.b),
    };
    check_panel(&panel)?;
    let mut rgb = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        let (left, right) = root.split_horizontally(SCENE_WIDTH);
        draw_scene(&left, &panel).map_err(PictureError::draw("the lit scene"))?;
        draw_curves(&right, p).map_err(PictureError::draw("B(s)"))?;
        root.present()
            .map_err(PictureError::draw("the lit scene's picture"))?;
    }
    encode_png(&rgb, WIDTH, HEIGHT)
}

/// The lit scene alone ([`Panel`]), PNG-encoded.
pub fn panel_png(panel: &Panel<'_>) -> Result<Vec<u8>, PictureError> {
    check_panel(panel)?;
    register_font();
    let mut rgb = vec![255u8; (SCENE_WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (SCENE_WIDTH, HEIGHT)).into_drawing_area();
        draw_scene(&root, panel).map_err(PictureError::draw("the lit scene"))?;
        root.present()
            .map_err(PictureError::draw("the lit scene's picture"))?;
    }
    encode_png(&rgb, SCENE_WIDTH, HEIGHT)
}

/// Refuses a panel whose B or B along the elements is not one per element of its mesh.
fn check_panel(p: &Panel<'_>) -> Result<(), PictureError> {
    PictureError::per_element("B", p.b.len(), p.mesh.len())?;
    PictureError::per_element("B along the elements", p.along.len(), p.mesh.len())
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;
/// The curves' axes: `s` against `B`.
type Axes =
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>;

/// Each element in the colour of its B, blockers grey, emitters and point lights marked, a
/// colour bar.
fn draw_scene(area: &Area<'_>, p: &Panel<'_>) -> DrawResult {
    let (plot, bar) = area.split_horizontally(SCENE_WIDTH - 110);
    let (lo, hi) = p.scene.bounds();
    let span = (hi - lo).max_element() * 1.1;
    let centre = (lo + hi) * 0.5;
    let mut chart = ChartBuilder::on(&plot)
        .caption(&p.caption, ("sans-serif", 20))
        .margin(12)
        .build_cartesian_2d(
            (centre.x - span / 2.0)..(centre.x + span / 2.0),
            (centre.y - span / 2.0)..(centre.y + span / 2.0),
        )?;
    let top = p.top;
    for edge in p.scene.edges().iter().filter(|e| e.role == Role::Blocker) {
        chart.draw_series(LineSeries::new(
            [(edge.a.x, edge.a.y), (edge.b.x, edge.b.y)],
            RGBColor(140, 140, 140).stroke_width(3),
        ))?;
    }
    // Each element in pieces of a few pixels, each in the colour of B at its middle.
    let pixels_per_unit = f64::from(plot.dim_in_pixel().0) / span;
    for (e, along) in p.mesh.elements().iter().zip(p.along) {
        let pieces = ((e.length * pixels_per_unit / 3.0).ceil() as usize).clamp(1, 16);
        for k in 0..pieces {
            let (u0, u1) = (k as f64 / pieces as f64, (k + 1) as f64 / pieces as f64);
            let (a, b) = (e.a + (e.b - e.a) * u0, e.a + (e.b - e.a) * u1);
            let value = along_at(along, 0.5 * (u0 + u1));
            chart.draw_series(LineSeries::new(
                [(a.x, a.y), (b.x, b.y)],
                inferno(value / top).stroke_width(8),
            ))?;
        }
    }
    // Emitters: a sun on the front side of each, with its emission.
    for edge in p.mesh.edges().iter().filter(|e| e.emission > 0.0) {
        let mid = (edge.a + edge.b) * 0.5;
        let at = mid + edge.normal * (0.045 * span);
        let at = (at.x, at.y);
        chart.draw_series([Circle::new(at, 9, RGBColor(255, 200, 0).filled())])?;
        chart.draw_series([Circle::new(at, 9, BLACK.stroke_width(1))])?;
        let text = format!("E = {}", edge.emission);
        chart.draw_series([Text::new(
            text,
            (at.0 + 0.025 * span, at.1 + 0.01 * span),
            ("sans-serif", 16).into_font(),
        )])?;
    }
    // Point lights: a yellow disc with a cross where each stands.
    for light in p.lights.iter().filter(|l| l.power > 0.0) {
        let at = (light.at.x, light.at.y);
        chart.draw_series([Circle::new(at, 7, RGBColor(255, 230, 60).filled())])?;
        chart.draw_series([Circle::new(at, 7, BLACK.stroke_width(2))])?;
        chart.draw_series([Cross::new(at, 11, BLACK.stroke_width(1))])?;
    }
    draw_colour_bar(&bar, top)
}

/// B at fraction `u` of an element from its values at the start, middle and end: the line
/// through them.
fn along_at(along: &[f64; 3], u: f64) -> f64 {
    if u <= 0.5 {
        along[0] + (along[1] - along[0]) * 2.0 * u
    } else {
        along[1] + (along[2] - along[1]) * (2.0 * u - 1.0)
    }
}

/// The lit scene's colour bar: 0 at the bottom, `top` (the brightest non-emitter) at the top.
fn draw_colour_bar(bar: &Area<'_>, top: f64) -> DrawResult {
    let (_, h) = bar.dim_in_pixel();
    let (x0, y0, bar_h) = (20_i32, (h as i32) / 5, (h as i32) * 3 / 5);
    for k in 0..bar_h {
        let v = 1.0 - f64::from(k) / f64::from(bar_h - 1);
        bar.draw(&Rectangle::new(
            [(x0, y0 + k), (x0 + 24, y0 + k + 1)],
            inferno(v).filled(),
        ))?;
    }
    bar.draw(&Rectangle::new(
        [(x0, y0), (x0 + 24, y0 + bar_h)],
        BLACK.stroke_width(1),
    ))?;
    let font = ("sans-serif", 15).into_font();
    for (frac, value) in [(0.0, 0.0), (0.5, 0.5 * top), (1.0, top)] {
        let y = y0 + ((1.0 - frac) * f64::from(bar_h)) as i32;
        bar.draw(&PathElement::new([(x0 + 24, y), (x0 + 30, y)], BLACK))?;
        bar.draw(&Text::new(
            format!("{value:.3}"),
            (x0 + 33, y - 7),
            font.clone(),
        ))?;
    }
    bar.draw(&Text::new(
        "B",
        (x0 + 6, y0 - 28),
        ("sans-serif", 18).into_font(),
    ))?;
    bar.draw(&Text::new(
        "emitters",
        (x0 - 12, y0 + bar_h + 14),
        ("sans-serif", 13).into_font(),
    ))?;
    bar.draw(&Text::new(
        "above scale",
        (x0 - 12, y0 + bar_h + 30),
        ("sans-serif", 13).into_font(),
    ))?;
    Ok(())
}

/// The B axis of the curves: emitters are 10–100× brighter than what they light, so the axis
/// stops above the brightest non-emitter (emitters' values are written where they leave the
/// plot); a poor kernel can give negative radiosity, shown down to a quarter of the range.
fn curve_range(p: &Picture<'_>) -> (f64, f64) {
    let (fine, exact) = (p.reference.mesh(), &p.reference.solution().radiosity);
    let lit = |mesh: &Mesh, b: &[f64]| {
        (0..mesh.len())
            .filter(|&i| mesh.edge_of(i).emission == 0.0)
            .map(|i| b[i])
            .fold(0.0_f64, f64::max)
    };
    let mut y_max = lit(p.mesh, p.b).max(lit(fine, exact)) * 1.25;
    if y_max <= 0.0 || !y_max.is_finite() {
        y_max =
            p.b.iter()
                .chain(exact)
                .copied()
                .fold(0.0_f64, f64::max)
                .max(1e-300)
                * 1.08;
    }
    let lowest = p.b.iter().copied().fold(0.0_f64, f64::min);
    let y_min = lowest.max(-0.25 * y_max);
    (y_min, y_max)
}

/// B(s): the solution as it runs along each element, the exact reference as a line through
/// its fine elements, emitters shaded, edges marked.
fn draw_curves(area: &Area<'_>, p: &Picture<'_>) -> DrawResult {
    let fine = p.reference.mesh();
    let exact = &p.reference.solution().radiosity;
    let (y_min, y_max) = curve_range(p);
    let clip = |b: f64| b.clamp(y_min, y_max);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "B(s): {} kernel on {} elements vs exact on {} (rel. L2 of B − E: {:.2} %)",
                p.kernel,
                p.mesh.len(),
                fine.len(),
                100.0 * p.rel_l2_reflected
            ),
            ("sans-serif", 18),
        )
        .margin(14)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(0.0..1.0, y_min..y_max)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("s (arc length / L)")
        .y_desc("radiosity B")
        .label_style(("sans-serif", 15))
        .draw()?;
    for edge in p.mesh.edges() {
        if edge.emission > 0.0 {
            chart.draw_series([Rectangle::new(
                [(edge.s[0], y_min), (edge.s[1], y_max)],
                RGBColor(255, 215, 80).mix(0.25).filled(),
            )])?;
        }
        chart.draw_series(LineSeries::new(
            [(edge.s[0], y_min), (edge.s[0], y_max)],
            RGBColor(200, 200, 200).stroke_width(1),
        ))?;
    }
    for edge in fine.edges() {
        let points: Vec<(f64, f64)> = edge
            .elements
            .clone()
            .map(|i| (fine.elements()[i].s_mid, clip(exact[i])))
            .collect();
        chart.draw_series(LineSeries::new(points, BLACK.stroke_width(2)))?;
    }
    let solution = RGBColor(220, 80, 30);
    for edge in p.mesh.edges() {
        // B along each element, joined within an edge.
        let along: Vec<(f64, f64)> = edge
            .elements
            .clone()
            .flat_map(|i| {
                let e = &p.mesh.elements()[i];
                let [start, middle, end] = p.along[i];
                [
                    (e.s[0], clip(start)),
                    (e.s_mid, clip(middle)),
                    (e.s[1], clip(end)),
                ]
            })
            .collect();
        chart.draw_series(LineSeries::new(along, solution.stroke_width(2)))?;
    }
    for edge in p.mesh.edges().iter().filter(|e| e.emission > 0.0) {
        let range = edge.elements.clone();
        let mean = range.clone().map(|i| p.b[i]).sum::<f64>() / range.len().max(1) as f64;
        if mean > y_max {
            chart.draw_series([Text::new(
                format!("B = {mean:.3} (off the axis)"),
                (edge.s[0], y_max * 0.97),
                ("sans-serif", 14).into_font(),
            )])?;
        }
    }
    draw_legend(&mut chart, p, fine.len(), solution)
}

/// The legend of [`draw_curves`], drawn by hand: one entry per kind, not one per segment.
fn draw_legend<'a>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Axes>,
    p: &Picture<'_>,
    fine_elements: usize,
    solution: RGBColor,
) -> DrawResult {
    chart
        .draw_series(LineSeries::new(std::iter::empty(), BLACK.stroke_width(2)))?
        .label(format!("exact kernel, {fine_elements} elements"))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 22, y)], BLACK.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            std::iter::empty(),
            solution.stroke_width(2),
        ))?
        .label(format!("{} kernel, {} elements", p.kernel, p.mesh.len()))
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 22, y)], solution.stroke_width(2)));
    chart
        .draw_series([Rectangle::new(
            [(0.0, 0.0), (0.0, 0.0)],
            RGBColor(255, 215, 80).mix(0.25).filled(),
        )])?
        .label("emitters")
        .legend(|(x, y)| {
            Rectangle::new(
                [(x, y - 6), (x + 22, y + 6)],
                RGBColor(255, 215, 80).mix(0.5).filled(),
            )
        });
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colormap::inferno;
    use flatland_geom::Kernel;
    use flatland_solve::{SolveParams, never};

    /// The exact solve of fig3 drawn against itself: the picture's size, the colour bar from
    /// the bottom colour to the top one, and both curves of B(s) drawn.
    #[test]
    fn the_lit_scene_has_a_colour_bar_and_both_curves() {
        let kernel = Kernel::new(flatland_geom::bundled::scene("fig3").unwrap());
        let params = SolveParams::default();
        let reference = ExactReference::new(&kernel, 128, &params, &never).unwrap();
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let b = reference.radiosity_on(&mesh, &never).unwrap();
        let png = lit_scene_png(&Picture {
            scene: kernel.scene(),
            label: "fig3",
            kernel: "exact",
            mesh: &mesh,
            b: &b,
            along: &flatland_solve::line_along(&mesh, &b),
            reference: &reference,
            rel_l2_reflected: 0.0,
        })
        .unwrap();
        let image = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), (WIDTH, HEIGHT));
        let at = |x: u32, y: u32| image.get_pixel(x, y).0;
        // The bar: 24 pixels wide, 20 right of the scene's plot, from a fifth of the height
        // over three fifths of it, row k in the colour of 1 − k / (rows − 1), in a frame.
        let (x, y0, rows) = (SCENE_WIDTH - 110 + 32, HEIGHT / 5, HEIGHT * 3 / 5);
        let colour_of_row = |k: u32| inferno(1.0 - f64::from(k) / f64::from(rows - 1));
        for k in 1..rows {
            assert_eq!(at(x, y0 + k), colour_of_row(k), "the bar's row {k}");
        }
        assert_eq!(at(x, y0 + 1), inferno(1.0 - 1.0 / f64::from(rows - 1)));
        assert_eq!(at(x, y0 + rows - 1), inferno(0.0));
        let right =
            |colour: [u8; 3]| (SCENE_WIDTH..WIDTH).any(|x| (0..HEIGHT).any(|y| at(x, y) == colour));
        assert!(right([220, 80, 30]), "the solution's curve");
        assert!(right([0, 0, 0]), "the exact curve");
    }

    /// A relighting's panel: the scene alone, each point light marked in its colour.
    #[test]
    fn a_panel_marks_its_lights() {
        let kernel = Kernel::new(flatland_geom::bundled::scene("fig3").unwrap());
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let b = vec![0.5; mesh.len()];
        let along = vec![[0.5; 3]; mesh.len()];
        let (lo, hi) = kernel.scene().bounds();
        let lights = [PointLight::new((lo + hi) * 0.5, 1.0)];
        let panel = |lights| Panel {
            scene: kernel.scene(),
            caption: "fig3".into(),
            mesh: &mesh,
            b: &b,
            along: &along,
            lights,
            top: 1.0,
        };
        let marked = |png: &[u8]| {
            let image = image::load_from_memory(png).unwrap().to_rgb8();
            assert_eq!(image.dimensions(), (SCENE_WIDTH, HEIGHT));
            image.pixels().any(|p| p.0 == [255, 230, 60])
        };
        assert!(marked(&panel_png(&panel(&lights)).unwrap()));
        assert!(!marked(&panel_png(&panel(&[])).unwrap()));
    }
}
