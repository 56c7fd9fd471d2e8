//! What an import left out or found odd: [`Warning`]s naming the element, and the
//! [`Skipped`] counts.

use std::fmt;

use glam::DVec2;

use crate::ElementName;

/// Something the import did not take as drawn. The scene is still valid; the caller shows these
/// (each is one line).
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// The element, or `None` for the drawing as a whole.
    pub element: Option<ElementName>,
    /// What happened.
    pub kind: WarningKind,
}

/// What a [`Warning`] says.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum WarningKind {
    /// A shape that usvg did not draw: hidden (`display: none`), zero size, numbers it could
    /// not read, or neither fill nor stroke. Skipped.
    NotDrawn,
    /// A shape usvg keeps but does not show: `visibility: hidden`, or neither fill nor stroke.
    /// Skipped.
    Hidden,
    /// A `text` element. Skipped: text is not geometry.
    Text,
    /// An `image` element. Skipped: a raster is not geometry.
    Image,
    /// A filled shape whose outline crosses or touches itself near `at` (plan coordinates), so
    /// its pieces have no single outside. Skipped.
    Crosses {
        /// Where (plan coordinates).
        at: DVec2,
    },
    /// A filled shape (or one with `data-flatland-faces` out or in) that encloses no area, or
    /// an outline that merges to a point. Skipped.
    Degenerate,
    /// Coordinates that are not finite after the element's transforms. Skipped.
    NonFinite,
    /// Subpaths of a fill left out: `flat` enclose no area, `inside` lie inside the fill
    /// (a loop within a loop of the same direction under the nonzero rule).
    LoopsLeftOut {
        /// Subpaths with no area.
        flat: usize,
        /// Subpaths with the fill on both sides.
        inside: usize,
    },
    /// Zero-length pieces merged into their neighbours.
    Merged {
        /// How many.
        pieces: usize,
    },
    /// Surface edges of this element lie on top of edges of `other`, facing the same way, so
    /// that stretch is counted twice.
    Overlaps {
        /// The other element (may be the same one).
        other: ElementName,
    },
    /// Paths drawn by markers or patterns, which have no element of their own. Skipped.
    Unsourced {
        /// How many.
        paths: usize,
    },
    /// Nothing emits and no light is marked: the plan would be dark.
    NothingLights,
    /// A `transform` that does not parse, or is not finite and invertible: the SVG reader
    /// ignores the first kind and flattens with the second, so the element and what it holds
    /// may be misplaced.
    BadTransform {
        /// The attribute's text.
        value: String,
    },
    /// A `use` whose `href` names no element of the drawing: it draws nothing.
    BrokenReference {
        /// The `href`.
        href: String,
    },
    /// An id an earlier element already has: references and messages mean the first.
    DuplicateId,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(element) = &self.element {
            write!(f, "{element}: ")?;
        }
        match &self.kind {
            WarningKind::NotDrawn => write!(
                f,
                "not drawn (display: none, zero size, numbers that do not parse, or neither fill nor stroke); skipped"
            ),
            WarningKind::Hidden => write!(
                f,
                "not visible (visibility: hidden, or neither fill nor stroke); skipped"
            ),
            WarningKind::Text => write!(f, "text is not geometry; skipped"),
            WarningKind::Image => write!(f, "an image is not geometry; skipped"),
            WarningKind::Crosses { at } => write!(
                f,
                "its fill's outline crosses or touches itself near ({:.6}, {:.6}); skipped (a filled shape needs outlines that do not meet, or mark it data-flatland-faces=\"both\" to make thin walls of it)",
                at.x, at.y
            ),
            WarningKind::Degenerate => {
                write!(f, "encloses no area or has no length; skipped")
            }
            WarningKind::NonFinite => write!(
                f,
                "coordinates are not finite numbers after its transforms; skipped"
            ),
            WarningKind::LoopsLeftOut { flat, inside } => write!(
                f,
                "{flat} subpath(s) with no area and {inside} lying inside the fill left out"
            ),
            WarningKind::Merged { pieces } => {
                write!(
                    f,
                    "{pieces} zero-length piece(s) merged into their neighbours"
                )
            }
            WarningKind::Overlaps { other } => write!(
                f,
                "surfaces lie on top of surfaces of {other}, facing the same way; that stretch reflects and emits twice"
            ),
            WarningKind::Unsourced { paths } => write!(
                f,
                "{paths} path(s) drawn by markers or patterns skipped (they have no element of their own)"
            ),
            WarningKind::BadTransform { value } => write!(
                f,
                "transform={value:?} does not parse, or is not finite and invertible; this element may be misplaced or flattened"
            ),
            WarningKind::BrokenReference { href } => {
                write!(f, "href={href:?} names no element; it draws nothing")
            }
            WarningKind::DuplicateId => write!(
                f,
                "an earlier element has the same id; references and messages mean that one"
            ),
            WarningKind::NothingLights => write!(
                f,
                "nothing emits: mark an element data-flatland-emission=\"E\" (E > 0) or the plan stays dark"
            ),
        }
    }
}

/// How many elements an import skipped, by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Skipped {
    /// `text` elements.
    pub texts: usize,
    /// `image` elements.
    pub images: usize,
    /// Shapes usvg did not draw.
    pub not_drawn: usize,
    /// Shapes not visible (`visibility: hidden`, or neither fill nor stroke).
    pub hidden: usize,
    /// Shapes marked (or inside a group marked) `data-flatland-role="ignore"`.
    pub ignored: usize,
    /// Shapes whose geometry could not be used (crossing fills, no area, not finite).
    pub invalid: usize,
    /// Paths drawn by markers or patterns.
    pub unsourced: usize,
    /// Faces of touching filled shapes that face into each other (each inside the other's
    /// fill, never lit), removed in pairs: the tiles of a tile map become one solid.
    pub hidden_faces: usize,
}

impl fmt::Display for Skipped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts = [
            (self.texts, "text"),
            (self.images, "image"),
            (self.not_drawn, "not drawn"),
            (self.hidden, "hidden"),
            (self.ignored, "ignored"),
            (self.invalid, "invalid"),
            (self.unsourced, "marker or pattern"),
            (self.hidden_faces, "hidden face"),
        ];
        let listed: Vec<String> = parts
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| format!("{n} {what}"))
            .collect();
        if listed.is_empty() {
            write!(f, "nothing skipped")
        } else {
            write!(f, "skipped: {}", listed.join(", "))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skipped_lists_only_what_was_skipped() {
        assert_eq!(Skipped::default().to_string(), "nothing skipped");
        let skipped = Skipped {
            texts: 2,
            hidden_faces: 6,
            ..Skipped::default()
        };
        assert_eq!(skipped.to_string(), "skipped: 2 text, 6 hidden face");
    }

    #[test]
    fn a_warning_names_its_element_first() {
        let element = ElementName {
            tag: "polygon".into(),
            id: Some("bow".into()),
            nth: 1,
            line: 3,
        };
        let warning = Warning {
            element: Some(element),
            kind: WarningKind::Crosses {
                at: DVec2::new(1.5, -2.0),
            },
        };
        let text = warning.to_string();
        assert!(
            text.starts_with("polygon#bow (line 3): its fill's outline crosses"),
            "{text}"
        );
        assert!(text.contains("(1.500000, -2.000000)"));
        let drawing = Warning {
            element: None,
            kind: WarningKind::NothingLights,
        };
        assert!(drawing.to_string().starts_with("nothing emits"));
    }
}
