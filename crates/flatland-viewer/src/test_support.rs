//! What the unit tests share: small worlds and moments made without a learner, and the
//! viewer's sources (for the glyph check).

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use flatland_geom::Kernel;
use flatland_solve::Reference;
use kernel_fit::{FitParams, HistoryPoint};

use crate::prefix::Prefix;
use crate::timeline::Moment;
use crate::worker::{CellMark, Growth, Progress, Status, World};

/// The text of every source file of the crate (`src/**.rs`).
pub fn sources() -> Vec<String> {
    fn walk(dir: &Path, out: &mut Vec<String>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .expect("the crate's sources")
            .map(|e| e.expect("a directory entry").path())
            .collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|x| x == "rs") {
                out.push(std::fs::read_to_string(&path).expect("a source file"));
            }
        }
    }
    let mut out = Vec::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut out);
    out
}

/// A world of `fig3` with a tiny reference, numbered `id`.
pub fn world(id: u64) -> Arc<World> {
    let scene = flatland_geom::bundled::scene("fig3").unwrap();
    let kernel = Arc::new(Kernel::new(scene.clone()));
    Arc::new(World {
        id,
        scene,
        reference: Arc::new(Reference::new(&kernel, 4, 16, 1)),
        kernel,
        exact_small: Vec::new(),
        defined: [true; 2],
    })
}

/// Moment `i` of a made-up run on `world`: at `i` × 100 ms and `i` × 100 steps, with `cells`
/// cells, 10 (`i` + 1) samples and `i` + 1 points of the curve (each moment's vectors its own,
/// as the learner publishes them).
pub fn moment(world: &Arc<World>, i: u64, cells: usize) -> Moment {
    let samples: Vec<([f32; 2], u32)> = (0..10 * (i + 1)).map(|k| ([k as f32, 0.0], 0)).collect();
    let history: Vec<HistoryPoint> = (0..=i)
        .map(|k| HistoryPoint {
            steps: k * 100,
            rays: k,
            cells,
            samples: 0,
            rel_l2_heldout: 1.0,
        })
        .collect();
    let growth = Growth {
        steps: i * 100,
        cells: vec![
            CellMark {
                st: Some([0.5, 0.5]),
                width: 0.1,
                critical: false,
                seen: Default::default(),
            };
            cells
        ],
        face_edges: Vec::new(),
        run_time: Duration::from_millis(100 * i),
        progress: Progress::Steps { rays: i, sets: 1 },
    };
    Moment {
        world: Arc::clone(world),
        status: Status {
            growth: Arc::new(growth),
            samples: Prefix::new(Arc::new(samples)),
            history: Prefix::new(Arc::new(history)),
            world: world.id,
            running: true,
            stopped: None,
            steps_per_s: 0.0,
            summary: None,
            handled: 0,
            params: FitParams::default(),
            occupied_faces: None,
        },
        learned: None,
        lit: None,
    }
}
