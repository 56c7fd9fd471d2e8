//! Scene → SVG → scene gives the same edges, in the same order: the bundled scenes and
//! generated floor plans and halls.

use flatland_geom::{Scene, bundled, generate};
use flatland_svg::{ImportParams, WarningKind, import, scene_svg};

/// Imports `scene_svg(scene)` and checks every edge against the original: coordinates within
/// f32 rounding of the scene's size (usvg keeps coordinates as f32), everything else equal.
fn assert_round_trip(name: &str, scene: &Scene) {
    let svg = scene_svg(scene, name);
    let drawing =
        import(svg.as_bytes(), &ImportParams::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (lo, hi) = scene.bounds();
    let tolerance = 2.0 * f64::from(f32::EPSILON) * lo.abs().max(hi.abs()).max_element();
    let back = drawing.scene().edges();
    assert_eq!(back.len(), scene.edges().len(), "{name}: edge count");
    for (i, (e, f)) in scene.edges().iter().zip(back).enumerate() {
        let near = (e.a - f.a).abs().max_element() <= tolerance
            && (e.b - f.b).abs().max_element() <= tolerance;
        assert!(near, "{name}: edge {i} {e:?} came back as {f:?}");
        assert_eq!(
            (e.reflectance, e.emission, e.role, e.two_sided),
            (f.reflectance, f.emission, f.role, f.two_sided),
            "{name}: edge {i}"
        );
    }
    let lights = drawing
        .clone()
        .into_scene()
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(
        lights.lights().len(),
        scene.lights().len(),
        "{name}: lights"
    );
    for (l, m) in scene.lights().iter().zip(lights.lights()) {
        let near = (l.at - m.at).abs().max_element() <= tolerance;
        assert!(
            near && l.power == m.power,
            "{name}: light {l:?} came back as {m:?}"
        );
    }
    let expected = |kind: &WarningKind| match kind {
        WarningKind::NothingLights => !scene.is_lit(),
        WarningKind::Overlaps { .. } => !scene.overlapping_surface_edges().is_empty(),
        _ => false,
    };
    for warning in drawing.warnings() {
        assert!(expected(&warning.kind), "{name}: {warning}");
    }
}

#[test]
fn the_bundled_scenes_come_back() {
    for name in bundled::names() {
        assert_round_trip(name, &bundled::scene(name).unwrap());
    }
}

#[test]
fn generated_plans_and_halls_come_back() {
    for seed in 0..3 {
        assert_round_trip("floor plan", &generate::floor_plan(400, seed).unwrap());
        assert_round_trip("hall", &generate::hall(300, seed).unwrap());
    }
    assert_round_trip("large floor plan", &generate::floor_plan(5000, 7).unwrap());
    // Lit by lamps instead of emitters: the lights come back with their power.
    assert_round_trip("lit plan", &generate::floor_plan_lit(400, 3).unwrap());
    assert_round_trip("lit hall", &generate::hall_lit(300, 4).unwrap());
}

#[test]
fn solids_are_written_as_filled_polygons_and_walls_as_faced_lines() {
    let scene = generate::floor_plan(400, 1).unwrap();
    let svg = scene_svg(&scene, "plan & <co>");
    assert!(svg.contains("<title>plan &amp; &lt;co&gt;</title>"));
    // Furniture boxes are solids; the walls' faces are lines facing left.
    assert!(svg.contains("<polygon points=") && svg.contains("data-flatland-faces=\"left\""));
    let solids = svg
        .lines()
        .filter(|l| l.starts_with("<polygon") && !l.contains("fill=\"none\""))
        .count();
    assert!(solids > 0);
}
