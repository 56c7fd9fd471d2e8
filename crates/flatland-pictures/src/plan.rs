//! The lit plan as a drawing: each element a stroked segment coloured by B as it runs along it
//! (a gradient through B at its start, middle and end: the final gather's where the caller has
//! one, else the line through the element midpoints; its value as `data-b`), blockers grey, point lights and emitters marked, a colour bar — written by
//! `flatland_svg::lit_svg`, coloured here by the one colour map and scale rule of every picture
//! and of the viewer. It opens in any browser and over the user's own drawing; its PNG is the
//! same SVG rendered.

use flatland_geom::{PointLight, Role, Scene};
use flatland_solve::Mesh;
use flatland_svg::{ColourScale, LitPlan, LitSegment, LitSvg, lit_svg};

use crate::colormap::{Scale, inferno, radiosity_top};

/// How many labelled marks the colour bar has, bottom and top included.
const TICKS: usize = 5;

/// The colour scale of a lit plan: the viewer's default tone (the top is the brightest element
/// that does not emit, and the scale is logarithmic over four decades below it: on a real level
/// a linear scale set by the walls beside a lamp shows the rest of the plan black).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanColours {
    scale: Scale,
}

impl PlanColours {
    /// The scale for radiosity `b` on `mesh`.
    #[must_use]
    pub fn new(mesh: &Mesh, b: &[f64]) -> Self {
        PlanColours {
            scale: Scale {
                top: radiosity_top(mesh, b),
                log: true,
            },
        }
    }

    /// A scale whose top is `top` (one scale for many pictures, e.g. every position of a
    /// moving light), log or linear.
    #[must_use]
    pub fn with_top(top: f64, log: bool) -> Self {
        PlanColours {
            scale: Scale { top, log },
        }
    }

    /// The scale it colours by.
    #[must_use]
    pub fn scale(&self) -> Scale {
        self.scale
    }
}

impl ColourScale for PlanColours {
    fn colour(&self, value: f64) -> [u8; 3] {
        self.scale.colour(value)
    }

    fn bar(&self, x: f64) -> [u8; 3] {
        inferno(x)
    }

    fn ticks(&self) -> Vec<(f64, String)> {
        (0..TICKS)
            .map(|k| {
                let x = k as f64 / (TICKS - 1) as f64;
                (x, format!("{:.3e}", self.scale.value_at(x)))
            })
            .collect()
    }

    fn caption(&self) -> String {
        if self.scale.log {
            "B (log scale)".into()
        } else {
            "B".into()
        }
    }
}

/// `scene` lit by `b` (one radiosity per element of `mesh`, a mesh of `scene`), each element
/// drawn by `along` (B at its start, middle and end: [`FinalGather::along`] or
/// [`line_along`]), titled `title`.
///
/// # Panics
/// If `b` or `along` does not have one value per element of `mesh` (a caller's bug: a
/// solution is always of its own mesh).
///
/// [`FinalGather::along`]: flatland_solve::FinalGather::along
/// [`line_along`]: flatland_solve::line_along
#[must_use]
pub fn lit_plan(scene: &Scene, mesh: &Mesh, b: &[f64], along: &[[f64; 3]], title: &str) -> LitSvg {
    let colours = PlanColours::new(mesh, b);
    lit_plan_by(scene, mesh, b, along, mesh.lights(), title, &colours)
}

/// [`lit_plan`] lit by `lights` (which may not be the mesh's own: a moving light) and coloured
/// by `colours`.
///
/// # Panics
/// As [`lit_plan`].
#[must_use]
pub fn lit_plan_by(
    scene: &Scene,
    mesh: &Mesh,
    b: &[f64],
    along: &[[f64; 3]],
    lights: &[PointLight],
    title: &str,
    colours: &PlanColours,
) -> LitSvg {
    assert_eq!(b.len(), mesh.len(), "one radiosity per element");
    assert_eq!(along.len(), mesh.len(), "B along every element");
    let segments: Vec<LitSegment> = mesh
        .elements()
        .iter()
        .zip(b)
        .zip(along)
        .map(|((element, &value), &along)| LitSegment {
            edge: element.edge,
            a: element.a,
            b: element.b,
            value,
            along,
            emission: mesh.edge_of(element.mesh_edge).emission,
        })
        .collect();
    let blockers: Vec<_> = scene
        .edges()
        .iter()
        .filter(|e| e.role == Role::Blocker)
        .map(|e| (e.a, e.b))
        .collect();
    let lights: Vec<_> = lights.iter().map(|l| l.at).collect();
    lit_svg(&LitPlan {
        title,
        segments: &segments,
        blockers: &blockers,
        lights: &lights,
        colours,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use flatland_geom::Kernel;
    use flatland_solve::{ExactReference, SolveParams, line_along};

    fn solved(name: &str) -> (Arc<Kernel>, Mesh, Vec<f64>) {
        let kernel = Arc::new(Kernel::new(flatland_geom::bundled::scene(name).unwrap()));
        let never = || false;
        let reference = ExactReference::new(&kernel, 256, &SolveParams::default(), &never).unwrap();
        let b = reference.solution().radiosity.clone();
        (Arc::clone(&kernel), reference.mesh().clone(), b)
    }

    #[test]
    fn every_element_is_a_segment_in_its_colour_carrying_its_value() {
        let (kernel, mesh, b) = solved("maze");
        let svg = lit_plan(kernel.scene(), &mesh, &b, &line_along(&mesh, &b), "maze");
        let text = svg.svg();
        assert_eq!(text.matches("data-b=").count(), mesh.len());
        let colours = PlanColours::new(&mesh, &b);
        let brightest_lit = (0..mesh.len())
            .filter(|&i| mesh.edge_of(i).emission == 0.0)
            .max_by(|&i, &j| b[i].total_cmp(&b[j]))
            .unwrap();
        let [r, g, bl] = colours.colour(b[brightest_lit]);
        assert_eq!(
            [r, g, bl],
            inferno(1.0),
            "the brightest lit element tops the scale"
        );
        assert!(text.contains(&format!("#{r:02x}{g:02x}{bl:02x}")));
    }

    #[test]
    fn the_png_is_the_svg_rendered() {
        let (kernel, mesh, b) = solved("fig3");
        let svg = lit_plan(kernel.scene(), &mesh, &b, &line_along(&mesh, &b), "fig3");
        let png = svg.png().unwrap();
        assert!(png.starts_with(b"\x89PNG"));
        let image = image::load_from_memory(&png).unwrap();
        assert_eq!((image.width(), image.height()), svg.size());
    }

    #[test]
    fn the_bar_is_labelled_bottom_to_top_by_the_scale() {
        let (_, mesh, b) = solved("box");
        let colours = PlanColours::new(&mesh, &b);
        let ticks = colours.ticks();
        assert_eq!(ticks.len(), TICKS);
        assert_eq!(ticks[0].0, 0.0);
        assert_eq!(ticks[TICKS - 1].0, 1.0);
        let top: f64 = ticks[TICKS - 1].1.parse().unwrap();
        assert!((top - colours.scale().top).abs() <= 1e-3 * colours.scale().top);
    }
}
