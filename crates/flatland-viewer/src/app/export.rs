//! Export: the window as a PNG (egui's screenshot command; the pixels are encoded by `image`
//! and written atomically on a thread of their own, so no frame waits for it) and the run as
//! the model file `flatland eval` reads (written by the learner's thread, which owns the fit).
//! Files are named after the scene, the learner and the step: `floorplan-visibility-step12000.png`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender};

use egui::{ColorImage, ScreenshotCallback, ViewportCommand};

use super::ViewerApp;
use crate::worker::Command;

/// Where exports go and the screenshots under way.
pub(super) struct Exports {
    /// The folder.
    pub(super) dir: PathBuf,
    done_tx: Sender<Result<PathBuf, String>>,
    done_rx: Receiver<Result<PathBuf, String>>,
}

impl Exports {
    pub(super) fn new() -> Exports {
        let (done_tx, done_rx) = mpsc::channel();
        Exports {
            dir: PathBuf::from("."),
            done_tx,
            done_rx,
        }
    }

    /// Says in the message line which pictures were written (or why not).
    pub(super) fn take_finished(&mut self, message: &mut Option<(String, bool)>) {
        while let Ok(done) = self.done_rx.try_recv() {
            *message = Some(match done {
                Ok(path) => (format!("saved the view to {}", path.display()), false),
                Err(e) => (e, true),
            });
        }
    }

    /// Asks `ctx` (the window's context, the one that draws the frames) for a screenshot of
    /// the next frame, to be written to `path`.
    fn request_png(&self, ctx: &egui::Context, path: PathBuf) {
        let done = self.done_tx.clone();
        let repaint = ctx.clone();
        let callback = ScreenshotCallback::new(move |image: Arc<ColorImage>| {
            // Encoding 1280 × 800 takes tens of milliseconds: not on the render thread.
            let _ = std::thread::Builder::new()
                .name("flatland-png".into())
                .spawn(move || {
                    let _ = done.send(write_png(&path, &image).map(|()| path));
                    repaint.request_repaint();
                });
        });
        ctx.send_viewport_cmd(ViewportCommand::Screenshot(callback));
    }
}

/// `image` as a PNG file at `path`, written atomically.
pub fn write_png(path: &Path, image: &ColorImage) -> Result<(), String> {
    use image::ImageEncoder as _;
    let fail = |e: &dyn std::fmt::Display| format!("could not save {}: {e}", path.display());
    let [w, h] = image.size;
    let rgba: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|c| c.to_srgba_unmultiplied())
        .collect();
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgba, w as u32, h as u32, image::ExtendedColorType::Rgba8)
        .map_err(|e| fail(&e))?;
    flatland_geom::write_atomic(path, &png).map_err(|e| fail(&e))
}

/// A scene label as a file name part: letters, digits, `-` and `_` (the file's extension
/// dropped, "(edited)" a word).
fn file_part(label: &str) -> String {
    let label = label
        .replace(".ron", "")
        .replace(".json", "")
        .replace(".svg", "");
    let mut part = String::new();
    for c in label.chars() {
        if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
            part.push(c);
        } else if !part.ends_with('-') {
            part.push('-');
        }
    }
    part.trim_matches('-').to_owned()
}

impl ViewerApp {
    /// Files of this run start with the scene and the learner's name: `floorplan-light`,
    /// `floorplan-visibility`.
    fn export_stem(&self) -> String {
        let scene = file_part(&self.scene_label);
        format!(
            "{}-{}",
            if scene.is_empty() { "scene" } else { &scene },
            self.fit_learner.name()
        )
    }

    /// Saves the window `ctx` draws, as drawn in the next frame, to `{stem}-step{N}.png` in the
    /// export folder, `N` the step of the moment shown.
    pub fn export_png(&mut self, ctx: &egui::Context) {
        let steps = self.shown().map_or(0, crate::timeline::Moment::steps);
        let path = self
            .export
            .dir
            .join(format!("{}-step{steps}.png", self.export_stem()));
        self.export.request_png(ctx, path);
        self.message = Some(("saving the view…".into(), false));
    }

    /// Saves the running fit as a model file `{stem}-step{N}.model.json` in the export folder
    /// (the learner's network as it is now, whatever moment is shown: past moments keep what
    /// the plots need, not the network).
    pub fn export_model(&mut self) {
        let dir = self.export.dir.clone();
        let stem = self.export_stem();
        self.worker.send(Command::ExportModel { dir, stem });
    }

    /// The folder exports go to.
    pub fn export_dir(&self) -> &Path {
        &self.export.dir
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_keep_only_plain_characters() {
        assert_eq!(file_part("floorplan.ron"), "floorplan");
        assert_eq!(file_part("my room (edited).ron"), "my-room-edited");
        assert_eq!(file_part("a.json"), "a");
        assert_eq!(file_part("maze.ron (edited)"), "maze-edited");
        assert_eq!(file_part("(((.ron"), "");
        assert_eq!(file_part("floorplan.svg"), "floorplan");
    }

    #[test]
    fn a_png_is_written_whole_and_reads_back() {
        let dir = std::env::temp_dir().join(format!("flatland-viewer-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("view.png");
        let mut image = ColorImage::filled([4, 3], egui::Color32::from_rgb(10, 20, 30));
        image.pixels[5] = egui::Color32::from_rgb(200, 100, 0);
        write_png(&path, &image).unwrap();
        let back = image::open(&path).unwrap().to_rgba8();
        assert_eq!(back.dimensions(), (4, 3));
        assert_eq!(back.get_pixel(1, 1).0, [200, 100, 0, 255]);
        assert_eq!(back.get_pixel(0, 0).0, [10, 20, 30, 255]);
        let err = write_png(&dir.join("no/such/folder/x.png"), &image).unwrap_err();
        assert!(err.contains("could not save"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
