//! The file schema of a scene (`RawScene`, `RawEdge`) and serde through validation.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::{Edge, PointLight, Role, Scene};
use crate::GeomError;

impl Scene {
    /// The serializable form.
    pub(crate) fn to_raw(&self) -> RawScene {
        RawScene {
            edges: self.edges.iter().map(RawEdge::from).collect(),
            lights: self.lights.iter().map(RawLight::from).collect(),
        }
    }
}

/// The file schema of a scene, before validation.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    pub edges: Vec<RawEdge>,
    /// Left out when empty, so a scene without lights is written as before lights existed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<RawLight>,
}

/// The file schema of a point light.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLight {
    at: [f64; 2],
    power: f64,
}

impl From<&PointLight> for RawLight {
    fn from(l: &PointLight) -> Self {
        RawLight {
            at: l.at.to_array(),
            power: l.power,
        }
    }
}

/// The file schema of an edge.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEdge {
    a: [f64; 2],
    b: [f64; 2],
    reflectance: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    emission: f64,
    #[serde(default, skip_serializing_if = "is_surface")]
    role: Role,
    #[serde(default, skip_serializing_if = "is_false")]
    two_sided: bool,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
fn is_surface(r: &Role) -> bool {
    *r == Role::Surface
}
fn is_false(b: &bool) -> bool {
    !*b
}

impl From<&Edge> for RawEdge {
    fn from(e: &Edge) -> Self {
        RawEdge {
            a: e.a.to_array(),
            b: e.b.to_array(),
            reflectance: e.reflectance,
            emission: e.emission,
            role: e.role,
            two_sided: e.two_sided,
        }
    }
}

impl TryFrom<RawScene> for Scene {
    type Error = GeomError;
    fn try_from(raw: RawScene) -> Result<Scene, GeomError> {
        Scene::new(
            raw.edges
                .into_iter()
                .map(|e| Edge {
                    a: DVec2::from_array(e.a),
                    b: DVec2::from_array(e.b),
                    reflectance: e.reflectance,
                    emission: e.emission,
                    role: e.role,
                    two_sided: e.two_sided,
                })
                .collect(),
        )?
        .with_lights(
            raw.lights
                .into_iter()
                .map(|l| PointLight::new(DVec2::from_array(l.at), l.power))
                .collect(),
        )
    }
}

impl Serialize for Scene {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_raw().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Scene {
    /// Deserializes through validation: an invalid scene is a deserialization error.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Scene, D::Error> {
        let raw = RawScene::deserialize(deserializer)?;
        Scene::try_from(raw).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_and_ron_round_trip_and_defaults() {
        let text = r#"{"edges":[{"a":[0,0],"b":[1,0],"reflectance":0.5},
            {"a":[1,0],"b":[0,1],"reflectance":0.5,"emission":2},
            {"a":[0,1],"b":[0,0],"reflectance":0.5,"role":"blocker","two_sided":true}]}"#;
        let scene = Scene::from_json_str(text).unwrap();
        assert_eq!(scene.edges()[0].role, Role::Surface);
        assert!(!scene.edges()[1].two_sided && scene.edges()[2].two_sided);
        assert_eq!(scene.edges()[2].role, Role::Blocker);
        let dir = std::env::temp_dir().join(format!("flatland-geom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for ext in ["ron", "json", "RON"] {
            let path = dir.join(format!("scene.{ext}"));
            scene.save(&path).unwrap();
            assert_eq!(Scene::load(&path).unwrap(), scene, "{ext}");
        }
        let json = serde_json::to_string(&scene).unwrap();
        assert_eq!(serde_json::from_str::<Scene>(&json).unwrap(), scene);
        assert_eq!(
            Scene::from_ron_str(&ron::to_string(&scene).unwrap()).unwrap(),
            scene
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn lights_round_trip_and_a_scene_without_them_is_written_as_before() {
        let text = r#"{"edges":[{"a":[0,0],"b":[2,0],"reflectance":0.5},
            {"a":[2,0],"b":[0,2],"reflectance":0.5},{"a":[0,2],"b":[0,0],"reflectance":0.5}],
            "lights":[{"at":[0.5,0.5],"power":2.0},{"at":[0.25,1],"power":0}]}"#;
        let scene = Scene::from_json_str(text).unwrap();
        assert_eq!(
            scene.lights(),
            &[
                PointLight::new(DVec2::new(0.5, 0.5), 2.0),
                PointLight::new(DVec2::new(0.25, 1.0), 0.0)
            ]
        );
        let json = serde_json::to_string(&scene).unwrap();
        assert!(
            json.contains(r#""lights":[{"at":[0.5,0.5],"power":2.0}"#),
            "{json}"
        );
        assert_eq!(Scene::from_json_str(&json).unwrap(), scene);
        let ron = ron::to_string(&scene).unwrap();
        assert!(ron.contains("lights:[(at:(0.5,0.5),power:2.0)"), "{ron}");
        assert_eq!(Scene::from_ron_str(&ron).unwrap(), scene);
        let dir = std::env::temp_dir().join(format!("flatland-geom-lights-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for ext in ["ron", "json"] {
            let path = dir.join(format!("scene.{ext}"));
            scene.save(&path).unwrap();
            assert_eq!(Scene::load(&path).unwrap(), scene, "{ext}");
        }
        // Without lights: no `lights` key at all.
        let dark = Scene::new(scene.edges().to_vec()).unwrap();
        assert!(!serde_json::to_string(&dark).unwrap().contains("lights"));
        assert!(!ron::to_string(&dark).unwrap().contains("lights"));
        // A bad light in a file: the file, then the light and the rule, on one line.
        let path = dir.join("bad.json");
        std::fs::write(&path, text.replace("0.25,1", "0,1")).unwrap();
        let err = Scene::load(&path).unwrap_err().to_string();
        assert!(err.ends_with("bad.json: light 1: at (0, 1) lies on edge 2; a light must be off every edge (move it into the room, even a little)"), "{err}");
        // An unknown field of a light is refused with its line.
        let err = Scene::from_json_str(&text.replace("\"power\":0", "\"watts\":0"))
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("3:") && err.contains("watts"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
