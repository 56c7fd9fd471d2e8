//! SVG drawings in, lit plans out: floor plans, game levels and diagrams drawn in any vector
//! editor, CAD program or tile-map editor become validated Flatland scenes ([`import`]), a scene
//! becomes a drawing that imports back to the same edges ([`scene_svg`]), and a solved plan
//! becomes a picture of its radiosity, as SVG and PNG ([`lit_svg`]). The SVG is read by usvg,
//! which resolves transforms, units, `use`/`defs`, CSS and shapes; nothing here parses SVG by
//! hand. docs/SVG.md says the same for users, with examples.
//!
//! # Coordinates
//! The plan is in the root's user units (inside its viewBox: a drawing whose viewBox is in
//! millimetres gives millimetres, whatever its `width`), times [`ImportParams::unit`], with y
//! flipped so the plan reads as drawn: a drawing point `(x, y)` is the plan point
//! `(unit·x, −unit·y)`. Curves (arcs, Béziers, circles) become segments no further than
//! [`ImportParams::flatten`] from them. usvg keeps numbers as f32; the importer reads each back
//! as the decimal the drawing wrote, so `7.8` is 7.8, while numbers usvg computes (a rect's far
//! corner, a rotated point) carry f32 rounding (a relative 6e-8).
//!
//! # What becomes what
//! - A **filled** shape (a fill that paints an area) is a solid: its outline, facing out of
//!   the fill (a column, a table, a thick wall). A path's subpaths are one fill under its
//!   `fill-rule`: a wall drawn as an outline with the rooms as holes faces out of the building
//!   and into the rooms. The outline must not cross or touch itself.
//! - A **stroke** without an area fill is a thin wall: two one-sided edges back to back.
//! - Touching solids (tiles) lose the faces they press together, in pairs
//!   ([`Skipped::hidden_faces`]).
//! - A **circle of class `flatland-light`** is a point light at its centre
//!   ([`Drawing::lights`]), not geometry. flatland-geom cannot hold point lights yet:
//!   [`Drawing::into_scene`] refuses a drawing that marks one, saying so.
//! - `text` and `image` elements, and paths drawn by markers or patterns, are skipped and
//!   counted; clip paths, masks, filters and stroke widths change nothing.
//!
//! # Attributes
//! Set on an element or any group above it (the nearest wins); for a `use`, on the `use`, its
//! groups, or the element it refers to (usvg drops what identifies the elements inside a
//! referred group, so attributes set there are not seen).
//!
//! | attribute | values | default |
//! |---|---|---|
//! | `data-flatland-reflectance` | ρ in `[0, 1]` | [`ImportParams::reflectance`] (0.5) |
//! | `data-flatland-emission` | E, finite, ≥ 0 | 0 |
//! | `data-flatland-role` | `surface`, `blocker` (occludes only), `ignore` | `surface` |
//! | `data-flatland-faces` | `out`, `in` (of the fill the shape would paint), `left`, `right` (of the way it is drawn, as seen), `both` | `out` for an area fill, else `both` |
//! | `class="flatland-light"` on a `circle` | marks a point light | |
//! | `data-flatland-power` on such a circle | power, finite, > 0 | 1 |
//!
//! A blocker is one edge per piece, two-sided unless its faces are `left` or `right`.
//!
//! # Messages
//! Errors ([`SvgError`]) and warnings ([`Warning`]) are one line and name the element: its id,
//! or its tag and its position among the elements with that tag (`line[17]`), and its line in
//! the file. A value that is not valid (an attribute out of range, the light class on a
//! rectangle) is an error; geometry that cannot be used (a crossing fill, a zero-size shape, a
//! transform that does not parse) is a warning, and the element is skipped.
//!
//! # Example
//! ```
//! use flatland_svg::{ImportParams, import};
//!
//! // A 4 × 3 room drawn as a stroked rectangle whose walls face in, a strip light just above
//! // its floor and a table (a filled square: its edges face out).
//! let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 4 3">
//!   <rect width="4" height="3" fill="none" stroke="black" data-flatland-faces="in"/>
//!   <line x1="1" y1="2.9" x2="3" y2="2.9" stroke="gold" data-flatland-emission="1"
//!         data-flatland-faces="left"/>
//!   <rect x="1.5" y="1" width="1" height="1" data-flatland-reflectance="0.8"/>
//! </svg>"#;
//! let drawing = import(svg.as_bytes(), &ImportParams::default())?;
//! assert!(drawing.warnings().is_empty());
//! let scene = drawing.into_scene()?;
//! assert_eq!(scene.edges().len(), 4 + 1 + 4);
//! // y is flipped: the room spans y from −3 to 0.
//! assert_eq!(scene.bounds().0, flatland_geom::DVec2::new(0.0, -3.0));
//! // The light is drawn to the right: its left, as seen, is up, into the room.
//! let lamp = scene.edges()[4];
//! assert_eq!((lamp.emission, lamp.normal().y), (1.0, 1.0));
//! # Ok::<(), flatland_svg::SvgError>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod attributes;
mod crossing;
mod drawing;
mod error;
mod faces;
mod import;
mod name;
mod outline;
mod params;
mod render;
mod source;
mod warning;
mod write;

pub use attributes::{ElementRole, Faces, LIGHT_CLASS};
pub use drawing::{Drawing, MarkedLight};
pub use error::SvgError;
pub use import::{import, import_file};
pub use name::ElementName;
pub use params::ImportParams;
pub use warning::{Skipped, Warning, WarningKind};
pub use write::lit::{ColourScale, LitPlan, LitSegment, LitSvg, lit_svg};
pub use write::scene_svg;
