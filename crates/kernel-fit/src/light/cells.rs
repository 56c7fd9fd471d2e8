//! The light-driven learner's model: one cell per face of the visibility structure it has
//! learned.
//!
//! A face is learned by one ray, the first time a resolved block meets it; the ray's `(s, t)`
//! becomes a cell carrying the face's visibility, filed by the face's key so that every later
//! block meeting the face reads the cell instead of casting again. A cell is a basis function:
//! the indicator of its face times the closed-form unoccluded kernel. Cells are kept in the
//! order they were learned, which is the order the light led the learner to them.
//!
//! They are not joined into an SGCS network: inserting cells at arbitrary positions, without
//! the adaptation steps that move cells into place, makes the network's topology degenerate
//! (measured: 12 s to insert the 43 000 cells of a 200-edge floor plan, 570 s for the
//! 300 000 of a hall of 125 boxes, against 0.3 s and 3 s for the same loop with a key table
//! alone).

use std::sync::Arc;

use flatland_geom::Kernel;
use foldhash::HashMap;
use rayon::prelude::*;

use super::Faces;
use crate::FitError;
use crate::visibility::FaceKey;

/// One learned face: where its ray was cast and what it found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceCell {
    /// The ray's sender parameter.
    pub s: f64,
    /// The ray's receiver parameter.
    pub t: f64,
    /// Whether the ray found the face clear (`V = 1`) or blocked (`V = 0`).
    pub visible: bool,
}

/// Bytes per face in the key table (key and cell index; the table's slack is counted by
/// its capacity).
const BYTES_PER_KEY: usize = std::mem::size_of::<(FaceKey, u32)>() + 1;

/// The faces learned so far, one cell each.
#[derive(Clone)]
pub(crate) struct FaceCells {
    kernel: Arc<Kernel>,
    /// The cell of each face learned.
    known: HashMap<FaceKey, u32>,
    cells: Vec<FaceCell>,
}

impl FaceCells {
    /// No face learned yet.
    pub(crate) fn new(kernel: Arc<Kernel>) -> FaceCells {
        FaceCells {
            kernel,
            known: HashMap::default(),
            cells: Vec::new(),
        }
    }

    /// The cells, in the order they were learned.
    pub(crate) fn cells(&self) -> &[FaceCell] {
        &self.cells
    }

    /// Bytes held: the key table and the cells.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.known.capacity() * BYTES_PER_KEY
            + self.cells.capacity() * std::mem::size_of::<FaceCell>()
    }
}

impl Faces for FaceCells {
    fn known(&self, key: &FaceKey) -> Option<f64> {
        let cell = self.cells[*self.known.get(key)? as usize];
        Some(if cell.visible { 1.0 } else { 0.0 })
    }

    fn learn(&mut self, rays: &[(FaceKey, [f64; 2])]) -> Result<u64, FitError> {
        let kernel = &self.kernel;
        let visible: Vec<bool> = rays
            .par_iter()
            .with_min_len(64)
            .map(|(_, [s, t])| kernel.eval(*s, *t).visible)
            .collect();
        for ((key, [s, t]), visible) in rays.iter().zip(visible) {
            if !self.known.contains_key(key) {
                let id =
                    u32::try_from(self.cells.len()).map_err(|_| FitError::InvalidParameter {
                        name: "max_rays",
                        value: self.cells.len().to_string(),
                        valid: "at most 2³² − 1 faces learned",
                    })?;
                self.known.insert(key.clone(), id);
                self.cells.push(FaceCell {
                    s: *s,
                    t: *t,
                    visible,
                });
            }
        }
        Ok(rays.len() as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::test_support::RayFaces;
    use flatland_geom::generate;

    /// The cells hold what the plain ray store holds, face for face, one cell per face, in
    /// the order learned.
    #[test]
    fn cells_learn_what_one_ray_per_face_says() {
        let kernel = Arc::new(Kernel::new(generate::floor_plan(60, 2).unwrap()));
        let (mut cells, mut rays) = (FaceCells::new(kernel.clone()), RayFaces::new(kernel));
        let mut batch = Vec::new();
        for k in 0..400 {
            let (s, t) = ((k as f64 * 0.618_034) % 1.0, (k as f64 * 0.414_214) % 1.0);
            if let Some(key) = rays.key(s, t)
                && !batch.iter().any(|(b, _)| b == &key)
            {
                batch.push((key, [s, t]));
            }
        }
        assert!(batch.len() > 10, "only {} faces", batch.len());
        assert_eq!(cells.learn(&batch).unwrap(), batch.len() as u64);
        rays.learn(&batch).unwrap();
        for (key, _) in &batch {
            assert_eq!(cells.known(key), rays.known(key));
        }
        assert_eq!(cells.cells().len(), batch.len());
        for (cell, (key, [s, t])) in cells.cells().iter().zip(&batch) {
            assert_eq!((cell.s, cell.t), (*s, *t));
            assert_eq!(Some(f64::from(u8::from(cell.visible))), rays.known(key));
        }
        // A face learned again keeps its first cell.
        cells.learn(&batch[..1]).unwrap();
        assert_eq!(cells.cells().len(), batch.len());
    }
}
