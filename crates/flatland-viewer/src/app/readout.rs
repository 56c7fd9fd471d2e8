//! The readout under the pointer in the kernel plots: the two points, G, V, k, ζ, the learned
//! value, and for a visibility model how its Ṽ is decided there.

use flatland_geom::{Kernel, PairClass};
use flatland_solve::Representation;
use kernel_fit::LearnedKernel;

use crate::worker::{APPROX_RES, LearnedGrid};

/// Where the readout's learned value comes from.
#[derive(Clone, Copy)]
pub(super) enum Learned<'a> {
    /// The live model: exact at the pointer.
    Model(&'a LearnedKernel),
    /// A past moment's display grid: the value of the grid cell under the pointer.
    Grid(&'a LearnedGrid),
    /// Nothing learned to show yet.
    Unknown,
}

impl Learned<'_> {
    fn value(self, s: f64, t: f64) -> String {
        match self {
            Learned::Model(m) => format!("{:.5}", m.zeta(s, t)),
            Learned::Grid(g) => {
                let cell = |x: f64| ((x * APPROX_RES as f64) as usize).min(APPROX_RES - 1);
                g.values
                    .get(cell(s) * APPROX_RES + cell(t))
                    .map_or("–".into(), |v| format!("{v:.5} (display grid, then)"))
            }
            Learned::Unknown => "–".into(),
        }
    }
}

/// What the pointer at `(s, t)` shows: the two points, G, V, k, ζ; the learned ζ̃; for a
/// visibility model live, Ṽ and how it is decided there (geometry, or the cells of the face).
pub(super) fn readout_text(kernel: &Kernel, learned: Learned<'_>, s: f64, t: f64) -> String {
    let k = kernel.eval(s, t);
    let mut text = format!(
        "s {s:.4} (edge {}), t {t:.4} (edge {})\nG {:.4}  V {}  k {:.5}\nζ {:.5}  learned {}",
        k.x.edge,
        k.y.edge,
        k.geometry,
        if k.visible {
            "1 (visible)"
        } else {
            "0 (blocked)"
        },
        k.k,
        k.zeta,
        learned.value(s, t),
    );
    let Learned::Model(model) = learned else {
        return text;
    };
    if model.target() != kernel_fit::Target::Visibility {
        return text;
    }
    let u = kernel.unoccluded(s, t);
    let line = if u.k <= 0.0 {
        "learned V –: the points do not face each other".to_owned()
    } else {
        match kernel.pair_class(u.sender, u.receiver) {
            PairClass::Zero => "learned V –: no transfer between these edges".to_owned(),
            PairClass::Visible => "learned V 1: geometry says visible (no cell, no ray)".to_owned(),
            PairClass::Hidden => "learned V 0: geometry says blocked (no cell, no ray)".to_owned(),
            PairClass::Varies => {
                let v = model.zeta(s, t) / u.zeta;
                match model.face_cells(s, t).map_or(0, |c| c.len()) {
                    0 => {
                        format!("learned V {v:.3}: no cell in this face (its pair's cells answer)")
                    }
                    1 => format!("learned V {v:.3}: from the 1 cell of this face"),
                    n => format!("learned V {v:.3}: from the {n} cells of this face"),
                }
            }
        }
    };
    text.push('\n');
    text.push_str(&line);
    text
}
