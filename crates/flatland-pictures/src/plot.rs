//! Log–log line charts as PNG: one line per series, a band from the min to the max over seeds.
//! Heatmaps of `(s, t)` are drawn by [`heatmap_png`]; both use the one font of every picture.

use std::sync::Once;

use plotters::coord::combinators::{BindKeyPoints, LogCoord, WithKeyPoints};
use plotters::prelude::*;

use crate::PictureError;

pub use heatmap::{Heatmap, Overlay, heatmap, heatmap_png};

mod heatmap;

/// One line: x values with, per x, the mean, min and max of y over repetitions.
pub struct Series {
    /// Legend label.
    pub label: String,
    /// `(x, mean y, min y, max y)`, sorted by x.
    pub points: Vec<(f64, f64, f64, f64)>,
}

const WIDTH: u32 = 900;
const HEIGHT: u32 = 600;
/// Twelve distinct colours: a scaling plot has two scenes × five methods, and a colour that
/// came round again would make two curves one.
const PALETTE: [RGBColor; 12] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 0),
    RGBColor(174, 199, 232),
];

/// Registers the one font every picture uses (once per process; later calls do nothing).
pub(crate) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // egui's bundled Ubuntu-Light: no system font lookup, the same text on every machine.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// A number with at most three significant digits, trailing zeros trimmed: `0.5`, `20`, `1e-5`.
pub(crate) fn short_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".to_owned();
    }
    if !(1e-3..1e5).contains(&a) {
        let text = format!("{v:.1e}");
        return text.replace(".0e", "e");
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    }
}

/// Labelled (bold) and unlabelled (light) ticks of a log axis over `[lo, hi]`: 1, 2, 5 × 10ᵏ
/// when that gives at least three labels in the range, every 1 … 9 × 10ᵏ when the range is
/// narrower, whole decades (thinned to at most eight) when it is wide.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return (Vec::new(), Vec::new());
    }
    let in_range = |mantissas: &[f64]| -> Vec<f64> {
        let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (k0..=k1)
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let all = in_range(&[1., 2., 3., 4., 5., 6., 7., 8., 9.]);
    let mut bold = in_range(&[1., 2., 5.]);
    if bold.len() > 8 {
        bold = in_range(&[1.]);
        let step = bold.len().div_ceil(8);
        bold = bold.into_iter().step_by(step).collect();
    } else if bold.len() < 3 {
        bold.clone_from(&all);
    }
    if bold.len() < 2 {
        // Less than a factor 2 wide: three evenly spaced labels.
        bold = (0..3)
            .map(|i| lo * (hi / lo).powf(f64::from(i) / 2.0))
            .collect();
    }
    let light = if all.len() <= 60 { all } else { Vec::new() };
    (bold, light)
}

/// Below this a plotted value counts as 0 (an exact model's error is 0 up to rounding).
const ZERO_FLOOR: f64 = 1e-12;

/// Whether `v` has a place on a log axis (values below [`ZERO_FLOOR`] count as 0).
fn positive(v: f64) -> bool {
    v.is_finite() && v > ZERO_FLOOR
}

/// The axes' ranges of a log–log chart of `series`, and its title. A 0 (no ray, an exact
/// model) has no place on a log axis: it is drawn at the axis' lower end, which the title
/// then says.
fn log_axes(title: &str, series: &[Series]) -> ((f64, f64), (f64, f64), String) {
    let range = |values: Vec<f64>| {
        let (lo, hi) = values
            .iter()
            .filter(|v| positive(**v))
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let zeros = values.iter().any(|v| v.is_finite() && !positive(*v));
        match (lo.is_finite(), zeros) {
            (true, false) => (lo / 1.3, hi * 1.3, false),
            (true, true) => (lo / 4.0, hi * 1.3, true),
            (false, _) => (0.5, 2.0, zeros),
        }
    };
    let xs: Vec<f64> = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .collect();
    let ys: Vec<f64> = series
        .iter()
        .flat_map(|s| s.points.iter().flat_map(|p| [p.1, p.2, p.3]))
        .collect();
    let (x0, x1, x_zeros) = range(xs);
    let (y0, y1, y_zeros) = range(ys);
    let title = match (x_zeros, y_zeros) {
        (false, false) => title.to_owned(),
        (true, false) => format!("{title} (0 drawn at the left end)"),
        (false, true) => format!("{title} (0 drawn at the bottom)"),
        (true, true) => format!("{title} (0 drawn at the left end and at the bottom)"),
    };
    ((x0, x1), (y0, y1), title)
}

/// A log–log chart of `series`, PNG-encoded.
pub fn log_log(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<u8>, PictureError> {
    register_font();
    let ((x0, x1), (y0, y1), title) = log_axes(title, series);
    let title = title.as_str();

    let mut buffer = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        let err = PictureError::draw("the plot");
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1))
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| short_number(*v))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        for (i, s) in series.iter().enumerate() {
            draw_one(&mut chart, s, PALETTE[i % PALETTE.len()], (x0, y0))?;
        }
        chart
            .configure_series_labels()
            .position(emptiest_corner(series, (x0, x1), (y0, y1)))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    encode_png(&buffer, WIDTH, HEIGHT)
}

/// A log axis with chosen ticks ([`log_axis`]).
type LogAxis = WithKeyPoints<LogCoord<f64>>;
/// A log–log chart being drawn.
type LogLogChart<'a> = ChartContext<'a, BitMapBackend<'a>, Cartesian2d<LogAxis, LogAxis>>;

/// One series of [`log_log`] in `color`: its min–max bands, its line (with a legend entry) and
/// its points; zeros at the axes' lower ends `(x0, y0)`.
fn draw_one(
    chart: &mut LogLogChart<'_>,
    s: &Series,
    color: RGBColor,
    (x0, y0): (f64, f64),
) -> Result<(), PictureError> {
    let err = PictureError::draw("the plot");
    let at_floor = |v: f64, floor: f64| if positive(v) { v } else { floor * 1.15 };
    let finite = |v: f64| v.is_finite();
    let pts: Vec<_> = s
        .points
        .iter()
        .filter(|p| finite(p.0) && finite(p.1))
        .map(|p| {
            (
                at_floor(p.0, x0),
                at_floor(p.1, y0),
                at_floor(p.2, y0),
                at_floor(p.3, y0),
            )
        })
        .collect();
    for p in &pts {
        if finite(p.2) && finite(p.3) && p.3 > p.2 {
            chart
                .draw_series(LineSeries::new(
                    [(p.0, p.2), (p.0, p.3)],
                    color.stroke_width(2),
                ))
                .map_err(|e| err(e.to_string()))?;
        }
    }
    chart
        .draw_series(LineSeries::new(
            pts.iter().map(|p| (p.0, p.1)),
            color.stroke_width(2),
        ))
        .map_err(|e| err(e.to_string()))?
        .label(s.label.clone())
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(3)));
    chart
        .draw_series(
            pts.iter()
                .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
        )
        .map_err(|e| err(e.to_string()))?;
    Ok(())
}

/// The corner of a log–log chart with the fewest points of `series` near it (where the legend
/// hides the least).
fn emptiest_corner(series: &[Series], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let unit = |v: f64, (lo, hi): (f64, f64)| {
        if v > 0.0 && v.is_finite() {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            0.0
        }
    };
    let points: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter())
        .map(|p| (unit(p.0, x), unit(p.1, y)))
        .collect();
    // (position, x range, y range) of each corner's box, in unit coordinates.
    let corners = [
        (SeriesLabelPosition::UpperRight, (0.6, 1.0), (0.6, 1.0)),
        (SeriesLabelPosition::LowerLeft, (0.0, 0.4), (0.0, 0.4)),
        (SeriesLabelPosition::UpperLeft, (0.0, 0.4), (0.6, 1.0)),
        (SeriesLabelPosition::LowerRight, (0.6, 1.0), (0.0, 0.4)),
    ];
    corners
        .into_iter()
        .min_by_key(|(_, (x0, x1), (y0, y1))| {
            points
                .iter()
                .filter(|(px, py)| (*x0..=*x1).contains(px) && (*y0..=*y1).contains(py))
                .count()
        })
        .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
}

/// A log axis over `[lo, hi]` whose ticks are [`log_ticks`].
fn log_axis(lo: f64, hi: f64) -> LogAxis {
    let (bold, light) = log_ticks(lo, hi);
    (lo..hi)
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

/// Encodes an RGB buffer as PNG.
pub(crate) fn encode_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, PictureError> {
    use image::ImageEncoder as _;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png).write_image(
        rgb,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers_read_well() {
        let cases = [
            (0.0, "0"),
            (0.5, "0.5"),
            (0.25, "0.25"),
            (0.123_456, "0.123"),
            (1.0, "1"),
            (20.0, "20"),
            (400.0, "400"),
            (1234.6, "1235"),
            (1e-5, "1e-5"),
            (2.5e7, "2.5e7"),
            (-0.5, "-0.5"),
        ];
        for (v, text) in cases {
            assert_eq!(short_number(v), text, "{v}");
        }
    }

    #[test]
    fn log_axes_get_at_least_two_labels_whatever_their_width() {
        // The bench's error axis (0.1 … 1.3) once had a single labelled tick.
        for (lo, hi) in [
            (0.1, 1.3),
            (0.2, 0.9),
            (0.31, 0.58),
            (38.0, 1040.0),
            (1e-3, 5e2),
            (1e-12, 1e12),
            (1.5, 1.9),
        ] {
            let (bold, light) = log_ticks(lo, hi);
            assert!(bold.len() >= 2 && bold.len() <= 9, "[{lo}, {hi}]: {bold:?}");
            assert!(bold.iter().all(|v| (lo..=hi).contains(v)), "{bold:?}");
            assert!(light.iter().all(|v| (lo..=hi).contains(v)), "{light:?}");
        }
        assert_eq!(log_ticks(0.1, 1.3).0, vec![0.1, 0.2, 0.5, 1.0]);
    }
}
