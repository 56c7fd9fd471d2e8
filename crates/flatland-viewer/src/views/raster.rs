//! Lines and discs drawn either by egui's painter, which tessellates them again every frame,
//! or into a [`Canvas`] rastered once at the screen's resolution and shown as one texture
//! until what it shows changes ([`EdgesTexture`]). A lit floor plan of a thousand edges is
//! some 10 000 lines with their ticks; tessellated every frame for the software renderer they
//! cost more than every other panel together.

use egui::{Color32, ColorImage, Painter, Pos2, Rect, Stroke, TextureHandle, TextureOptions};

/// Where lines and discs go.
pub(super) trait Pen {
    /// A segment with round caps, `stroke.width` wide (in points).
    fn line(&mut self, a: Pos2, b: Pos2, stroke: Stroke);
    /// A filled disc of radius `r` (in points).
    fn disc(&mut self, c: Pos2, r: f32, fill: Color32);
    /// A circle of radius `r` (in points), `stroke.width` wide.
    fn ring(&mut self, c: Pos2, r: f32, stroke: Stroke);
}

impl Pen for &Painter {
    fn line(&mut self, a: Pos2, b: Pos2, stroke: Stroke) {
        self.line_segment([a, b], stroke);
    }

    fn disc(&mut self, c: Pos2, r: f32, fill: Color32) {
        self.circle_filled(c, r, fill);
    }

    fn ring(&mut self, c: Pos2, r: f32, stroke: Stroke) {
        self.circle_stroke(c, r, stroke);
    }
}

/// A transparent image over a screen rectangle, `ppp` pixels per point, drawn into with
/// anti-aliased coverage (a pixel's share within half a pixel of the shape's edge).
pub(super) struct Canvas {
    image: ColorImage,
    origin: Pos2,
    ppp: f32,
}

impl Canvas {
    /// A clear canvas over `rect` at `ppp` pixels per point.
    pub(super) fn new(rect: Rect, ppp: f32) -> Canvas {
        let size = pixel_size(rect, ppp);
        Canvas {
            image: ColorImage::filled(size, Color32::TRANSPARENT),
            origin: rect.min,
            ppp,
        }
    }

    fn pixel(&self, p: Pos2) -> [f32; 2] {
        [
            (p.x - self.origin.x) * self.ppp,
            (p.y - self.origin.y) * self.ppp,
        ]
    }

    /// Blends `color` into the pixels of the box `lo`–`hi` (in pixels) by `coverage` of
    /// their centres, clamped to 1; pixels it gives nothing are left alone.
    fn cover(
        &mut self,
        lo: [f32; 2],
        hi: [f32; 2],
        color: Color32,
        coverage: impl Fn(f32, f32) -> f32,
    ) {
        let [w, h] = self.image.size;
        let x0 = lo[0].floor().max(0.0) as usize;
        let y0 = lo[1].floor().max(0.0) as usize;
        let x1 = (hi[0].ceil().max(0.0) as usize).min(w);
        let y1 = (hi[1].ceil().max(0.0) as usize).min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let c = coverage(x as f32 + 0.5, y as f32 + 0.5);
                if c > 0.0 {
                    let px = &mut self.image.pixels[y * w + x];
                    *px = blend(*px, color.gamma_multiply(c.min(1.0)));
                }
            }
        }
    }

    /// A segment `width` points wide in opaque colours running from `colours[0]` at `a` to
    /// `colours[1]` at `b`, not anti-aliased: a span across the line per pixel step along its
    /// longer axis (a wall along an axis is an exact rectangle). Some ten thousand of them
    /// cost a millisecond, where the anti-aliased [`Pen::line`] costs ten.
    pub(super) fn span_line(&mut self, a: Pos2, b: Pos2, colours: [Color32; 2], width: f32) {
        let (a, b) = (self.pixel(a), self.pixel(b));
        let [w, h] = self.image.size;
        let d = [b[0] - a[0], b[1] - a[1]];
        // Along the longer axis `major`, across it `minor`.
        let major = usize::from(d[1].abs() > d[0].abs());
        let minor = 1 - major;
        let steps = d[major].abs().ceil().max(1.0) as usize;
        // The span across a line at angle θ to its major axis is width / cos θ.
        let slope = d[minor] / d[major].abs().max(1e-6);
        let half = 0.5 * width * self.ppp * (1.0 + slope * slope).sqrt();
        let limits = [w as isize, h as isize];
        for k in 0..=steps {
            let u = k as f32 / steps as f32;
            let along = (a[major] + u * d[major]).floor() as isize;
            if along < 0 || along >= limits[major] {
                continue;
            }
            let centre = a[minor] + u * d[minor];
            let lo = ((centre - half).round() as isize).max(0);
            let hi = ((centre + half).round() as isize).min(limits[minor]);
            let colour = lerp(colours, u);
            for across in lo..hi {
                let (x, y) = if major == 0 {
                    (along, across)
                } else {
                    (across, along)
                };
                self.image.pixels[y as usize * w + x as usize] = colour;
            }
        }
    }

    /// The image, for a texture.
    pub(super) fn into_image(self) -> ColorImage {
        self.image
    }
}

impl Pen for Canvas {
    fn line(&mut self, a: Pos2, b: Pos2, stroke: Stroke) {
        let (a, b) = (self.pixel(a), self.pixel(b));
        let half = 0.5 * stroke.width * self.ppp;
        let reach = half + 0.5;
        let lo = [a[0].min(b[0]) - reach, a[1].min(b[1]) - reach];
        let hi = [a[0].max(b[0]) + reach, a[1].max(b[1]) + reach];
        let d = [b[0] - a[0], b[1] - a[1]];
        let length2 = d[0] * d[0] + d[1] * d[1];
        self.cover(lo, hi, stroke.color, |x, y| {
            let (px, py) = (x - a[0], y - a[1]);
            let u = if length2 > 0.0 {
                ((px * d[0] + py * d[1]) / length2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (ex, ey) = (px - u * d[0], py - u * d[1]);
            reach - (ex * ex + ey * ey).sqrt()
        });
    }

    fn disc(&mut self, c: Pos2, r: f32, fill: Color32) {
        let c = self.pixel(c);
        let reach = r * self.ppp + 0.5;
        self.cover(
            [c[0] - reach, c[1] - reach],
            [c[0] + reach, c[1] + reach],
            fill,
            |x, y| reach - ((x - c[0]).powi(2) + (y - c[1]).powi(2)).sqrt(),
        );
    }

    fn ring(&mut self, c: Pos2, r: f32, stroke: Stroke) {
        let c = self.pixel(c);
        let (r, half) = (r * self.ppp, 0.5 * stroke.width * self.ppp + 0.5);
        let reach = r + half;
        self.cover(
            [c[0] - reach, c[1] - reach],
            [c[0] + reach, c[1] + reach],
            stroke.color,
            |x, y| half - (((x - c[0]).powi(2) + (y - c[1]).powi(2)).sqrt() - r).abs(),
        );
    }
}

/// The pixels of `rect` at `ppp` pixels per point (at least one each way).
fn pixel_size(rect: Rect, ppp: f32) -> [usize; 2] {
    [
        ((rect.width() * ppp).round() as usize).max(1),
        ((rect.height() * ppp).round() as usize).max(1),
    ]
}

/// The colour `u` of the way from `c[0]` to `c[1]` (component by component).
fn lerp(c: [Color32; 2], u: f32) -> Color32 {
    let mix = |p: u8, q: u8| (f32::from(p) + u * (f32::from(q) - f32::from(p))).round() as u8;
    Color32::from_rgba_premultiplied(
        mix(c[0].r(), c[1].r()),
        mix(c[0].g(), c[1].g()),
        mix(c[0].b(), c[1].b()),
        mix(c[0].a(), c[1].a()),
    )
}

/// `src` over `dst`, both premultiplied.
pub(super) fn blend(dst: Color32, src: Color32) -> Color32 {
    let k = u16::from(255 - src.a());
    let mix = |s: u8, d: u8| s.saturating_add(((u16::from(d) * k + 127) / 255) as u8);
    Color32::from_rgba_premultiplied(
        mix(src.r(), dst.r()),
        mix(src.g(), dst.g()),
        mix(src.b(), dst.b()),
        mix(src.a(), dst.a()),
    )
}

/// A scene's edges rastered for one panel, kept while the same `key` (the scene, its colours,
/// the panel's pixels) is asked for.
#[derive(Default)]
pub struct EdgesTexture {
    cached: Option<([u64; 3], TextureHandle)>,
    /// The lit elements, a layer of their own under the lines: a new B rasters only them.
    lit: Option<([u64; 3], TextureHandle)>,
}

/// A texture kept under its key: the key, and the texture shown.
type Kept = Option<([u64; 3], TextureHandle)>;

impl EdgesTexture {
    /// Paints the lit elements' layer for `key` over `rect` (under what [`EdgesTexture::paint`]
    /// paints after it), rastering it with `draw` first when the key changed.
    pub(super) fn paint_lit(
        &mut self,
        painter: &Painter,
        rect: Rect,
        key: [u64; 2],
        draw: impl FnOnce(&mut Canvas),
    ) {
        paint_kept(&mut self.lit, "lit elements", painter, rect, key, draw);
    }

    /// Paints the texture for `key` over `rect`, rastering it with `draw` first when the key
    /// changed.
    pub(super) fn paint(
        &mut self,
        painter: &Painter,
        rect: Rect,
        key: [u64; 2],
        draw: impl FnOnce(&mut Canvas),
    ) {
        paint_kept(&mut self.cached, "edges", painter, rect, key, draw);
    }
}

/// Paints the texture kept in `kept` for `key` over `rect`, rastered with `draw` first when
/// the key or the panel's pixels changed.
fn paint_kept(
    kept: &mut Kept,
    name: &str,
    painter: &Painter,
    rect: Rect,
    key: [u64; 2],
    draw: impl FnOnce(&mut Canvas),
) {
    let ppp = painter.ctx().pixels_per_point();
    let size = pixel_size(rect, ppp);
    let key = [key[0], key[1], (size[0] as u64) << 32 | size[1] as u64];
    let texture = match kept {
        Some((k, texture)) if *k == key => texture,
        cached => {
            let mut canvas = Canvas::new(rect, ppp);
            draw(&mut canvas);
            let image = canvas.into_image();
            let texture = match cached.take() {
                Some((_, mut texture)) => {
                    texture.set(image, TextureOptions::LINEAR);
                    texture
                }
                None => painter
                    .ctx()
                    .load_texture(name, image, TextureOptions::LINEAR),
            };
            &mut cached.insert((key, texture)).1
        }
    };
    let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
    painter.image(texture.id(), rect, uv, Color32::WHITE);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn canvas() -> Canvas {
        Canvas::new(
            Rect::from_min_size(Pos2::new(10.0, 20.0), egui::vec2(40.0, 30.0)),
            1.0,
        )
    }

    fn alpha(canvas: &Canvas, x: usize, y: usize) -> u8 {
        canvas.image.pixels[y * canvas.image.size[0] + x].a()
    }

    #[test]
    fn a_line_covers_its_width_and_nothing_beyond() {
        let mut c = canvas();
        // Horizontal, 4 points wide, along pixel row 10 of the canvas (y = 30.5 on screen).
        c.line(
            Pos2::new(15.0, 30.5),
            Pos2::new(45.0, 30.5),
            Stroke::new(4.0, Color32::WHITE),
        );
        assert_eq!(alpha(&c, 20, 10), 255, "on the line");
        assert_eq!(alpha(&c, 20, 11), 255, "within half the width");
        // Row 12's centre lies on the rim, 2 pixels off: half covered.
        let rim = alpha(&c, 20, 12);
        assert!((120..=135).contains(&rim), "the rim is blended: {rim}");
        assert_eq!(alpha(&c, 20, 13), 0, "beyond it");
        assert_eq!(alpha(&c, 2, 10), 0, "before its start");
    }

    #[test]
    fn a_disc_and_a_ring_cover_what_they_should() {
        let mut c = canvas();
        c.disc(Pos2::new(20.5, 30.5), 3.0, Color32::RED);
        assert_eq!(alpha(&c, 10, 10), 255, "the centre");
        assert_eq!(alpha(&c, 10, 15), 0, "outside");
        c.ring(Pos2::new(35.5, 35.5), 5.0, Stroke::new(1.0, Color32::WHITE));
        assert_eq!(alpha(&c, 25, 15), 0, "the ring's centre stays clear");
        assert!(alpha(&c, 30, 15) > 200, "on the ring");
    }

    #[test]
    fn the_texture_is_rastered_again_only_when_its_key_or_size_changes() {
        let ctx = egui::Context::default();
        let painter = Painter::new(ctx, egui::LayerId::background(), Rect::EVERYTHING);
        let rect = Rect::from_min_size(Pos2::ZERO, egui::vec2(30.0, 20.0));
        let mut texture = EdgesTexture::default();
        let drawn = std::cell::Cell::new(0);
        let paint = |texture: &mut EdgesTexture, rect: Rect, key: u64| {
            texture.paint(&painter, rect, [key, 0], |c| {
                drawn.set(drawn.get() + 1);
                c.disc(Pos2::new(5.0, 5.0), 2.0, Color32::WHITE);
            });
        };
        paint(&mut texture, rect, 1);
        paint(&mut texture, rect, 1);
        assert_eq!(drawn.get(), 1, "the same key: kept");
        paint(&mut texture, rect, 2);
        assert_eq!(drawn.get(), 2, "a new key: rastered");
        paint(&mut texture, rect.expand(4.0), 2);
        assert_eq!(drawn.get(), 3, "a new size: rastered");
    }

    #[test]
    fn shapes_off_the_canvas_are_clipped() {
        let mut c = canvas();
        c.line(
            Pos2::new(-100.0, -100.0),
            Pos2::new(500.0, 500.0),
            Stroke::new(3.0, Color32::WHITE),
        );
        c.disc(Pos2::new(-50.0, 20.0), 10.0, Color32::WHITE);
        assert!(
            c.image.pixels.iter().any(|p| p.a() > 0),
            "the diagonal crosses it"
        );
    }
}
