//! The light-driven learner against the exact solve on generated scenes.

use std::sync::Arc;

use flatland_geom::{Kernel, Scene, generate};
use flatland_solve::{
    ExactReference, Mesh, Representation, SolveParams, TransferOperator, never, solve,
    solve_errors, solve_operator, sweep_operator,
};

use super::*;
use flatland_testkit::assert_close;

fn fit(scene: Scene, params: LightParams) -> LightFit {
    let kernel = Arc::new(Kernel::new(scene));
    let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
    let mut fit = LightFit::new(kernel, mesh, params).unwrap();
    fit.run(&never, |_| {}).unwrap();
    fit
}

fn exact_b(fit: &LightFit) -> Vec<f64> {
    let op = sweep_operator(fit.kernel(), fit.mesh(), &never).unwrap();
    solve_operator(&op, fit.mesh(), &SolveParams::default(), &never)
        .unwrap()
        .radiosity
}

/// Probed everywhere, left without doubt, or with an estimate of nothing (the doubt that is
/// left multiplies no light), the learned operator lights the scene as the sweep's does: the
/// same B as the exact kernel's solve on the same mesh.
#[test]
fn probing_to_the_end_gives_the_exact_solution() {
    for scene in [
        generate::floor_plan(150, 4).unwrap(),
        generate::hall(150, 4).unwrap(),
    ] {
        let params = LightParams {
            tolerance: 1e-12,
            ..LightParams::default()
        };
        let fit = fit(scene, params);
        let estimate = fit.estimated_error().unwrap();
        assert!(
            fit.stopped() == Some(LightStop::Exact)
                || (fit.stopped() == Some(LightStop::Tolerance) && estimate <= 1e-12),
            "{:?}",
            fit.history()
        );
        let errors = solve_errors(fit.mesh(), fit.radiosity(), &exact_b(&fit));
        // GMRES stops at a relative residual of 1e-10; B − E is a part of B.
        assert!(errors.rel_l2_reflected < 1e-8, "{errors:?}");
    }
}

/// Stopped at the default tolerance, the measured error against the exact solve on the same
/// mesh is near the learner's own estimate, with fewer probes than elements.
#[test]
fn the_estimate_tracks_the_measured_error_at_the_tolerance() {
    for (name, scene) in [
        ("floor plan", generate::floor_plan(300, 11).unwrap()),
        ("hall", generate::hall(300, 12).unwrap()),
    ] {
        let params = LightParams::default();
        let fit = fit(scene, params);
        assert_eq!(
            fit.stopped(),
            Some(LightStop::Tolerance),
            "{name}: {:?}",
            fit.history()
        );
        let measured = solve_errors(fit.mesh(), fit.radiosity(), &exact_b(&fit)).rel_l2_reflected;
        let estimated = fit.estimated_error().unwrap();
        assert!(estimated <= params.tolerance);
        assert!(
            measured <= 3.0 * params.tolerance,
            "{name}: measured {measured}, estimated {estimated}"
        );
        assert!(fit.cells().len() < fit.mesh().len(), "{name}");
    }
}

/// Whatever is probed, no row gathers more than its ρ and no entry is negative: no light is
/// made, and B is never negative.
#[test]
fn rows_never_gather_more_than_rho_and_b_stays_physical() {
    let kernel = Arc::new(Kernel::new(generate::hall(200, 5).unwrap()));
    let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
    let mut fit = LightFit::new(kernel, mesh.clone(), LightParams::default()).unwrap();
    for _ in 0..5 {
        let stopped = fit.round(&never).unwrap();
        let ones = vec![1.0; mesh.len()];
        let mut sums = vec![0.0; mesh.len()];
        fit.rows.apply(&ones, &mut sums);
        for (i, s) in sums.iter().enumerate() {
            let rho = mesh.edge_of(i).reflectance;
            assert!(
                *s <= rho * (1.0 + 1e-12) && *s >= 0.0,
                "row {i}: {s}, ρ = {rho}"
            );
        }
        assert!(fit.radiosity().iter().all(|&b| b >= 0.0));
        if stopped.is_some() {
            break;
        }
    }
}

/// A solve with the fit as a representation on its own mesh gives the B its last round
/// solved.
#[test]
fn solving_with_the_fit_gives_its_own_radiosity() {
    let fit = fit(
        generate::floor_plan(120, 3).unwrap(),
        LightParams::default(),
    );
    let solved = solve(&fit, fit.mesh(), &SolveParams::default(), &never).unwrap();
    for (a, b) in solved.radiosity.iter().zip(fit.radiosity()) {
        assert_close!(*a, *b, 1e-6 * (1.0 + b.abs()));
    }
    assert_eq!(fit.basis_functions(), Some(fit.cells().len()));
}

/// On another mesh it solves through its pointwise ζ̃ (the probes' views), which lights the
/// scene like the exact kernel.
#[test]
fn on_another_mesh_the_pointwise_kernel_lights_the_scene_alike() {
    let fit = fit(generate::floor_plan(80, 5).unwrap(), LightParams::default());
    let other = Mesh::new(fit.kernel(), fit.mesh().len() * 2).unwrap();
    let solved = solve(&fit, &other, &SolveParams::default(), &never).unwrap();
    let params = SolveParams::default();
    let reference = ExactReference::new(fit.kernel(), other.len(), &params, &never).unwrap();
    let exact = reference.radiosity_on(&other, &never).unwrap();
    let error = solve_errors(&other, &solved.radiosity, &exact).rel_l2_reflected;
    assert!(error < 0.1, "{error}");
    assert!(solved.radiosity.iter().all(|&b| b >= 0.0));
}

/// A probe's view, read pointwise, is the kernel's own visibility at that receiver.
#[test]
fn a_probed_row_reads_the_kernel_exactly_pointwise() {
    let fit = fit(generate::hall(120, 8).unwrap(), LightParams::default());
    let kernel = fit.kernel();
    let mut compared = 0;
    for cell in fit.cells().iter().step_by(5) {
        for k in 0..200 {
            let s = (k as f64 + 0.37) / 200.0;
            let exact = kernel.eval(s, cell.t).zeta;
            let learned = fit.zeta(s, cell.t);
            assert!(
                (exact - learned).abs() <= 1e-9 * exact.abs().max(1.0),
                "({s}, {}): {learned} vs {exact}",
                cell.t
            );
            compared += usize::from(exact > 0.0);
        }
    }
    assert!(compared > 100, "{compared}");
}

/// Raising the demand after a stop continues the fit; the same settings give the same fit
/// (no randomness).
#[test]
fn a_stopped_fit_goes_on_when_asked_for_more_and_is_deterministic() {
    let loose = LightParams {
        tolerance: 0.2,
        ..LightParams::default()
    };
    let mut a = fit(generate::floor_plan(100, 7).unwrap(), loose);
    let cells = a.cells().len();
    a.set_params(LightParams {
        tolerance: 0.001,
        ..LightParams::default()
    })
    .unwrap();
    a.run(&never, |_| {}).unwrap();
    assert!(
        a.cells().len() > cells,
        "{} cells after {cells}",
        a.cells().len()
    );
    let b = fit(
        generate::floor_plan(100, 7).unwrap(),
        LightParams::default(),
    );
    let c = fit(
        generate::floor_plan(100, 7).unwrap(),
        LightParams::default(),
    );
    assert_eq!(b.radiosity(), c.radiosity());
    assert_eq!(b.cells(), c.cells());
}

/// A cell budget stops it, with no more cells than allowed.
#[test]
fn the_cell_budget_stops_it() {
    let kernel = Arc::new(Kernel::new(generate::floor_plan(300, 2).unwrap()));
    let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
    let first = LightFit::new(Arc::clone(&kernel), mesh.clone(), LightParams::default())
        .unwrap()
        .probes
        .first()
        .len();
    let params = LightParams {
        tolerance: 1e-9,
        max_cells: first + 10,
        ..LightParams::default()
    };
    let mut fit = LightFit::new(kernel, mesh, params).unwrap();
    assert_eq!(fit.run(&never, |_| {}).unwrap(), LightStop::Cells);
    assert!(fit.cells().len() <= first + 10);
}

/// Parameters out of range are refused by name.
#[test]
fn bad_parameters_are_refused_by_name() {
    for (params, name) in [
        (
            LightParams {
                tolerance: 0.0,
                ..LightParams::default()
            },
            "tolerance",
        ),
        (
            LightParams {
                tolerance: f64::NAN,
                ..LightParams::default()
            },
            "tolerance",
        ),
        (
            LightParams {
                first_round: 0,
                ..LightParams::default()
            },
            "first_round",
        ),
        (
            LightParams {
                max_cells: 0,
                ..LightParams::default()
            },
            "max_cells",
        ),
        (
            LightParams {
                max_seconds: 0.0,
                ..LightParams::default()
            },
            "max_seconds",
        ),
    ] {
        let message = params.check().unwrap_err().to_string();
        assert!(message.contains(name), "{message}");
    }
}
