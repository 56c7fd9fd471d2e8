//! The bundled scenes of `scenes/`, embedded in the library so every program and test finds them
//! from any folder: the one list of them in the project.

use crate::{GeomError, Scene};

/// Every bundled scene: name, what it shows, its RON text.
pub const SCENES: [(&str, &str, &str); 6] = [
    (
        "fig3",
        "the paper's Fig. 3: a room, a light in the ceiling, a floating blocker (the default)",
        include_str!("../../../scenes/fig3.ron"),
    ),
    (
        "box",
        "a closed square room with a light",
        include_str!("../../../scenes/box.ron"),
    ),
    (
        "maze",
        "a concave room with a notch, partition walls and many floating blockers",
        include_str!("../../../scenes/maze.ron"),
    ),
    (
        "corners",
        "sharp corners, slivers and touching edges",
        include_str!("../../../scenes/corners.ron"),
    ),
    (
        "floorplan",
        "a realistic floor plan: 24 rooms, thick one-sided walls, doors, furniture, two lamps",
        include_str!("../../../scenes/floorplan.ron"),
    ),
    (
        "hall",
        "a realistic hall: 70 solid boxes under two skylights",
        include_str!("../../../scenes/hall.ron"),
    ),
];

/// The default scene's name.
pub const DEFAULT: &str = "fig3";

/// The names of the bundled scenes, in [`SCENES`] order.
pub fn names() -> impl Iterator<Item = &'static str> {
    SCENES.iter().map(|s| s.0)
}

/// The RON text of the bundled scene `name`, if there is one.
pub fn ron(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|s| s.0 == name).map(|s| s.2)
}

/// The bundled scene `name`; an error naming the valid names if there is none.
pub fn scene(name: &str) -> Result<Scene, GeomError> {
    let text = ron(name).ok_or_else(|| GeomError::UnknownBundled {
        name: name.to_owned(),
        valid: names().collect::<Vec<_>>().join(", "),
    })?;
    Scene::from_ron_str(text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::bundled;

    #[test]
    fn every_bundled_scene_loads_and_unknown_names_are_refused_with_the_list() {
        for name in names() {
            let scene = scene(name).unwrap();
            assert!(!scene.surface_edges().is_empty(), "{name}");
        }
        assert!(ron(DEFAULT).is_some());
        let err = scene("nope").unwrap_err().to_string();
        assert!(
            err.contains("nope") && err.contains("fig3, box, maze, corners"),
            "{err}"
        );
    }

    #[test]
    fn bundled_scenes_load() {
        for name in ["fig3", "box", "maze", "corners"] {
            let scene = bundled(name);
            assert!(scene.total_length() > 0.0);
            assert!(scene.max_emission() > 0.0, "{name} has no light");
        }
    }
}
