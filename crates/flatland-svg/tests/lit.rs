//! The lit plan: each element a segment in its colour carrying its B, and the PNG is the SVG
//! rendered.

use flatland_geom::{DVec2, Role};
use flatland_svg::{ColourScale, ImportParams, LitPlan, LitSegment, import, lit_svg};

/// A test colour map: blue through purple to orange, linear up to `top`.
struct Ramp {
    top: f64,
}

impl ColourScale for Ramp {
    fn colour(&self, value: f64) -> [u8; 3] {
        self.bar(value / self.top)
    }
    fn bar(&self, x: f64) -> [u8; 3] {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        [
            (255.0 * x) as u8,
            (64.0 + 96.0 * x) as u8,
            (255.0 * (1.0 - x)) as u8,
        ]
    }
    fn ticks(&self) -> Vec<(f64, String)> {
        vec![
            (0.0, "0".into()),
            (0.5, format!("{:.2}", self.top / 2.0)),
            (1.0, format!("{:.2}", self.top)),
        ]
    }
    fn caption(&self) -> String {
        "B (linear)".into()
    }
}

fn floor_plan() -> (Vec<LitSegment>, Vec<(DVec2, DVec2)>) {
    let path = format!(
        "{}/../../scenes/svg/floorplan.svg",
        env!("CARGO_MANIFEST_DIR")
    );
    let drawing = import(&std::fs::read(path).unwrap(), &ImportParams::default()).unwrap();
    let kernel = flatland_geom::Kernel::new(drawing.into_scene().unwrap());
    let mesh = flatland_solve::Mesh::new(
        &kernel,
        flatland_solve::Mesh::default_elements(kernel.scene()),
    )
    .unwrap();
    let params = flatland_solve::SolveParams::default();
    let b = flatland_solve::solve(&kernel, &mesh, &params, &flatland_solve::never)
        .unwrap()
        .radiosity;
    let segments = mesh
        .elements()
        .iter()
        .zip(&b)
        .map(|(e, &value)| LitSegment {
            edge: e.edge,
            a: e.a,
            b: e.b,
            value,
            along: [value; 3],
            emission: kernel.scene().edge(e.edge).emission,
        })
        .collect();
    let blockers = kernel
        .scene()
        .edges()
        .iter()
        .filter(|e| e.role == Role::Blocker)
        .map(|e| (e.a, e.b))
        .collect();
    (segments, blockers)
}

#[test]
fn each_element_carries_its_b_and_is_drawn_in_its_colour() {
    let (segments, blockers) = floor_plan();
    let top = segments
        .iter()
        .filter(|s| s.emission == 0.0)
        .map(|s| s.value)
        .fold(0.0, f64::max);
    let colours = Ramp { top };
    let picture = lit_svg(&LitPlan {
        title: "Two-room flat: exact solve",
        segments: &segments,
        blockers: &blockers,
        lights: &[],
        colours: &colours,
    });
    let svg = picture.svg();
    // Every element once, in order, with its B exactly.
    let written: Vec<f64> = svg
        .split("data-b=\"")
        .skip(1)
        .map(|rest| rest[..rest.find('"').unwrap()].parse().unwrap())
        .collect();
    let values: Vec<f64> = segments.iter().map(|s| s.value).collect();
    assert_eq!(written, values);
    assert!(svg.contains("<title>Two-room flat: exact solve</title>"));
    assert_eq!(svg.matches("class=\"emitter-mark\"").count(), 8);

    // The PNG is the SVG rendered: decoded, it is pixel for pixel resvg's picture of the text.
    let png = picture.png().unwrap();
    let decoded = resvg::tiny_skia::Pixmap::decode_png(&png).unwrap();
    let mut fonts = usvg::fontdb::Database::new();
    fonts.load_font_data(epaint_default_fonts::UBUNTU_LIGHT.to_vec());
    let options = usvg::Options {
        font_family: "Ubuntu".into(),
        fontdb: std::sync::Arc::new(fonts),
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_str(svg, &options).unwrap();
    let (w, h) = picture.size();
    let mut rendered = resvg::tiny_skia::Pixmap::new(w, h).unwrap();
    resvg::render(&tree, usvg::Transform::identity(), &mut rendered.as_mut());
    assert_eq!((decoded.width(), decoded.height()), (w, h));
    assert!(
        decoded.data() == rendered.data(),
        "the PNG is not the SVG rendered"
    );

    // And it shows the plan in its B colours: at the middle of each long element, on its
    // front side where its stroke lies, the pixel has the element's colour.
    let mut checked = 0;
    for s in segments.iter().filter(|s| s.emission == 0.0) {
        let (pa, pb) = (picture.to_pixel(s.a), picture.to_pixel(s.b));
        if (pb - pa).length() < 12.0 {
            continue;
        }
        let d = (pb - pa).normalize();
        // Front (left of a → b in the plan) is to the right of the on-screen direction.
        let centre = (pa + pb) * 0.5 + DVec2::new(-d.y, d.x) * -2.0;
        let pixel = decoded.pixel(centre.x as u32, centre.y as u32).unwrap();
        let want = colours.colour(s.value);
        let got = [pixel.red(), pixel.green(), pixel.blue()];
        let off = (0..3).map(|c| got[c].abs_diff(want[c])).max().unwrap();
        assert!(
            off <= 2,
            "{s:?}: pixel {got:?} at {centre}, colour {want:?}"
        );
        checked += 1;
    }
    assert!(checked > 50, "{checked} elements checked");
}

#[test]
fn lights_are_marked_and_text_is_escaped() {
    let segments = [LitSegment {
        edge: flatland_geom::EdgeId::new(0),
        a: DVec2::new(0.0, 0.0),
        b: DVec2::new(1.0, 0.0),
        value: 0.5,
        along: [0.5; 3],
        emission: 0.0,
    }];
    let picture = lit_svg(&LitPlan {
        title: "a < b & c",
        segments: &segments,
        blockers: &[(DVec2::new(0.0, 1.0), DVec2::new(1.0, 1.0))],
        lights: &[DVec2::new(0.5, 0.5)],
        colours: &Ramp { top: 1.0 },
    });
    let svg = picture.svg();
    assert!(svg.contains("a &lt; b &amp; c"));
    assert_eq!(svg.matches("class=\"light\"").count(), 1);
    assert_eq!(svg.matches("class=\"blocker\"").count(), 1);
    // The light's marker is where the light is.
    let at = picture.to_pixel(DVec2::new(0.5, 0.5));
    assert!(svg.contains(&format!("translate({} {})", at.x, at.y)));
    assert!(usvg::Tree::from_str(svg, &usvg::Options::default()).is_ok());
    // Nothing to draw still gives a picture.
    let empty = lit_svg(&LitPlan {
        title: "empty",
        segments: &[],
        blockers: &[],
        lights: &[],
        colours: &Ramp { top: 1.0 },
    });
    assert!(empty.png().is_ok());
}

/// A segment whose B runs from 0 to the top is drawn as it runs: dark at its start, bright at
/// its end, the middle between; a segment of one colour writes no gradient.
#[test]
fn a_segment_is_drawn_as_b_runs_along_it() {
    let segment = |a: DVec2, b: DVec2, along: [f64; 3]| LitSegment {
        edge: flatland_geom::EdgeId::new(0),
        a,
        b,
        value: along[1],
        along,
        emission: 0.0,
    };
    let colours = Ramp { top: 1.0 };
    // Horizontal and vertical: a gradient by bounding box would vanish on either.
    let segments = [
        segment(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), [0.0, 0.5, 1.0]),
        segment(DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), [1.0, 0.5, 0.0]),
        segment(DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0), [0.3; 3]),
    ];
    let picture = lit_svg(&LitPlan {
        title: "a ramp",
        segments: &segments,
        blockers: &[],
        lights: &[],
        colours: &colours,
    });
    let svg = picture.svg();
    assert_eq!(
        svg.matches("gradientUnits=\"userSpaceOnUse\"").count(),
        2,
        "{svg}"
    );
    let png = resvg::tiny_skia::Pixmap::decode_png(&picture.png().unwrap()).unwrap();
    for s in &segments {
        let (pa, pb) = (picture.to_pixel(s.a), picture.to_pixel(s.b));
        let d = (pb - pa).normalize();
        for (x, want) in [(0.1, 0.1), (0.5, 0.5), (0.9, 0.9)] {
            let value = if s.along[0] == s.along[2] {
                s.along[0]
            } else {
                s.along[0] + (s.along[2] - s.along[0]) * want
            };
            let at = pa + (pb - pa) * x + DVec2::new(-d.y, d.x) * -2.0;
            let pixel = png.pixel(at.x as u32, at.y as u32).unwrap();
            let got = [pixel.red(), pixel.green(), pixel.blue()];
            let want = colours.colour(value);
            let off = (0..3).map(|c| got[c].abs_diff(want[c])).max().unwrap();
            assert!(off <= 8, "{s:?} at {x}: pixel {got:?}, colour {want:?}");
        }
    }
    // A segment of under three pixels is drawn in its middle colour: no gradient to write.
    let mut with_a_speck = segments.to_vec();
    with_a_speck.push(segment(
        DVec2::new(0.5, 0.5),
        DVec2::new(0.501, 0.5),
        [0.0, 0.5, 1.0],
    ));
    let picture = lit_svg(&LitPlan {
        title: "a ramp and a speck",
        segments: &with_a_speck,
        blockers: &[],
        lights: &[],
        colours: &colours,
    });
    let svg = picture.svg();
    assert_eq!(svg.matches("gradientUnits=\"userSpaceOnUse\"").count(), 2);
    let [r, g, b] = colours.colour(0.5);
    assert!(svg.contains(&format!("stroke=\"#{r:02x}{g:02x}{b:02x}\" stroke-width")));
}
