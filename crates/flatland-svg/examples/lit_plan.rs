//! Imports an SVG floor plan, solves it exactly with default arguments and writes the lit plan
//! as SVG and PNG, in a grey ramp of its own: `flatland solve --scene plan.svg --out lit.svg`
//! does the same in the project's colours.
//!
//! `cargo run --release -p flatland-svg --example lit_plan -- scenes/svg/floorplan.svg lit.svg`
//! (writes `lit.svg` and `lit.png`). The colour map here is a plain grey ramp; the CLI passes
//! the project's own.

use flatland_svg::{ColourScale, ImportParams, LitPlan, LitSegment, import_file, lit_svg};

/// Black to light grey over three decades below `top`.
struct Grey {
    top: f64,
}

impl Grey {
    const DECADES: f64 = 3.0;
}

impl ColourScale for Grey {
    fn colour(&self, value: f64) -> [u8; 3] {
        self.bar(1.0 + (value / self.top).log10() / Self::DECADES)
    }
    fn bar(&self, x: f64) -> [u8; 3] {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        [(220.0 * x) as u8; 3]
    }
    fn ticks(&self) -> Vec<(f64, String)> {
        (0..=3)
            .map(|k| {
                let x = f64::from(k) / Self::DECADES;
                let value = self.top * 10f64.powf((x - 1.0) * Self::DECADES);
                (x, format!("{value:.3}"))
            })
            .collect()
    }
    fn caption(&self) -> String {
        "B (log)".into()
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output] = args.as_slice() else {
        return Err("usage: lit_plan PLAN.svg OUT.svg".into());
    };
    let drawing = import_file(input, &ImportParams::default())?;
    for warning in drawing.warnings() {
        eprintln!("warning: {warning}");
    }
    let kernel = flatland_geom::Kernel::new(drawing.into_scene()?);
    let elements = flatland_solve::Mesh::default_elements(kernel.scene());
    let mesh = flatland_solve::Mesh::new(&kernel, elements)?;
    let params = flatland_solve::SolveParams::default();
    let b = flatland_solve::solve(&kernel, &mesh, &params, &flatland_solve::never)?.radiosity;
    // B along each element: the line through the element midpoints.
    let along = flatland_solve::line_along(&mesh, &b);
    let segments: Vec<LitSegment> = mesh
        .elements()
        .iter()
        .zip(&b)
        .zip(&along)
        .map(|((e, &value), &along)| LitSegment {
            edge: e.edge,
            a: e.a,
            b: e.b,
            value,
            along,
            emission: kernel.scene().edge(e.edge).emission,
        })
        .collect();
    let top = segments
        .iter()
        .filter(|s| s.emission == 0.0)
        .map(|s| s.value)
        .fold(f64::MIN_POSITIVE, f64::max);
    let picture = lit_svg(&LitPlan {
        title: &format!("{input}: exact solve, {} elements", segments.len()),
        segments: &segments,
        blockers: &[],
        lights: &[],
        colours: &Grey { top },
    });
    std::fs::write(output, picture.svg())?;
    std::fs::write(
        std::path::Path::new(output).with_extension("png"),
        picture.png()?,
    )?;
    Ok(())
}
