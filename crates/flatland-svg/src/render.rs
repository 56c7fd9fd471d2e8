//! SVG to PNG with resvg, with the font this crate ships (no system fonts: a picture must not
//! depend on the machine it was drawn on).

use std::sync::{Arc, OnceLock};

use crate::SvgError;

/// The fonts a picture's text is set in: Ubuntu Light, from `epaint_default_fonts`, as every
/// generic family.
fn fonts() -> Arc<usvg::fontdb::Database> {
    static FONTS: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let mut db = usvg::fontdb::Database::new();
            db.load_font_data(epaint_default_fonts::UBUNTU_LIGHT.to_vec());
            db.set_sans_serif_family("Ubuntu");
            db.set_serif_family("Ubuntu");
            Arc::new(db)
        })
        .clone()
}

/// `svg` rendered at its own size, as PNG bytes.
pub fn png(svg: &str) -> Result<Vec<u8>, SvgError> {
    let options = usvg::Options {
        font_family: "Ubuntu".to_string(),
        fontdb: fonts(),
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_str(svg, &options).map_err(|e| SvgError::Render(e.to_string()))?;
    let size = tree.size().to_int_size();
    let mut pixmap =
        resvg::tiny_skia::Pixmap::new(size.width(), size.height()).ok_or_else(|| {
            SvgError::Render(format!(
                "a {}x{} picture has no pixels",
                size.width(),
                size.height()
            ))
        })?;
    resvg::render(&tree, usvg::Transform::identity(), &mut pixmap.as_mut());
    pixmap
        .encode_png()
        .map_err(|e| SvgError::Render(e.to_string()))
}
