//! Log–log line charts as PNG: one line per series, a band from the min to the max over seeds.

use std::path::Path;
use std::sync::Once;

use anyhow::{Context, Result, anyhow};
use plotters::prelude::*;

/// One line: x values with, per x, the mean, min and max of y over repetitions.
pub struct Series {
    /// Legend label.
    pub label: String,
    /// `(x, mean y, min y, max y)`, sorted by x.
    pub points: Vec<(f64, f64, f64, f64)>,
}

const WIDTH: u32 = 900;
const HEIGHT: u32 = 600;
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

pub fn register_font() {
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

/// A tick label with as many digits as its size needs (log axes span decades).
fn tick(v: f64) -> String {
    match v.abs() {
        a if a >= 100.0 => format!("{v:.0}"),
        a if a >= 1.0 => format!("{v:.1}"),
        a if a >= 0.01 => format!("{v:.2}"),
        _ => format!("{v:.0e}"),
    }
}

/// Draws a log–log chart of `series` to a PNG at `path` (atomically).
pub fn log_log(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<()> {
    register_font();
    let finite = |v: f64| v.is_finite() && v > 0.0;
    let xs = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .filter(|v| finite(*v));
    let ys = series
        .iter()
        .flat_map(|s| s.points.iter().flat_map(|p| [p.2, p.3]))
        .filter(|v| finite(*v));
    let range = |it: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = it.fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        if lo.is_finite() && hi > 0.0 {
            Some((lo / 1.3, hi * 1.3))
        } else {
            None
        }
    };
    let (x0, x1) =
        range(&mut xs.into_iter()).ok_or_else(|| anyhow!("no positive x values to plot"))?;
    let (y0, y1) =
        range(&mut ys.into_iter()).ok_or_else(|| anyhow!("no positive y values to plot"))?;

    let mut buffer = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        let err = |e| anyhow!("drawing the plot: {e}");
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_labels(8)
            .y_labels(8)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        for (i, s) in series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let pts: Vec<_> = s
                .points
                .iter()
                .filter(|p| finite(p.0) && finite(p.1))
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
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], color.stroke_width(3))
                });
            chart
                .draw_series(
                    pts.iter()
                        .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
                )
                .map_err(|e| err(e.to_string()))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    write_rgb_png(path, &buffer, WIDTH, HEIGHT)
}

/// Encodes an RGB buffer as PNG and writes it atomically.
pub fn write_rgb_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> Result<()> {
    use image::ImageEncoder as _;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
        .context("encoding the PNG")?;
    flatland_geom::write_atomic(path, &png)?;
    Ok(())
}
