//! Load a scene, learn its kernel, and light the scene with it: the radiosity solved with the
//! learned kernel against the one solved with the exact kernel.
//!
//! ```text
//! cargo run --release --example solve_scene -- [SCENE.ron] [CELLS]
//! ```

use std::error::Error;
use std::ops::ControlFlow;
use std::sync::Arc;

use flatland_geom::{Kernel, Scene};
use flatland_solve::{
    ExactReference, Mesh, Reference, Representation, SolveParams, never, solve_against,
};
use kernel_fit::{Fit, FitParams};

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "scenes/fig3.ron".to_owned());
    let cells: usize = match args.next() {
        Some(text) => text.parse().map_err(|e| format!("CELLS `{text}`: {e}"))?,
        None => 400,
    };

    // Learn the kernel (what `flatland fit` does).
    let kernel = Arc::new(Kernel::new(Scene::load(&path)?));
    let params = FitParams {
        target_cells: cells,
        ..FitParams::default()
    };
    let reference = Arc::new(Reference::new(&kernel, 128, params.heldout, params.seed));
    let mut fit = Fit::new(Arc::clone(&kernel), reference, params)?;
    let summary = fit.run(10_000, |_| ControlFlow::Continue(()))?;
    println!(
        "{path}: learned {} cells, relative L2 of zeta {:.4} (held out)",
        summary.cells, summary.errors.heldout
    );

    // Solve on the scene's default mesh; the exact kernel on a 4× finer one is the reference.
    let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene()))?;
    let solve_params = SolveParams::default();
    let fine = ExactReference::default_elements(mesh.len());
    let exact =
        ExactReference::new(&kernel, fine, &solve_params, &never)?.radiosity_on(&mesh, &never)?;
    let kernels: [(&str, &dyn Representation); 2] =
        [("exact", kernel.as_ref()), ("learned", fit.model())];
    for (name, rep) in kernels {
        let lit = solve_against(rep, &mesh, &exact, &solve_params, &never)?;
        println!(
            "{name:>8} kernel, {} elements: relative L2 of B {:.4}, of the reflected part {:.4} \
             ({} iterations, {:.3} s)",
            mesh.len(),
            lit.errors.rel_l2_b,
            lit.errors.rel_l2_reflected,
            lit.solution.iterations,
            lit.solution.wall_s()
        );
    }
    Ok(())
}
