//! The flatland viewer: watch a learner of a Flatland radiosity kernel at work over the
//! `(s, t)` plot of that kernel, live, and scrub back through the run afterwards. Three learners
//! ([`Learner`]), named as everywhere in the project ([`flatland_methods::Method`]): the
//! light-driven learner (`light`, the default: [`flatland_light::LightFit`], rounds of solving
//! the scene and probing where the most light flows), the visibility network (`visibility`) and
//! the paper's network (`paper`), both supervised growing cell structures trained step by step.
//!
//! An eframe (glow) desktop app on top of [`kernel_fit`]; the library crates never depend on it.
//! Its colours are the project's one colour map and scale rule ([`flatland_pictures::colormap`]),
//! so a plot here looks like the CLI's picture of the same grid.
//!
//! - **Kernel plot**: the exact `ζ(s, t)` as a heatmap (`t`, the receiver, to the right; `s`,
//!   the sender, upwards; linear or log colour scale), the surface edges' boundaries on both
//!   axes, labelled where the labels have room; over it a network's cells re-projected to the
//!   mean `(s, t)` of the samples they won (paper Fig. 3c), sized by `δ_c`, cyan when critical,
//!   ringed when new, the network's edges between cells of one face (the others join cells that
//!   never answer the same ray), and optionally every training sample coloured by its set. The
//!   light-driven learner's cells are its probes: a light blue disc at the probed point's `t`
//!   with the column of `s` it sees (`V = 1`) drawn faintly, ringed when the newest round
//!   placed them. A legend under the plot says what each mark means.
//! - **ζ̃ and |ζ̃ − ζ|** beside it, on the same colour scale (paper Fig. 3d). Hovering any of the
//!   three shows `G`, `V`, `k`, `ζ` and the learned value at the pointer; for the visibility
//!   network also its `Ṽ` and whether the geometry or the cells of that face decide it.
//! - **Moving light** (the biggest panel): the scene relit under its point lights (or one
//!   placed where the free-space walk starts) on a thread of its own ([`relit`]), every
//!   bounce, each time a light moves; on first launch the light wanders along the walk by
//!   itself. By default the later bounces come from the learned transport
//!   (`flatland_transport`, built in the background while the exact re-solve answers; its
//!   blocks of `M₂` appear over the kernel plot as they are built, coloured by rank), else
//!   from the exact re-solve. Drag a light's mark, click the floor to add one, right-click one
//!   to delete it; the title gives the median ms per move and the residual reached or the
//!   transport's own error estimate, the panel's foot its bytes and build time. B is drawn as
//!   a function (linear between element midpoints). An exposure slider and a log or linear
//!   tone scale set how B reads.
//! - **Lit scene**: the radiosity `B` solved with the kernel learned so far colours the scene's
//!   edges, with `B(s)` of it and of the exact kernel and the error of the
//!   solved `B − E` as the learner goes ([`lit`]: for a network solved on the learner's thread
//!   at most every half second and for at most a tenth of its time; the light-driven learner
//!   solves it every round).
//! - **Scene view**: emitters, surfaces, blockers, front sides; the ray `x(s) → y(t)` under the
//!   pointer; the `s` of a hovered surface point marked in the plots. Dragging an end point
//!   changes the scene: the references are recomputed and a network keeps learning from
//!   where it is (`Fit::set_kernel`).
//! - **Curves**: held-out relative L2 of ζ and of the solved `B − E` against steps and rays,
//!   cells and samples; for the light-driven learner, per round, the `B − E` error measured
//!   against the exact solve and the learner's own estimate of it, and its probes.
//! - **Timeline**: every moment the learner published is kept (thinned to every 2^k-th past a
//!   cap, the first and latest always), and a slider shows any of them — kernel plot, cells, lit
//!   scene and curves as they were then; Replay plays the run back at a chosen speed, Live
//!   returns to the running learner ([`timeline`]).
//! - **Controls**: play, pause, step (a round of the light-driven learner), reset, the pace of
//!   growth; the scene (offered by name, a `.ron`/`.json` file or an SVG drawing, typed in or
//!   dropped on the window: [`scenes`]); the learner and every parameter of the networks
//!   (docs/ALGORITHM.md §8) with its valid range; a live parameter ([`kernel_fit::LiveParams`])
//!   reaches the running fit, any other (target, gating, importance, the network's rules, …)
//!   starts a new fit with it. Settings persist; settings saved by an older viewer load with
//!   the learner they ran under its current name. Export saves the window as a PNG and a
//!   network's run as the model file `flatland eval` reads, named after scene, learner and
//!   step.
//!
//! The first launch opens a generated floor plan ([`scenes`]) and learns at a pace tied to wall
//! time rather than as fast as the machine goes. The light-driven learner meets its tolerance
//! on that floor plan in 7 rounds and under 0.2 s, so each round's new probes appear in the
//! order learned over at most 2 s (at least the pace of cells per second asked for) before the
//! next round runs: about 12 s of rounds to watch, the lit scene changing with each. A network
//! grows at the pace of cells per second: on `fig3` the visibility network is exact after
//! 17 000 steps, which a fast machine runs before the window has drawn a useful frame.
//!
//! Training runs on its own thread, which owns the running learner; the UI sends commands
//! and takes published snapshots without ever waiting for the learner. Textures are rebuilt
//! only when the data behind them changes, and what is drawn over the plots is rastered at the
//! plot's size in screen pixels, so a frame costs the same for 24 edges and 3 cells as for
//! 1000 edges and 6400 cells.
//!
//! A learner by its name, as `flatland view --learner` reads it:
//!
//! ```
//! use flatland_viewer::Learner;
//!
//! let learner = Learner::parse("visibility")?;
//! assert_eq!(learner.title(), "visibility network");
//! // A retired name is refused with the one to write now, a method that is not a learner with
//! // the three.
//! assert!(Learner::parse("theta").unwrap_err().to_string().contains("`visibility`"));
//! assert!(Learner::parse("hr").unwrap_err().to_string().contains("light, visibility or paper"));
//! # Ok::<(), flatland_methods::MethodError>(())
//! ```
//!
//! What `flatland view --learner paper` does: a window if there is a display.
//!
//! ```no_run
//! use flatland_viewer::{Learner, Options};
//!
//! if flatland_viewer::display_available() {
//!     flatland_viewer::run_with(Options {
//!         learner: Some(Learner::Paper),
//!         ..Options::default()
//!     })?;
//! }
//! # Ok::<(), flatland_viewer::ViewerError>(())
//! ```

#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod app;
mod background;
mod colormap;
mod learner;
pub mod lit;
mod prefix;
pub mod relit;
pub mod scenes;
mod settings;
#[cfg(test)]
mod test_support;
pub mod timeline;
mod views;
mod worker;

use std::path::PathBuf;

pub use app::{Options, ViewerApp, stop_text};
pub use colormap::{colour, grid_image, samples_image, set_color};
pub use learner::Learner;
pub use prefix::Prefix;
pub use scenes::SceneChoice;
pub use settings::{Settings, with_preset};
pub use timeline::{Moment, Timeline};
pub use worker::{CellMark, Growth, LearnedGrid, Lit, LitState, Progress, Status, World};

/// Why the viewer could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// A scene file does not load.
    #[error("could not open {path}: {source}")]
    Scene {
        /// The file.
        path: PathBuf,
        /// Why.
        source: flatland_geom::GeomError,
    },
    /// An SVG drawing does not import.
    #[error("could not open {path}: {source}")]
    Drawing {
        /// The file.
        path: PathBuf,
        /// Why (boxed: the importer's error is large, and rare).
        source: Box<flatland_svg::SvgError>,
    },
    /// The window could not be opened (no display, no OpenGL, …).
    #[error("could not open the viewer window: {0}")]
    Window(String),
}

/// Whether a window can be opened here: on Linux and the BSDs an X11 display must be named by
/// `DISPLAY` (the viewer is built for X11; XWayland provides one under Wayland). Elsewhere a
/// desktop is assumed.
#[must_use]
pub fn display_available() -> bool {
    if cfg!(any(
        target_os = "linux",
        target_os = "freebsd",
        target_os = "openbsd",
        target_os = "netbsd"
    )) {
        std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty())
    } else {
        true
    }
}

/// The global rayon pool, which the learner uses for resampling and reference grids: all cores,
/// at the lowest priority (the UI never uses it), so the window keeps its frames and the learner
/// gets every core the window leaves. Ignored when the global pool already exists.
fn background_learner_pool() {
    let _ = rayon::ThreadPoolBuilder::new()
        .start_handler(|_| {
            background::Priority::Background.apply_to_this_thread();
        })
        .build_global();
}

/// Opens the viewer on `scene` (a `.ron`/`.json` file, an `.svg` drawing, or a scene it offers
/// by name: [`scenes::named`]), or on the scene remembered from the last run, else the
/// generated floor plan, learning at once. Returns when the window is closed.
pub fn run(scene: Option<PathBuf>) -> Result<(), ViewerError> {
    run_with(Options {
        scene,
        ..Options::default()
    })
}

/// [`run`] with all options (start paused, the learner, target cells, pace, fresh settings,
/// frame-rate log, export folder).
pub fn run_with(options: Options) -> Result<(), ViewerError> {
    if let Some(path) = &options.scene
        && let SceneChoice::File(file) = scenes::choice_for(path)
    {
        // Refuse a bad file before a window opens.
        scenes::open_file(&file)?;
    }
    background_learner_pool();
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("flatland — SGCS learning the radiosity kernel")
            .with_inner_size([1280.0, 800.0])
            .with_min_inner_size([900.0, 600.0]),
        renderer: eframe::Renderer::Glow,
        // Dithering costs shader work per pixel, which Mesa's software rasterizer pays on the CPU.
        dithering: false,
        // Frames are paced by the app (≤ 60/s while training, on demand otherwise). With vsync,
        // a frame that misses a (software) vblank waits for the next one: measured under Xvfb,
        // 14–20 frames/s with vsync against 2–3× that without.
        glow_options: eframe::egui_glow::GlowConfiguration {
            vsync: false,
            ..Default::default()
        },
        ..Default::default()
    };
    eframe::run_native(
        "flatland-viewer",
        native,
        Box::new(move |cc| Ok(Box::new(ViewerApp::new(cc, &options)))),
    )
    .map_err(|e| ViewerError::Window(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_can_cross_threads_and_into_anyhow() {
        fn check<T: std::error::Error + Send + Sync + 'static>() {}
        check::<ViewerError>();
    }

    #[test]
    fn a_bad_scene_path_is_refused_before_a_window_opens() {
        let err = run(Some(PathBuf::from("/nonexistent/scene.ron"))).unwrap_err();
        assert!(matches!(err, ViewerError::Scene { .. }), "{err}");
        assert!(err.to_string().contains("/nonexistent/scene.ron"), "{err}");
        let err = run(Some(PathBuf::from("/nonexistent/plan.svg"))).unwrap_err();
        assert!(matches!(err, ViewerError::Drawing { .. }), "{err}");
        assert!(err.to_string().contains("/nonexistent/plan.svg"), "{err}");
    }
}
