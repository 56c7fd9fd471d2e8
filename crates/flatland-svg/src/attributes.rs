//! The `data-flatland-*` attributes an element may carry (the crate docs list them), read from
//! one element; inheritance down groups is the importer's.

use usvg::roxmltree::Node;

use crate::{ElementName, SvgError};

/// Which way an imported element's edges face (`data-flatland-faces`). The front of an edge is
/// where it reflects and emits; see the crate docs for the defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Faces {
    /// Away from the region the shape's fill paints (a column, a table, a thick wall).
    Out,
    /// Into the region the shape's fill paints (a room drawn as its floor).
    In,
    /// To the left of the direction the path is drawn in, as the drawing is seen.
    Left,
    /// To the right of the direction the path is drawn in, as the drawing is seen.
    Right,
    /// Both ways: a thin wall, two one-sided edges back to back.
    Both,
}

/// What an element becomes (`data-flatland-role`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementRole {
    /// Surfaces: reflect, emit and occlude.
    Surface,
    /// Blockers: occlude only.
    Blocker,
    /// Nothing (a background, a floor, a dimension line).
    Ignore,
}

/// The class that marks a circle as a point light.
pub const LIGHT_CLASS: &str = "flatland-light";

/// What one element's own `data-flatland-*` attributes say (`None`: not set here).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OwnAttributes {
    /// `data-flatland-reflectance`, in `[0, 1]`.
    pub reflectance: Option<f64>,
    /// `data-flatland-emission`, finite and ≥ 0.
    pub emission: Option<f64>,
    /// `data-flatland-role`.
    pub role: Option<ElementRole>,
    /// `data-flatland-faces`.
    pub faces: Option<Faces>,
    /// The power of a point light: `Some` when the class list holds [`LIGHT_CLASS`]
    /// (`data-flatland-power`, default 1).
    pub light: Option<f64>,
}

/// The attributes an element inherits and overrides, resolved down the tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Reflectance.
    pub reflectance: f64,
    /// Emission.
    pub emission: f64,
    /// Role.
    pub role: ElementRole,
    /// Faces, if any element on the way set it.
    pub faces: Option<Faces>,
}

impl Material {
    /// The material at the root: the default reflectance, no emission, a surface.
    #[must_use]
    pub fn root(reflectance: f64) -> Material {
        Material {
            reflectance,
            emission: 0.0,
            role: ElementRole::Surface,
            faces: None,
        }
    }

    /// This material with what `own` sets.
    #[must_use]
    pub fn with(self, own: &OwnAttributes) -> Material {
        Material {
            reflectance: own.reflectance.unwrap_or(self.reflectance),
            emission: own.emission.unwrap_or(self.emission),
            role: own.role.unwrap_or(self.role),
            faces: own.faces.or(self.faces),
        }
    }
}

/// Reads `node`'s own attributes; a value that is not valid is an error naming the element,
/// the attribute and what would be valid.
pub fn read(node: Node<'_, '_>, name: &ElementName) -> Result<OwnAttributes, SvgError> {
    let bad = |attribute: &'static str, problem: String| SvgError::Attribute {
        element: name.clone(),
        attribute,
        problem,
    };
    let number = |attribute: &'static str, valid: &str, ok: fn(f64) -> bool| {
        node.attribute(attribute)
            .map(|text| match text.trim().parse::<f64>() {
                Ok(v) if ok(v) => Ok(v),
                _ => Err(bad(attribute, format!("must be {valid}, but is {text:?}"))),
            })
            .transpose()
    };
    let reflectance = number("data-flatland-reflectance", "a number in [0, 1]", |v| {
        (0.0..=1.0).contains(&v)
    })?;
    let emission = number("data-flatland-emission", "a finite number >= 0", |v| {
        v.is_finite() && v >= 0.0
    })?;
    let power = number("data-flatland-power", "a finite number > 0", |v| {
        v.is_finite() && v > 0.0
    })?;
    let role = node
        .attribute("data-flatland-role")
        .map(|text| match text.trim() {
            "surface" => Ok(ElementRole::Surface),
            "blocker" => Ok(ElementRole::Blocker),
            "ignore" => Ok(ElementRole::Ignore),
            _ => Err(bad(
                "data-flatland-role",
                format!("must be surface, blocker or ignore, but is {text:?}"),
            )),
        })
        .transpose()?;
    let faces = node
        .attribute("data-flatland-faces")
        .map(|text| match text.trim() {
            "out" => Ok(Faces::Out),
            "in" => Ok(Faces::In),
            "left" => Ok(Faces::Left),
            "right" => Ok(Faces::Right),
            "both" => Ok(Faces::Both),
            _ => Err(bad(
                "data-flatland-faces",
                format!("must be out, in, left, right or both, but is {text:?}"),
            )),
        })
        .transpose()?;
    let marked = node
        .attribute("class")
        .is_some_and(|c| c.split_ascii_whitespace().any(|token| token == LIGHT_CLASS));
    if marked && name.tag != "circle" {
        return Err(bad(
            "class",
            format!("\"{LIGHT_CLASS}\" marks point lights, which must be <circle> elements"),
        ));
    }
    if power.is_some() && !marked {
        return Err(bad(
            "data-flatland-power",
            format!("is a light's power: only a circle of class \"{LIGHT_CLASS}\" takes it"),
        ));
    }
    Ok(OwnAttributes {
        reflectance,
        emission,
        role,
        faces,
        light: marked.then(|| power.unwrap_or(1.0)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_first(svg: &str) -> Result<OwnAttributes, SvgError> {
        let doc = usvg::roxmltree::Document::parse(svg).unwrap();
        let node = doc.root_element().first_element_child().unwrap();
        let name = ElementName {
            tag: node.tag_name().name().to_string(),
            id: node.attribute("id").map(str::to_string),
            nth: 1,
            line: 1,
        };
        read(node, &name)
    }

    #[test]
    fn valid_attributes_are_read() {
        let own = read_first(
            r#"<svg><rect id="r" data-flatland-reflectance="0.8" data-flatland-emission=" 2"
                data-flatland-role="blocker" data-flatland-faces="in"/></svg>"#,
        )
        .unwrap();
        assert_eq!(own.reflectance, Some(0.8));
        assert_eq!(own.emission, Some(2.0));
        assert_eq!(own.role, Some(ElementRole::Blocker));
        assert_eq!(own.faces, Some(Faces::In));
        assert_eq!(own.light, None);
        let lamp =
            read_first(r#"<svg><circle class="a flatland-light" data-flatland-power="3"/></svg>"#)
                .unwrap();
        assert_eq!(lamp.light, Some(3.0));
        let plain = read_first(r#"<svg><circle class="flatland-light"/></svg>"#).unwrap();
        assert_eq!(plain.light, Some(1.0));
    }

    #[test]
    fn invalid_values_name_the_element_the_attribute_and_the_range() {
        let cases = [
            (
                r#"<rect id="r" data-flatland-reflectance="1.5"/>"#,
                "rect#r (line 1): data-flatland-reflectance must be a number in [0, 1], but is \"1.5\"",
            ),
            (
                r#"<rect data-flatland-emission="-1"/>"#,
                "rect[1] (line 1): data-flatland-emission must be a finite number >= 0",
            ),
            (
                r#"<rect data-flatland-emission="NaN"/>"#,
                "data-flatland-emission must be a finite number >= 0",
            ),
            (
                r#"<rect data-flatland-role="wall"/>"#,
                "data-flatland-role must be surface, blocker or ignore",
            ),
            (
                r#"<rect data-flatland-faces="up"/>"#,
                "data-flatland-faces must be out, in, left, right or both",
            ),
            (
                r#"<rect class="flatland-light"/>"#,
                "which must be <circle> elements",
            ),
            (
                r#"<circle data-flatland-power="2"/>"#,
                "only a circle of class",
            ),
            (
                r#"<circle class="flatland-light" data-flatland-power="0"/>"#,
                "must be a finite number > 0",
            ),
        ];
        for (element, expected) in cases {
            let err = read_first(&format!("<svg>{element}</svg>"))
                .unwrap_err()
                .to_string();
            assert!(err.contains(expected), "{err}");
            assert!(!err.contains('\n'));
        }
    }
}
