//! The one error type of this crate.

use std::path::PathBuf;

use crate::ElementName;

/// Everything that stops an import, a write or a render. Every message is one line; a problem
/// with one element names it ([`ElementName`]: its id, or its tag and position, and its line).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SvgError {
    /// A parameter outside its valid range.
    #[error("{name} must be in {range}, but is {value}")]
    Param {
        /// The parameter's name.
        name: &'static str,
        /// The valid range.
        range: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The bytes are not UTF-8 text (a compressed `.svgz` must be unpacked first).
    #[error("line {line}: the drawing is not UTF-8 text (an .svgz must be unpacked first)")]
    NotText {
        /// 1-based line of the first invalid byte.
        line: usize,
    },
    /// The text is not well-formed XML.
    #[error("{line}:{column}: not well-formed XML: {message}")]
    Xml {
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
        /// What the XML parser said.
        message: String,
    },
    /// The XML is not an SVG document usvg can read (no `svg` root, an invalid size).
    #[error("not an SVG drawing usvg can read: {0}")]
    NotSvg(String),
    /// An element carries a `data-flatland-*` attribute (or the light marker) that is not valid.
    #[error("{element}: {attribute} {problem}")]
    Attribute {
        /// The element.
        element: ElementName,
        /// The attribute, e.g. `data-flatland-reflectance`.
        attribute: &'static str,
        /// What is wrong and what would be valid.
        problem: String,
    },
    /// Nothing in the drawing became a surface: there is no scene to light.
    #[error(
        "the drawing has no surface: {edges} blocker edges imported ({skipped}); draw walls as filled shapes or strokes not marked data-flatland-role=\"blocker\""
    )]
    NoSurface {
        /// Edges imported (all blockers).
        edges: usize,
        /// What was skipped, in words.
        skipped: String,
    },
    /// A circle marked as a point light that the scene refuses (on a wall, a bad power).
    #[error("{element}: {error}")]
    Light {
        /// The circle.
        element: ElementName,
        /// What the scene said.
        error: Box<flatland_geom::GeomError>,
    },
    /// An imported edge broke a scene rule (should not happen: the importer checks first).
    #[error("{element}: {error}")]
    Edge {
        /// The element the edge came from.
        element: ElementName,
        /// The scene's rule.
        error: Box<flatland_geom::GeomError>,
    },
    /// The imported edges broke a scene rule no one edge is to blame for (should not happen).
    #[error("the imported scene: {error}")]
    Scene {
        /// The scene's rule.
        error: Box<flatland_geom::GeomError>,
    },
    /// Reading or writing a file failed, or one of the errors above in a named file.
    #[error("{}: {error}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        error: Box<SvgError>,
    },
    /// The operating system refused a read or write.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// A picture could not be rendered or encoded.
    #[error("cannot render the picture: {0}")]
    Render(String),
}

impl SvgError {
    /// The same error, prefixed with the file it concerns.
    #[must_use]
    pub fn in_file(self, path: impl Into<PathBuf>) -> SvgError {
        SvgError::File {
            path: path.into(),
            error: Box::new(self),
        }
    }
}
