//! The drawings in `scenes/svg/`, one per producer's style: each imports to the edges its
//! design says, y up, in the right units.

use flatland_geom::{DVec2, EdgeId, Role, Scene};
use flatland_svg::{Drawing, ImportParams, WarningKind, import};
use usvg::roxmltree::Document;

fn fixture(name: &str) -> String {
    let path = format!("{}/../../scenes/svg/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn read(name: &str, params: &ImportParams) -> Drawing {
    import(fixture(name).as_bytes(), params).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The edges that came from the element with this id.
fn edges_of<'a>(drawing: &'a Drawing, id: &str) -> Vec<&'a flatland_geom::Edge> {
    let scene = drawing.scene();
    (0..scene.edges().len())
        .filter(|&i| drawing.element_of(EdgeId::new(i)).id.as_deref() == Some(id))
        .map(|i| &scene.edges()[i])
        .collect()
}

fn kinds(drawing: &Drawing) -> Vec<String> {
    drawing.warnings().iter().map(ToString::to_string).collect()
}

#[test]
fn the_floor_plan_imports_as_drawn_and_lights_with_default_arguments() {
    let drawing = read("floorplan.svg", &ImportParams::default());
    let scene = drawing.scene();
    // Outer wall 4 + 4 (outline and rooms), partition 2 × 4, door leaf 2 (a thin wall), sofa 4,
    // octagonal table 8, bed 4, wardrobe 4, two lamps 4 each; the door swing is ignored.
    assert_eq!(scene.edges().len(), 46);
    // The viewBox is in metres; y flipped.
    assert_eq!(
        scene.bounds(),
        (DVec2::new(0.0, -8.0), DVec2::new(12.0, 0.0))
    );
    assert_eq!(drawing.skipped().texts, 2);
    assert_eq!(drawing.skipped().ignored, 1);
    assert!(
        drawing
            .warnings()
            .iter()
            .all(|w| w.kind == WarningKind::Text),
        "{:?}",
        kinds(&drawing)
    );
    // The rooms' outline faces into the rooms: its bottom edge (y = −7.8) faces up.
    let outer = edges_of(&drawing, "outer-wall");
    assert_eq!(outer.len(), 8);
    let floor = outer
        .iter()
        .find(|e| e.a.y == -7.8 && e.b.y == -7.8)
        .expect("the rooms' south face");
    assert_eq!(floor.normal(), DVec2::new(0.0, 1.0));
    assert_eq!(floor.reflectance, 0.6);
    // The bed, turned 90° about its centre (9, 3.3) → plan (9, −3.3): 1.6 wide, 2 deep.
    let bed = edges_of(&drawing, "bed");
    let lo = bed.iter().fold(DVec2::INFINITY, |m, e| m.min(e.a));
    let hi = bed.iter().fold(DVec2::NEG_INFINITY, |m, e| m.max(e.a));
    flatland_testkit::assert_close!(hi.x - lo.x, 1.6, 1e-6);
    flatland_testkit::assert_close!(hi.y - lo.y, 2.0, 1e-6);
    flatland_testkit::assert_close!((lo + hi).x / 2.0, 9.0, 1e-6);
    flatland_testkit::assert_close!((lo + hi).y / 2.0, -3.3, 1e-6);
    // Furniture faces out of its fill, lamps emit.
    let sofa = edges_of(&drawing, "sofa");
    let centre = sofa.iter().map(|e| e.a).sum::<DVec2>() / 4.0;
    assert!(
        sofa.iter()
            .all(|e| e.normal().dot((e.a + e.b) * 0.5 - centre) > 0.0)
    );
    assert!(
        edges_of(&drawing, "lamp-living")
            .iter()
            .all(|e| e.emission == 5.0)
    );
    assert_eq!(sofa[0].reflectance, 0.5);

    let scene = drawing.into_scene().unwrap();
    let (elements, lit) = solve_default(scene);
    // Every element facing into the flat receives light (the door lets it into the bedroom);
    // the outer wall's outside faces see nothing and stay dark.
    // (Not the stretches of the outer wall the partition stands on: they face into its fill.)
    let partition = |p: DVec2| p.x > 5.92 && p.x < 6.08;
    let indoors = |p: DVec2| p.x > 0.2 && p.x < 11.8 && p.y > -7.8 && p.y < -0.2 && !partition(p);
    let outdoors = |p: DVec2| p.x < 0.0 || p.x > 12.0 || p.y < -8.0 || p.y > 0.0;
    let (mut inside, mut outside) = (0, 0);
    for (element, &b) in elements.iter().zip(&lit) {
        let d = element.b - element.a;
        let ahead = element.midpoint + DVec2::new(-d.y, d.x).normalize() * 1e-3;
        assert!(b.is_finite() && b >= 0.0);
        if indoors(ahead) {
            assert!(b > 0.0, "dark indoors: {element:?}");
            inside += 1;
        } else if outdoors(ahead) {
            assert_eq!(b, 0.0, "lit outdoors: {element:?}");
            outside += 1;
        }
    }
    assert!(inside > 0 && outside > 0);
}

/// The elements of the default mesh and their B, solved with default parameters.
fn solve_default(scene: Scene) -> (Vec<flatland_solve::Element>, Vec<f64>) {
    let kernel = flatland_geom::Kernel::new(scene);
    let mesh = flatland_solve::Mesh::new(
        &kernel,
        flatland_solve::Mesh::default_elements(kernel.scene()),
    )
    .unwrap();
    let params = flatland_solve::SolveParams::default();
    let b = flatland_solve::solve(&kernel, &mesh, &params, &flatland_solve::never)
        .unwrap()
        .radiosity;
    (mesh.elements().to_vec(), b)
}

#[test]
fn the_vector_editor_drawing_resolves_layers_transforms_styles_and_symbols() {
    let drawing = read("inkscape-office.svg", &ImportParams::default());
    let scene = drawing.scene();
    // The page is A5 in millimetres, the walls' layer is translated by (10, 10) and the bay
    // reaches 20 mm right of x = 170.
    let (lo, hi) = scene.bounds();
    flatland_testkit::assert_close!(lo.x, 10.0, 1e-9);
    flatland_testkit::assert_close!(hi.y, -10.0, 1e-9);
    flatland_testkit::assert_close!(lo.y, -138.5, 1e-9);
    flatland_testkit::assert_close!(hi.x, 200.0, 1e-3);
    // Straight pieces: desk 4, three chairs 4 each (from one symbol), lamp 4, and each wall
    // outline 5 plus its arc.
    assert_eq!(edges_of(&drawing, "desk").len(), 4);
    assert_eq!(edges_of(&drawing, "lamp").len(), 4);
    for chair in ["chair-1", "chair-2", "chair-3"] {
        let edges = edges_of(&drawing, chair);
        assert_eq!(edges.len(), 4, "{chair}");
        // The symbol's group sets the reflectance.
        assert!(edges.iter().all(|e| e.reflectance == 0.35), "{chair}");
    }
    assert!(edges_of(&drawing, "lamp").iter().all(|e| e.emission == 4.0));
    // The default tolerance is a thousandth of the page's diagonal; a half circle of radius r
    // needs at least π / (2 acos(1 − tol / r)) chords.
    let tolerance = 1e-3 * 210f64.hypot(148.5);
    let chords = |r: f64, turn: f64| turn / (2.0 * (1.0 - tolerance / r).acos());
    let arcs = edges_of(&drawing, "path-walls").len() - 10;
    let needed = 2.0 * chords(20.0, std::f64::consts::PI);
    assert!(
        (arcs as f64) >= needed && (arcs as f64) < 2.0 * needed + 8.0,
        "{arcs} for {needed}"
    );
    let table = edges_of(&drawing, "round-table");
    let needed = chords(12.0, std::f64::consts::TAU);
    assert!((table.len() as f64) >= needed && (table.len() as f64) < 2.0 * needed + 8.0);
    // The table's centre: (100, 80) in the layer, translated by (10, 10), y flipped.
    let centre = table.iter().map(|e| e.a).sum::<DVec2>() / table.len() as f64;
    flatland_testkit::assert_close!(centre.x, 110.0, 1e-3);
    flatland_testkit::assert_close!(centre.y, -90.0, 1e-3);
    // The plant's curves give a closed outline facing out.
    let plant = edges_of(&drawing, "plant");
    assert!(plant.len() > 6);
    assert_eq!((drawing.skipped().texts, drawing.skipped().images), (1, 1));
    let warnings = kinds(&drawing);
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with("text#text-title (line ")),
        "{warnings:?}"
    );
    assert!(
        warnings.iter().any(|w| w.starts_with("image#scan (line ")),
        "{warnings:?}"
    );
    assert_eq!(warnings.len(), 2, "{warnings:?}");
}

/// The `line` elements of the CAD drawing outside layers marked ignore.
fn cad_lines(text: &str) -> Vec<[f64; 4]> {
    let doc = Document::parse(text).unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("line"))
        .filter(|n| {
            !n.ancestors()
                .any(|a| a.attribute("data-flatland-role") == Some("ignore"))
        })
        .map(|n| ["x1", "y1", "x2", "y2"].map(|k| n.attribute(k).unwrap().parse().unwrap()))
        .collect()
}

#[test]
fn the_cad_export_is_in_millimetres_or_metres_with_y_up() {
    let text = fixture("cad-export.svg");
    let lines = cad_lines(&text);
    for (unit, size) in [(1.0, 12000.0), (1e-3, 12.0)] {
        let drawing = read(
            "cad-export.svg",
            &ImportParams {
                unit,
                ..ImportParams::default()
            },
        );
        let scene = drawing.scene();
        // Every line a thin wall: two one-sided edges back to back.
        assert_eq!(scene.edges().len(), 2 * lines.len());
        let (lo, hi) = scene.bounds();
        assert_eq!((lo.x, hi.x, hi.y), (0.0, size, 0.0));
        flatland_testkit::assert_close!(lo.y, -size * 8.0 / 12.0, 1e-12);
        // The model's y is up already (flipped into SVG by its group): a CAD point (x, y) is at
        // (x, y − 8000) in the plan, so the drawing reads as drawn.
        for (i, [x1, y1, x2, y2]) in lines.iter().enumerate() {
            let e = scene.edges()[2 * i];
            let close = |p: DVec2, q: DVec2| (p - q).length() <= 1e-12 * size;
            assert!(close(e.a, DVec2::new(*x1, y1 - 8000.0) * unit), "{e:?}");
            assert!(close(e.b, DVec2::new(*x2, y2 - 8000.0) * unit), "{e:?}");
            assert_eq!(
                (scene.edges()[2 * i + 1].a, scene.edges()[2 * i + 1].b),
                (e.b, e.a)
            );
        }
        let lights = scene.edges().iter().filter(|e| e.emission == 2.0).count();
        assert_eq!(lights, 2 * 12);
        // The exporter's duplicate face is named with the line it doubles.
        let overlaps: Vec<String> = drawing
            .warnings()
            .iter()
            .filter(|w| matches!(w.kind, WarningKind::Overlaps { .. }))
            .map(ToString::to_string)
            .collect();
        assert_eq!(overlaps.len(), 1, "{overlaps:?}");
        assert!(
            overlaps[0].starts_with("line[1] (line 10): "),
            "{}",
            overlaps[0]
        );
        assert!(
            overlaps[0].contains("line#dup-south-face (line "),
            "{}",
            overlaps[0]
        );
        assert_eq!(drawing.skipped().ignored, 2 + 6);
    }
}

#[test]
fn the_tile_map_becomes_one_solid_of_its_exposed_tile_sides() {
    let text = fixture("tilemap.svg");
    let doc = Document::parse(&text).unwrap();
    let tiles = |layer: &str| -> Vec<(i64, i64)> {
        doc.descendants()
            .find(|n| n.attribute("id") == Some(layer))
            .unwrap()
            .children()
            .filter(|n| n.has_tag_name("rect"))
            .map(|n| {
                let at = |k| n.attribute(k).unwrap().parse::<i64>().unwrap() / 32;
                (at("x"), at("y"))
            })
            .collect()
    };
    let walls: std::collections::HashSet<(i64, i64)> = tiles("Walls").into_iter().collect();
    let neighbours = [(1, 0), (-1, 0), (0, 1), (0, -1)];
    let exposed: usize = walls
        .iter()
        .map(|&(x, y)| {
            neighbours
                .iter()
                .filter(|(dx, dy)| !walls.contains(&(x + dx, y + dy)))
                .count()
        })
        .sum();
    let shared = 4 * walls.len() - exposed;
    let lamps = tiles("Lights").len();
    let drawing = read("tilemap.svg", &ImportParams::default());
    let scene = drawing.scene();
    assert_eq!(scene.edges().len(), exposed + 4 * lamps);
    assert_eq!(drawing.skipped().hidden_faces, shared);
    assert_eq!(drawing.skipped().ignored, tiles("Floor").len());
    assert_eq!(
        scene.bounds(),
        (DVec2::new(0.0, -480.0), DVec2::new(640.0, 0.0))
    );
    assert!(scene.edges().iter().all(|e| e.role == Role::Surface));
    assert!(drawing.warnings().is_empty(), "{:?}", kinds(&drawing));
    // No face lies inside the solid: every wall face has open floor in front of it (or is the
    // map's outer border, facing away from it).
    for e in scene.edges().iter().filter(|e| e.emission == 0.0) {
        let probe = (e.a + e.b) * 0.5 + e.normal() * 16.0;
        let cell = (
            (probe.x / 32.0).floor() as i64,
            (-probe.y / 32.0).floor() as i64,
        );
        assert!(
            !walls.contains(&cell),
            "{e:?} faces into the wall at {cell:?}"
        );
    }
}
