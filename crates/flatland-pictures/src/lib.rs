//! Flatland's pictures. The crate's one job is to *draw*: it turns numbers the crates below it
//! compute (a grid of ζ over `(s, t)`, a solved radiosity on a mesh, a chart's series) into
//! pictures, and does nothing else: it runs no experiment and writes no file. Every renderer
//! returns PNG bytes; the callers (`flatland_lab`, the CLI) write them where they go, and the
//! viewer colours its own textures with the same colour map.
//!
//! - [`colormap`]: the one colour map (inferno) and scale rule (the 99.5th percentile, four log
//!   decades) of every picture, CLI and viewer, so a kernel looks the same wherever it is drawn.
//! - [`plot`]: log–log line charts ([`plot::log_log`]) and heatmaps of a function of `(s, t)`
//!   with axes, edge boundaries and a colour bar ([`plot::heatmap_png`]).
//! - [`lit`]: the scene lit by a solved radiosity beside `B(s)` against the exact solution.
//! - [`plan`]: the lit plan as an SVG drawing (and its PNG), for `solve --out lit.svg`.
//! - [`figure`]: the paper's Fig. 3 panels of a finished fit.
//!
//! Errors are a [`PictureError`]. Text is drawn in a font egui ships, registered once per process,
//! so the same picture has the same pixels on every machine.
//!
//! Conventions as in the crates below: `s` is the sender parameter, `t` the receiver, both in
//! `[0, 1)`; grids are row-major with row `i ↔ s = (i + ½)/R`; pictures show `t` to the right and
//! `s` upwards.
//!
//! ```
//! use flatland_pictures::colormap::{Scale, inferno};
//! use flatland_pictures::plot::{heatmap, heatmap_png};
//!
//! // A 16 × 16 grid of ζ-like values, bright where s and t are both large.
//! let res = 16;
//! let grid: Vec<f64> = (0..res * res).map(|k| ((k / res) * (k % res)) as f64).collect();
//! // The top colour is the 99.5th percentile of the positive values, not their maximum.
//! let scale = Scale::fit(&grid, false);
//! assert_eq!(scale.colour(scale.top), inferno(1.0));
//!
//! let scene = flatland_geom::bundled::scene("fig3")?;
//! let map = heatmap("a title".into(), "ζ", &scene, &grid, false);
//! let png = heatmap_png(&grid, res, &map)?;
//! assert!(png.starts_with(b"\x89PNG"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

pub mod colormap;
mod error;
pub mod figure;
pub mod lit;
pub mod plan;
pub mod plot;

pub use error::PictureError;
