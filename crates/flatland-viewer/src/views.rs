//! Drawing: functions of what they show plus a little interaction state; nothing here trains
//! or waits. The `(s, t)` plots in [`plot`] with the cells' overlay rastered in [`overlay`]
//! and their layers composited into one image in [`layers`],
//! the learned transport's blocks over a plot in [`blocks`],
//! the scene view in [`scene`], the relit scene and its moving lights in [`lamps`], a scene's edges and the lit scene in [`edges`] (their lines
//! rastered once per change in [`raster`]), the learning
//! curves in [`curves`], the small pieces they share in [`widgets`].

mod blocks;
mod curves;
mod edges;
mod lamps;
mod layers;
mod lit_pieces;
mod overlay;
mod plot;
mod raster;
mod scene;
mod widgets;

use egui::Color32;
use flatland_geom::DVec2;

pub use blocks::BlocksTexture;
pub use curves::curves;
pub use edges::LitPaint;
pub use lamps::{LampsOut, RelitFrameView, relit_view};
pub use layers::composite;
pub use overlay::{Marks, NEW_FOR, boundaries_image, overlay_image};
pub use plot::{Overlay, PlotFrame, kernel_plot};
pub use raster::EdgesTexture;
pub use scene::{SceneFrame, moved_scene, scene_view};
pub use widgets::{placeholder, readout_box};

/// Height of a panel's title line.
pub const TITLE_H: f32 = 18.0;

/// A cell (white), a critical cell (cyan), a new cell's ring (lime): colours the inferno map of
/// the heatmaps never uses, so the marks read on any value.
const CELL: Color32 = Color32::from_rgb(245, 245, 245);
const CRITICAL: Color32 = Color32::from_rgb(40, 230, 255);
const NEW_CELL: Color32 = Color32::from_rgb(150, 255, 40);
/// A probe of the light-driven learner.
const FACE_VISIBLE: Color32 = Color32::from_rgb(90, 210, 255);
/// What a probe sees (`V = 1` along its column): faint, so the kernel shows through.
const SEEN: Color32 = Color32::from_rgba_premultiplied(45, 105, 128, 128);
/// The network's edges within a face: faint, so the kernel shows through.
const NET_EDGE: Color32 = Color32::from_rgba_premultiplied(110, 110, 110, 110);
/// The surface edges' boundaries over the plots.
const BOUNDARY: Color32 = Color32::from_rgba_premultiplied(70, 70, 70, 70);
const SCENE_MARK: Color32 = Color32::from_rgb(120, 255, 140);
const EMITTER: Color32 = Color32::from_rgb(255, 210, 60);
const SURFACE: Color32 = Color32::from_rgb(190, 190, 195);
const BLOCKER: Color32 = Color32::from_rgb(235, 80, 70);
/// Blockers in a lit scene: out of the colour map's range, so never read as a radiosity.
const LIT_BLOCKER: Color32 = Color32::from_rgb(110, 150, 210);

/// What the pointer is over, shared between the panels (one frame late for the other panels).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hover {
    /// `(s, t)` under the pointer in one of the plots.
    pub st: Option<[f64; 2]>,
    /// The parameter of the scene point under the pointer.
    pub scene_s: Option<f64>,
}

/// An end point being dragged in the scene view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneDrag {
    /// Where it was.
    pub from: DVec2,
    /// Where it is now.
    pub to: DVec2,
}

#[cfg(test)]
mod tests {
    use egui::FontId;

    /// Every non-ASCII character in the viewer's code (outside comments) is one the default
    /// fonts can draw: egui panics on a missing glyph in debug builds and draws tofu otherwise.
    #[test]
    fn every_character_the_viewer_writes_has_a_glyph() {
        let sources = crate::test_support::sources();
        let mut used: Vec<char> = sources
            .iter()
            .flat_map(|src| src.lines())
            .filter(|line| !line.trim_start().starts_with("//"))
            .flat_map(|line| line.split("//").next().unwrap_or("").chars())
            .filter(|c| !c.is_ascii())
            .collect();
        used.sort_unstable();
        used.dedup();
        assert!(used.contains(&'ζ'), "the scan finds the code's characters");
        let ctx = egui::Context::default();
        let mut output = ctx.run_ui(egui::RawInput::default(), |_| {});
        output.textures_delta.clear();
        let missing: Vec<char> = ctx.fonts_mut(|f| {
            used.iter()
                .copied()
                .filter(|&c| {
                    !f.has_glyph(&FontId::proportional(12.0), c)
                        || !f.has_glyph(&FontId::monospace(12.0), c)
                })
                .collect()
        });
        assert!(missing.is_empty(), "no glyph for {missing:?}");
    }
}
