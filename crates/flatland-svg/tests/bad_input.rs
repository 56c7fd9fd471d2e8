//! Malformed and odd drawings: each gives a one-line error or a warning naming the element,
//! never a panic. The property test at the bottom throws mutated drawings at the importer.

use flatland_svg::{ImportParams, SvgError, WarningKind, import};
use proptest::prelude::*;

/// A lit room the bad element is dropped into, so the rest of the drawing still imports.
fn in_room(element: &str) -> String {
    format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" viewBox="0 0 100 100">
<rect id="room" x="1" y="1" width="98" height="98" fill="none" stroke="black" data-flatland-faces="in" data-flatland-emission="1"/>
{element}
</svg>"##
    )
}

/// What a case must give: an error, or a warning, whose one-line message holds `text`.
enum Expect {
    Error(&'static str),
    Warning(&'static str),
}

fn check(case: &str, svg: &str, expect: &Expect) {
    let result = import(svg.as_bytes(), &ImportParams::default());
    match (expect, result) {
        (Expect::Error(text), Err(err)) => {
            let message = err.to_string();
            assert!(!message.contains('\n'), "{case}: two lines: {message}");
            assert!(message.contains(text), "{case}: {message:?} lacks {text:?}");
        }
        (Expect::Warning(text), Ok(drawing)) => {
            let warnings: Vec<String> =
                drawing.warnings().iter().map(ToString::to_string).collect();
            assert!(
                warnings.iter().all(|w| !w.contains('\n')),
                "{case}: {warnings:?}"
            );
            assert!(
                warnings.iter().any(|w| w.contains(text)),
                "{case}: no warning holds {text:?}: {warnings:?}"
            );
        }
        (_, Err(err)) => panic!("{case}: unexpected error {err}"),
        (_, Ok(drawing)) => panic!("{case}: imported, warnings {:?}", drawing.warnings()),
    }
}

#[test]
fn broken_documents_are_one_line_errors_with_a_position() {
    use Expect::Error;
    let cases: &[(&str, &str, Expect)] = &[
        ("empty", "", Error("not well-formed XML")),
        (
            "truncated",
            r#"<svg xmlns="http://www.w3.org/2000/svg"><rect x="0" y="0" wid"#,
            Error("1:"),
        ),
        (
            "unclosed",
            "<svg xmlns=\"http://www.w3.org/2000/svg\">\n<g>\n</svg>",
            Error("3:"),
        ),
        ("binary", "\u{0}\u{1}garbage", Error("not well-formed XML")),
        // Found by the fuzz target: roxmltree quotes the line break it met.
        (
            "line break quoted",
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><rect/\n></svg>",
            Error("1:47: not well-formed XML: expected '>' not '\\n'"),
        ),
        (
            "line break in an id",
            &in_room(
                r#"<rect id="two&#10;lines" width="5" height="5" data-flatland-reflectance="7"/>"#,
            ),
            Error("rect#two\\nlines (line 3): data-flatland-reflectance"),
        ),
        (
            "not svg",
            "<html><body/></html>",
            Error("not an SVG drawing"),
        ),
        (
            "negative size",
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="-10" height="5"/>"#,
            Error(""),
        ),
        (
            "empty svg",
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"/>"#,
            Error("the drawing has no surface"),
        ),
        (
            "only defs",
            r#"<svg xmlns="http://www.w3.org/2000/svg"><defs><rect width="5" height="5"/></defs></svg>"#,
            Error("no surface"),
        ),
        (
            "only blockers",
            r#"<svg xmlns="http://www.w3.org/2000/svg"><line x2="5" stroke="black" data-flatland-role="blocker"/></svg>"#,
            Error("the drawing has no surface: 1 blocker edges imported"),
        ),
        (
            "only text",
            r#"<svg xmlns="http://www.w3.org/2000/svg"><text>plan</text></svg>"#,
            Error("skipped: 1 text"),
        ),
        (
            "entity bomb",
            "<!DOCTYPE svg [<!ENTITY a \"aaaaaaaaaa\"><!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;\"><!ENTITY c \"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\"><!ENTITY d \"&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;\"><!ENTITY e \"&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;\"><!ENTITY f \"&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;\"><!ENTITY g \"&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;\">]><svg xmlns=\"http://www.w3.org/2000/svg\"><text>&g;</text></svg>",
            Error(""),
        ),
        (
            "bad reflectance",
            &in_room(r#"<rect id="r" width="5" height="5" data-flatland-reflectance="2"/>"#),
            Error("rect#r (line 3): data-flatland-reflectance must be a number in [0, 1]"),
        ),
        (
            "bad emission",
            &in_room(
                r#"<g id="lamps" data-flatland-emission="-1"><rect width="5" height="5"/></g>"#,
            ),
            Error("g#lamps (line 3): data-flatland-emission must be a finite number >= 0"),
        ),
        (
            "nan emission",
            &in_room(r#"<rect width="5" height="5" data-flatland-emission="NaN"/>"#),
            Error("rect[2] (line 3): data-flatland-emission"),
        ),
        (
            "bad role",
            &in_room(r#"<path id="p" d="M0 0H5" data-flatland-role="wall"/>"#),
            Error("must be surface, blocker or ignore"),
        ),
        (
            "bad faces",
            &in_room(r#"<path id="p" d="M0 0H5" data-flatland-faces="up"/>"#),
            Error("must be out, in, left, right or both"),
        ),
        (
            "light on a rect",
            &in_room(r#"<rect id="lamp" class="flatland-light" width="1" height="1"/>"#),
            Error("rect#lamp (line 3): class \"flatland-light\" marks point lights"),
        ),
        (
            "bad power",
            &in_room(
                r#"<circle id="lamp" class="flatland-light" r="1" data-flatland-power="-3"/>"#,
            ),
            Error("data-flatland-power must be a finite number > 0"),
        ),
        (
            "power without light",
            &in_room(r#"<circle id="c" r="1" data-flatland-power="3"/>"#),
            Error("only a circle of class"),
        ),
    ];
    for (case, svg, expect) in cases {
        check(case, svg, expect);
    }
}

#[test]
fn odd_elements_are_warnings_naming_them() {
    use Expect::Warning;
    let cases: &[(&str, &str, Expect)] = &[
        (
            "non-number width",
            r#"<rect id="r" width="abc" height="10"/>"#,
            Warning("rect#r (line 3): not drawn"),
        ),
        (
            "zero width",
            r#"<rect id="r" width="0" height="10"/>"#,
            Warning("rect#r (line 3): not drawn"),
        ),
        (
            "negative radius",
            r#"<circle id="c" r="-5"/>"#,
            Warning("circle#c (line 3): not drawn"),
        ),
        (
            "zero radius",
            "<circle r=\"0\"/>",
            Warning("circle[1] (line 3): not drawn"),
        ),
        (
            "empty path",
            r#"<path id="p" d=""/>"#,
            Warning("path#p (line 3): not drawn"),
        ),
        (
            "path of one point",
            r#"<path id="p" d="M 5 5"/>"#,
            Warning("path#p (line 3): not drawn"),
        ),
        (
            "path cut short",
            r#"<path id="p" d="M 5 5 L"/>"#,
            Warning("path#p (line 3): not drawn"),
        ),
        (
            "path with words",
            r#"<path id="p" d="M 5 5 L ten 4"/>"#,
            Warning("path#p (line 3): not drawn"),
        ),
        (
            "path with NaN",
            r#"<path id="p" d="M 5 5 L NaN 4" stroke="black"/>"#,
            Warning("path#p (line 3): not drawn"),
        ),
        (
            "huge coordinate",
            r#"<path id="p" d="M 5 5 L 1e39 4" stroke="black"/>"#,
            Warning("path#p (line 3): "),
        ),
        (
            "zero-length line",
            r#"<line id="l" x1="3" y1="3" x2="3" y2="3" stroke="black"/>"#,
            Warning("line#l (line 3): "),
        ),
        (
            "zero-length pieces",
            r#"<polyline id="pl" points="10,10 10,10 20,10 20,10 20,20" fill="none" stroke="black"/>"#,
            Warning("polyline#pl (line 3): 2 zero-length piece(s) merged"),
        ),
        (
            "collinear fill",
            r#"<polygon id="flat" points="10,10 20,10 30,10"/>"#,
            Warning("polygon#flat (line 3): encloses no area"),
        ),
        (
            "bow tie",
            r#"<polygon id="bow" points="10,10 20,20 20,10 10,20"/>"#,
            Warning(
                "polygon#bow (line 3): its fill's outline crosses or touches itself near (15.000000, -15.000000)",
            ),
        ),
        (
            "pinched fill",
            r#"<path id="pinch" d="M10 10 H30 V30 L20 10 L10 30 Z"/>"#,
            Warning(
                "path#pinch (line 3): its fill's outline crosses or touches itself near (20.000000, -10.000000)",
            ),
        ),
        (
            "hole touching outline",
            r#"<path id="ring" fill-rule="evenodd" d="M10 10 H30 V30 H10 Z M10 10 L20 15 L15 20 Z"/>"#,
            Warning("path#ring (line 3): its fill's outline crosses or touches"),
        ),
        (
            "loop inside a loop",
            r#"<path id="nested" d="M10 10 H30 V30 H10 Z M15 15 H25 V25 H15 Z"/>"#,
            Warning(
                "path#nested (line 3): 0 subpath(s) with no area and 1 lying inside the fill left out",
            ),
        ),
        (
            "NaN transform",
            r#"<g id="g" transform="scale(NaN)"><rect id="r" width="5" height="5"/></g>"#,
            Warning("g#g (line 3): transform=\"scale(NaN)\" does not parse"),
        ),
        (
            "nested NaN transform",
            r#"<g transform="translate(5)"><g transform="rotate(30)"><g id="deep" transform="matrix(1 0 0 1 NaN 0)"><rect width="5" height="5"/></g></g></g>"#,
            Warning("g#deep (line 3): transform="),
        ),
        (
            "infinite transform",
            r#"<rect id="r" width="5" height="5" transform="scale(1e39)"/>"#,
            Warning("rect#r (line 3): transform=\"scale(1e39)\""),
        ),
        (
            "singular transform",
            r#"<rect id="r" width="5" height="5" transform="matrix(1 1 1 1 0 0)"/>"#,
            Warning("rect#r (line 3): transform="),
        ),
        (
            "zero scale",
            r#"<rect id="r" width="5" height="5" transform="scale(0)"/>"#,
            Warning("rect#r (line 3): transform=\"scale(0)\""),
        ),
        (
            "text",
            r#"<text id="t" x="5" y="5">Kitchen</text>"#,
            Warning("text#t (line 3): text is not geometry; skipped"),
        ),
        (
            "image",
            r#"<image id="i" width="5" height="5" xlink:href="scan.png"/>"#,
            Warning("image#i (line 3): an image is not geometry"),
        ),
        (
            "hidden",
            r#"<rect id="r" width="5" height="5" visibility="hidden"/>"#,
            Warning("rect#r (line 3): not visible"),
        ),
        (
            "display none",
            r#"<rect id="r" width="5" height="5" style="display:none"/>"#,
            Warning("rect#r (line 3): not drawn"),
        ),
        (
            "no paint",
            r#"<rect id="r" width="5" height="5" fill="none"/>"#,
            Warning("rect#r (line 3): not visible"),
        ),
        (
            "overlapping walls",
            "<line id=\"a\" x1=\"10\" y1=\"50\" x2=\"60\" y2=\"50\" stroke=\"black\"/>\n<line id=\"b\" x1=\"30\" y1=\"50\" x2=\"90\" y2=\"50\" stroke=\"black\"/>",
            Warning("line#a (line 3): surfaces lie on top of surfaces of line#b (line 4)"),
        ),
        (
            "wall on the room",
            r#"<line id="dup" x1="1" y1="1" x2="99" y2="1" stroke="black"/>"#,
            Warning("rect#room (line 2): surfaces lie on top of surfaces of line#dup (line 3)"),
        ),
        (
            "broken use",
            r##"<use id="u" xlink:href="#nothing"/>"##,
            Warning("use#u (line 3): href=\"#nothing\" names no element"),
        ),
        (
            "duplicate id",
            "<rect id=\"d\" width=\"5\" height=\"5\"/>\n<rect id=\"d\" x=\"20\" width=\"5\" height=\"5\"/>",
            Warning("rect#d (line 4): an earlier element has the same id"),
        ),
        (
            "marker",
            r##"<defs><marker id="m" markerWidth="4" markerHeight="4"><path d="M0 0L4 2L0 4Z"/></marker></defs><path d="M20 20H60" stroke="black" marker-end="url(#m)"/>"##,
            Warning("path(s) drawn by markers or patterns skipped"),
        ),
    ];
    for (case, element, expect) in cases {
        check(case, &in_room(element), expect);
    }
    let dark = r#"<svg xmlns="http://www.w3.org/2000/svg"><rect width="5" height="5"/></svg>"#;
    check("nothing lights", dark, &Warning("nothing emits"));
}

#[test]
fn odd_but_valid_drawings_import() {
    let recursive = in_room(
        r##"<g id="loop"><use id="u" xlink:href="#loop"/><rect width="5" height="5"/></g>"##,
    );
    assert!(import(recursive.as_bytes(), &ImportParams::default()).is_ok());
    let mut deep = String::new();
    for _ in 0..2000 {
        deep.push_str("<g transform=\"translate(0.001)\">");
    }
    deep.push_str("<rect width=\"5\" height=\"5\"/>");
    for _ in 0..2000 {
        deep.push_str("</g>");
    }
    let result = import(in_room(&deep).as_bytes(), &ImportParams::default());
    // usvg refuses more than 1024 levels; either way, no panic and one line.
    if let Err(err) = result {
        assert!(!err.to_string().contains('\n'), "{err}");
    }
    let far = in_room(r#"<rect width="1e30" height="1e30" x="1e30"/>"#);
    let drawing = import(far.as_bytes(), &ImportParams::default()).unwrap();
    assert!(
        drawing
            .scene()
            .edges()
            .iter()
            .all(|e| e.a.is_finite() && e.b.is_finite())
    );
}

#[test]
fn a_marked_light_becomes_a_point_light_and_one_on_a_wall_is_refused_naming_its_circle() {
    let svg = in_room(
        r#"<g transform="translate(50 50)"><circle id="lamp" class="lamp flatland-light" r="2" cx="10" data-flatland-power="40"/></g>"#,
    );
    let drawing = import(svg.as_bytes(), &ImportParams::default()).unwrap();
    let lights = drawing.lights();
    assert_eq!(lights.len(), 1);
    assert_eq!(lights[0].element.to_string(), "circle#lamp (line 3)");
    assert_eq!(
        (lights[0].at.x, lights[0].at.y, lights[0].power),
        (60.0, -50.0, 40.0)
    );
    // The circle is a light, not a column.
    assert_eq!(drawing.scene().edges().len(), 4);
    let scene = drawing.into_scene().unwrap();
    assert_eq!(scene.lights().len(), 1);
    assert_eq!(
        (
            scene.lights()[0].at.x,
            scene.lights()[0].at.y,
            scene.lights()[0].power
        ),
        (60.0, -50.0, 40.0)
    );
    // A lamp drawn on a wall: the error names the circle and the wall.
    let svg = in_room(r#"<circle id="sconce" class="flatland-light" r="1" cx="1" cy="50"/>"#);
    let drawing = import(svg.as_bytes(), &ImportParams::default()).unwrap();
    let err = drawing.into_scene().unwrap_err();
    assert!(matches!(err, SvgError::Light { .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.starts_with("circle#sconce (line 3): light 0"),
        "{text}"
    );
    assert!(text.contains("edge"), "{text}");
}

#[test]
fn ignored_elements_say_nothing() {
    let svg = in_room(
        r#"<g data-flatland-role="ignore"><rect width="500" height="500"/><text>dims</text></g>"#,
    );
    let drawing = import(svg.as_bytes(), &ImportParams::default()).unwrap();
    assert_eq!(drawing.skipped().ignored, 1);
    let kinds: Vec<&WarningKind> = drawing.warnings().iter().map(|w| &w.kind).collect();
    assert_eq!(kinds, [&WarningKind::Text]);
}

/// Drawings built from pieces that are each odd in some way, spliced at random.
fn pieces() -> Vec<&'static str> {
    vec![
        r#"<rect width="10" height="10"/>"#,
        r#"<rect x="5" y="5" width="0" height="3"/>"#,
        r#"<circle cx="40" cy="40" r="8"/>"#,
        r#"<polygon points="10,10 20,20 20,10 10,20"/>"#,
        r#"<path d="M0 0 C 10 -10 20 10 30 0 S 50 10 60 0 Q 70 -5 80 0 A 5 5 0 1 1 90 0 Z"/>"#,
        r#"<path d="M0 0 L 0 0 L 0 0"/>"#,
        r#"<line x1="0" y1="0" x2="1e30" y2="1" stroke="black"/>"#,
        r#"<g transform="rotate(45) scale(2 0.5)">"#,
        "</g>",
        r#"<g transform="scale(NaN)" data-flatland-emission="2">"#,
        r#"<polyline points="1,1 2,2 1,1" stroke="black" fill="none" data-flatland-faces="left"/>"#,
        r#"<rect width="5" height="5" data-flatland-faces="in" data-flatland-role="blocker"/>"#,
        r#"<text>t</text>"#,
        r##"<use href="#x"/>"##,
        r#"<path id="x" fill-rule="evenodd" d="M0 0H9V9H0Z M1 1H8V8H1Z M2 2H7V7H2Z"/>"#,
        r#"<circle class="flatland-light" r="1"/>"#,
        r#"<rect width="1e-30" height="1e-30"/>"#,
        "<",
        r#"<ellipse rx="3" ry="1e-20"/>"#,
        r#"<svg viewBox="0 0 1 0"><rect width="1" height="1"/></svg>"#,
    ]
}

proptest! {
    // Bounded so that it runs in CI in a few seconds.
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// Whatever is spliced together — and then cut at any byte — the importer answers with a
    /// one-line error, or a valid scene whose warnings are one line each; it never panics.
    #[test]
    fn the_importer_never_panics(picks in prop::collection::vec(0usize..20, 0..12), cut in 0.0f64..1.0, flatten in prop::option::of(1e-4f64..10.0)) {
        let pieces = pieces();
        let body: String = picks.iter().map(|&i| pieces[i]).collect();
        let svg = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 100 100\">{body}</svg>");
        let end = (svg.len() as f64 * (0.5 + cut / 2.0)) as usize;
        let params = ImportParams { flatten, ..ImportParams::default() };
        for text in [&svg[..], &svg[..end]] {
            match import(text.as_bytes(), &params) {
                Ok(drawing) => {
                    let scene = drawing.scene();
                    prop_assert!(scene.edges().iter().all(|e| e.a.is_finite() && e.b.is_finite()));
                    for w in drawing.warnings() {
                        prop_assert!(!w.to_string().contains('\n'));
                    }
                    let _ = drawing.into_scene();
                }
                Err(err) => prop_assert!(!err.to_string().contains('\n'), "{}", err),
            }
        }
    }
}
