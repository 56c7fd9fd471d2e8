//! The one error type of this crate.

use std::path::PathBuf;

/// Everything that can go wrong when building, loading or saving a scene or a kernel.
///
/// Messages name the edge or light (by its index in the file, from 0), the rule and the valid range,
/// or the file, line and column of a parse error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GeomError {
    /// A bundled scene name that does not exist.
    #[error("no bundled scene is called \"{name}\"; the bundled scenes are {valid}")]
    UnknownBundled {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// A coordinate or the edge's direction is not a finite number.
    #[error("edge {edge}: {field} must be finite, but is {value}")]
    NonFinite {
        /// Index of the offending edge.
        edge: usize,
        /// Which field (`a.x`, `b.y`, `b - a`, ...).
        field: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The two end points coincide (or are so close that the length underflows).
    #[error(
        "edge {edge}: zero length (a = ({ax}, {ay}), b = ({bx}, {by})); an edge needs two distinct end points"
    )]
    ZeroLength {
        /// Index of the offending edge.
        edge: usize,
        /// `a.x`.
        ax: f64,
        /// `a.y`.
        ay: f64,
        /// `b.x`.
        bx: f64,
        /// `b.y`.
        by: f64,
    },
    /// Reflectance outside `[0, 1]` (or NaN).
    #[error("edge {edge}: reflectance must be in [0, 1], but is {value}")]
    Reflectance {
        /// Index of the offending edge.
        edge: usize,
        /// The offending value.
        value: f64,
    },
    /// Negative or non-finite emission.
    #[error("edge {edge}: emission must be finite and >= 0, but is {value}")]
    Emission {
        /// Index of the offending edge.
        edge: usize,
        /// The offending value.
        value: f64,
    },
    /// A surface marked two-sided: it has one radiosity, which cannot stand for both sides.
    #[error(
        "edge {edge}: a surface cannot be two-sided (one radiosity cannot stand for both of its sides); model a thin wall as a box, or as two one-sided edges back to back (the same end points, swapped); only a blocker may be two-sided"
    )]
    TwoSidedSurface {
        /// Index of the offending edge.
        edge: usize,
    },
    /// A light's position is not a finite number.
    #[error("light {light}: {field} must be finite, but is {value}")]
    LightNonFinite {
        /// Index of the offending light.
        light: usize,
        /// Which field (`at.x` or `at.y`).
        field: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A light's power is negative or not finite.
    #[error("light {light}: power must be finite and >= 0, but is {value}")]
    LightPower {
        /// Index of the offending light.
        light: usize,
        /// The offending value.
        value: f64,
    },
    /// A light lies on an edge (a corner lies on two: the first is named).
    #[error(
        "light {light}: at ({x}, {y}) lies on edge {edge}; a light must be off every edge (move it into the room, even a little)"
    )]
    LightOnEdge {
        /// Index of the offending light.
        light: usize,
        /// Its x.
        x: f64,
        /// Its y.
        y: f64,
        /// The edge it lies on.
        edge: usize,
    },
    /// A walk found no point to start from: none at least `margin` from every edge, inside a
    /// room.
    #[error(
        "the walk found no free point at least {margin} from every edge inside the scene (tried {tries} points across its bounds); a light needs a room wider than twice that margin"
    )]
    NoFreeSpace {
        /// The margin asked for.
        margin: f64,
        /// Points tried.
        tries: usize,
    },
    /// The scene has no edge with role `surface`, so there is nothing to parameterize.
    #[error(
        "scene has no surface edge ({edges} edges given): at least one edge must have role `surface`"
    )]
    NoSurface {
        /// How many edges the scene has.
        edges: usize,
    },
    /// An edge index outside the scene.
    #[error("edge index {index} out of range: the scene has {len} edges (valid 0..{len})")]
    EdgeIndex {
        /// The requested index.
        index: usize,
        /// The number of edges.
        len: usize,
    },
    /// A parameter outside its valid range.
    #[error("{name} must be in {range}, but is {value}")]
    Param {
        /// The parameter's name.
        name: &'static str,
        /// The valid range, e.g. `[0, 1]`.
        range: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The file extension is neither `.ron` nor `.json`.
    #[error("{}: unknown scene format (expected a .ron or .json file name)", path.display())]
    Format {
        /// The file.
        path: PathBuf,
    },
    /// A syntax or schema error, with its position (1-based line and column).
    #[error("{location}{line}:{column}: {message}")]
    Parse {
        /// `"path:"` or empty for in-memory text.
        location: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser said.
        message: String,
    },
    /// A scene file that parsed but is not a valid scene.
    // The cause is part of the message (not a `source`), so `err.chain()` does not repeat it.
    #[error("{}: {error}", path.display())]
    InvalidFile {
        /// The file.
        path: PathBuf,
        /// Why the scene is invalid.
        error: Box<GeomError>,
    },
    /// Reading or writing a file failed.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        error: std::io::Error,
    },
    /// Serializing a scene failed (should not happen for a valid scene).
    #[error("cannot serialize scene: {0}")]
    Serialize(String),
}
