//! The crate's one error type.

/// Everything that can go wrong while drawing a picture or encoding it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PictureError {
    /// A heatmap's values do not fill its grid.
    #[error("heatmap: {values} values for a {res}×{res} grid (expected res ≥ 1 and res² values)")]
    GridSize {
        /// The values given.
        values: usize,
        /// The grid's side.
        res: usize,
    },
    /// Values per element that are not one per element of the mesh drawn.
    #[error("{what}: {values} values for a mesh of {elements} elements (expected one per element)")]
    PerElement {
        /// What was given, e.g. "B along the elements".
        what: &'static str,
        /// How many were given.
        values: usize,
        /// The mesh's elements.
        elements: usize,
    },
    /// A picture would be wider or taller than an image can be.
    #[error("{what} too large: {side} pixels a side (at most {})", u32::MAX)]
    TooLarge {
        /// What was drawn.
        what: &'static str,
        /// Its side in pixels.
        side: usize,
    },
    /// The drawing library failed (its message, as text: its error type borrows the image).
    #[error("drawing {what}: {message}")]
    Draw {
        /// What was drawn, in words ("the plot", "the heatmap", …).
        what: &'static str,
        /// The drawing library's message.
        message: String,
    },
    /// The PNG encoder failed.
    #[error("encoding the PNG")]
    Encode(#[from] image::ImageError),
}

impl PictureError {
    /// Refuses `values` values of `what` for a mesh of `elements`, unless one per element.
    pub(crate) fn per_element(
        what: &'static str,
        values: usize,
        elements: usize,
    ) -> Result<(), PictureError> {
        if values == elements {
            Ok(())
        } else {
            Err(PictureError::PerElement {
                what,
                values,
                elements,
            })
        }
    }

    /// A drawing error of `what` (for `map_err`).
    pub(crate) fn draw<E: std::fmt::Display>(what: &'static str) -> impl Fn(E) -> PictureError {
        move |e| PictureError::Draw {
            what,
            message: e.to_string(),
        }
    }
}
