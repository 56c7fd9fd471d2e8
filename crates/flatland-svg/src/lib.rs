//! SVG drawings in, lit plans out.
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
