//! What each idea of the visibility network earns on some scenes, against hierarchical radiosity:
//! `cargo run --release -p flatland-lab --example ablation -- [CELLS] [SEEDS] [SCENES]` where
//! SCENES is a comma-separated list of bundled scene names and `roomN` (random room N), e.g.
//! `fig3,maze,room3`. `flatland results` writes the same tables into RESULTS.md.

use std::sync::Arc;

use flatland_baselines::{HrParams, run_hr_at_budget};
use flatland_geom::{Kernel, Scene};
use flatland_lab::ablation::{leave_one_out, path, run_variants};
use flatland_lab::rooms::random_room;
use flatland_solve::Reference;

fn scene(name: &str) -> Scene {
    match name.strip_prefix("room") {
        Some(seed) => random_room(seed.parse().expect("roomN")).expect("a valid room"),
        None => Scene::load(format!("scenes/{name}.ron")).expect("a bundled scene"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cells: usize = args.first().map_or(400, |a| a.parse().expect("CELLS"));
    let seeds: u64 = args.get(1).map_or(2, |a| a.parse().expect("SEEDS"));
    let names = args.get(2).map_or("fig3,maze,corners", String::as_str);
    for name in names.split(',') {
        let kernel = Arc::new(Kernel::new(scene(name)));
        let reference = Arc::new(Reference::new(&kernel, 256, 4096, 1));
        let hr = run_hr_at_budget(&kernel, cells, 1, &HrParams::default()).expect("HR");
        let hr = reference.errors(&hr.approx);
        println!(
            "\n{name}: HR at {cells} links: grid {:.4}, held out {:.4}",
            hr.grid, hr.heldout
        );
        for variants in [path(), leave_one_out()] {
            let rows = run_variants(&kernel, &reference, &variants, cells, seeds, &|| false)
                .expect("fits");
            for r in rows {
                println!(
                    "  {:<44} grid {:.4} ({:.2}× HR)  held {:.4}  L1 {:.4}  cells {:>5.0}  rays {:>6.0}  {:.2} s",
                    r.variant,
                    r.grid,
                    r.grid / hr.grid,
                    r.heldout,
                    r.l1_grid,
                    r.cells,
                    r.rays,
                    r.wall_s
                );
            }
            println!();
        }
    }
}
