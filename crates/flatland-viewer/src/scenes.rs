//! The scenes the viewer offers by name: the bundled ones, and a floor plan and a hall made by
//! `flatland_geom::generate` (asked for 300 edges, or for any number as `floorplan-1000`,
//! `hall-5000`), and the one it opens first.
//!
//! The first launch opens [`DEFAULT`], the floor plan: on a small scene such as `fig3` the
//! default learner is exact after a few dozen cells, before the window has shown anything
//! worth watching; a floor plan of 220 edges has hundreds of faces where visibility varies,
//! so cells keep appearing where the light flows for as long as the pace lets them.

use std::path::{Path, PathBuf};

use flatland_geom::{Scene, bundled, generate};

use serde::{Deserialize, Serialize};

/// Which scene to open: a bundled one by name or a file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SceneChoice {
    /// One of `flatland_geom::bundled::SCENES`.
    Bundled(String),
    /// A scene file (`.ron` or `.json`).
    File(PathBuf),
}

/// The scene of the first launch (and of a remembered scene that no longer loads).
pub const DEFAULT: &str = "floorplan";

/// Edges asked of the generated scenes (the floor plan comes out with 220): big enough that learning matters, small enough that the
/// reference kernel and the lit scene are ready in a second or two.
const GENERATED_EDGES: usize = 300;
/// Seed of the generated scenes (the same scenes on every machine).
const GENERATED_SEED: u64 = 1;

/// The generated scenes: name, what it shows, how it is made.
type Generated = (
    &'static str,
    &'static str,
    fn() -> Result<Scene, flatland_geom::GeomError>,
);
const GENERATED: [Generated; 2] = [
    (
        "floorplan",
        "a floor plan of 220 edges: rooms, thick walls, doors, furniture, two lamps (the default)",
        || generate::floor_plan(GENERATED_EDGES, GENERATED_SEED),
    ),
    (
        "hall",
        "a hall of 300 edges: crates and shelves under skylights",
        || generate::hall(GENERATED_EDGES, GENERATED_SEED),
    ),
];

/// Every scene by name, with what it shows: the generated ones first, then the bundled.
pub fn offered() -> impl Iterator<Item = (&'static str, &'static str)> {
    GENERATED
        .iter()
        .map(|g| (g.0, g.1))
        .chain(bundled::SCENES.iter().map(|b| (b.0, b.1)))
}

/// The scene named `name`, with its label; an error naming the valid names if there is none.
pub fn named(name: &str) -> Result<(Scene, String), String> {
    let scene = match GENERATED.iter().find(|g| g.0 == name) {
        Some(g) => (g.2)().map_err(|e| e.to_string())?,
        None => match sized(name) {
            Some(made) => made.map_err(|e| e.to_string())?,
            None => bundled::scene(name).map_err(|e| {
                let generated: Vec<&str> = GENERATED.iter().map(|g| g.0).collect();
                format!(
                    "{e} (or {}, or floorplan-N, hall-N for N edges)",
                    generated.join(", ")
                )
            })?,
        },
    };
    Ok((scene, name.to_string()))
}

/// A generated scene of any size by name, `floorplan-1000` or `hall-1000` (`None` for other
/// names; an error for a size `generate` refuses).
fn sized(name: &str) -> Option<Result<Scene, flatland_geom::GeomError>> {
    let (kind, edges) = name.rsplit_once('-')?;
    let edges: usize = edges.parse().ok()?;
    match kind {
        "floorplan" => Some(generate::floor_plan(edges, GENERATED_SEED)),
        "hall" => Some(generate::hall(edges, GENERATED_SEED)),
        _ => None,
    }
}

/// What a command line's scene means: a scene file when it names one (or ends in `.ron` or
/// `.json`), else a scene the viewer offers by that name, else a file (that will not open).
pub fn choice_for(arg: &Path) -> SceneChoice {
    let is_file = arg.exists() || arg.extension().is_some_and(|x| x == "ron" || x == "json");
    match arg.to_str() {
        Some(name) if !is_file && named(name).is_ok() => SceneChoice::Bundled(name.to_owned()),
        _ => SceneChoice::File(arg.to_path_buf()),
    }
}

/// A scene file's label: its file name.
pub fn file_label(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The scene `choice` names, with its label.
pub fn load(choice: &SceneChoice) -> Result<(Scene, String), String> {
    match choice {
        SceneChoice::Bundled(name) => named(name),
        SceneChoice::File(path) => Scene::load(path)
            .map(|s| (s, file_label(path)))
            .map_err(|e| format!("could not open {}: {e}", path.display())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_offered_scene_loads_and_the_default_is_a_floor_plan_where_learning_matters() {
        for (name, about) in offered() {
            let (scene, label) = named(name).unwrap();
            assert_eq!(label, name);
            assert!(!about.is_empty() && !scene.edges().is_empty());
        }
        let (floor, _) = named(DEFAULT).unwrap();
        assert!(floor.edges().len() >= 200, "{}", floor.edges().len());
        assert!(floor.edges().iter().any(|e| e.emission > 0.0), "it is lit");
        let err = named("nowhere").unwrap_err();
        assert!(err.contains("fig3") && err.contains("floorplan"), "{err}");
    }

    #[test]
    fn generated_scenes_of_any_size_are_named_by_their_size() {
        let (big, label) = named("hall-1000").unwrap();
        assert_eq!(label, "hall-1000");
        assert!(big.edges().len() >= 800, "{}", big.edges().len());
        assert!(
            named("floorplan-3").unwrap_err().contains("edges"),
            "too small"
        );
        assert!(named("attic-1000").is_err());
        assert_eq!(
            choice_for(Path::new("floorplan-1000")),
            SceneChoice::Bundled("floorplan-1000".into())
        );
        assert_eq!(
            choice_for(Path::new("fig3.ron")),
            SceneChoice::File("fig3.ron".into())
        );
        assert_eq!(
            choice_for(Path::new("no-such-thing")),
            SceneChoice::File("no-such-thing".into())
        );
    }
}
