//! SVG bytes → import → scene → SVG → import must never panic.
//!
//! A rejected drawing must give a one-line message; an accepted one a scene with finite
//! coordinates and one-line warnings, which writes to SVG that imports again.

#![no_main]

use flatland_svg::{ImportParams, import, scene_svg};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let drawing = match import(data, &ImportParams::default()) {
        Ok(drawing) => drawing,
        Err(err) => {
            let message = err.to_string();
            assert!(!message.contains('\n'), "multi-line error: {message:?}");
            return;
        }
    };
    for warning in drawing.warnings() {
        let line = warning.to_string();
        assert!(!line.contains('\n'), "multi-line warning: {line:?}");
    }
    let scene = drawing.scene();
    assert!(
        scene.edges().iter().all(|e| e.a.is_finite() && e.b.is_finite()),
        "non-finite edge"
    );
    // Written back, the scene reads again (edges may merge where f32 rounding meets).
    let svg = scene_svg(scene, "fuzz");
    if let Err(err) = import(svg.as_bytes(), &ImportParams::default()) {
        assert!(!err.to_string().contains('\n'));
    }
    let _ = drawing.into_scene();
});
