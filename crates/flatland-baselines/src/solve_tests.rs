//! The baselines solved through the one trait: their operators against brute-force
//! integration of their own ζ̃, and their errors against the exact kernel's B.

use flatland_geom::{Kernel, KernelParams, Scene};
use flatland_solve::{
    DenseOperator, ExactReference, Mesh, Representation, SolveError, SolveParams,
    inverse_source_weights, never, solve, solve_against, solve_errors, solve_operator,
};

use crate::{BlockValue, HrParams, UniformGrid, UniformParams, run_hr_at_budget};

fn bundled(name: &str) -> Scene {
    flatland_geom::bundled::scene(name).expect("bundled scene")
}

#[test]
fn every_representation_solves_through_the_one_trait() {
    let kernel = Kernel::new(bundled("fig3"));
    let mesh = Mesh::new(&kernel, 256).unwrap();
    let params = SolveParams::default();
    let truth = ExactReference::new(&kernel, 2048, &params, &never)
        .unwrap()
        .radiosity_on(&mesh, &never)
        .unwrap();
    let exact_b = solve_against(&kernel, &mesh, &truth, &params, &never).unwrap();
    assert!(
        exact_b.errors.rel_l2_reflected < 5e-3,
        "{:?}",
        exact_b.errors
    );
    let hr = run_hr_at_budget(&kernel, 400, 1, &HrParams::default())
        .unwrap()
        .approx;
    let uniform = UniformGrid::build(&kernel, 20, &UniformParams::default(), 1).unwrap();
    let exact_means = |block_value| {
        UniformGrid::build(
            &kernel,
            20,
            &UniformParams {
                block_value,
                ..UniformParams::default()
            },
            1,
        )
        .unwrap()
    };
    let reps: Vec<(&str, &dyn Representation)> = vec![("hr", &hr), ("uniform", &uniform)];
    for (name, rep) in reps {
        let c = solve_against(rep, &mesh, &truth, &params, &never).unwrap();
        assert!(c.solution.radiosity.iter().all(|b| b.is_finite()), "{name}");
        assert!(
            c.errors.rel_l2_reflected.is_finite()
                && c.errors.rel_l2_reflected > exact_b.errors.rel_l2_reflected,
            "{name}: {:?}",
            c.errors
        );
        println!("fig3, {name} at 400: {:?}", c.errors);
    }
    for block_value in [BlockValue::ExactZetaMean, BlockValue::ExactKernelMean] {
        let grid = exact_means(block_value);
        let c = solve_against(&grid, &mesh, &truth, &params, &never).unwrap();
        println!("fig3, uniform {block_value:?} 20×20: {:?}", c.errors);
        assert!(c.errors.rel_l2_reflected.is_finite());
    }
}

#[test]
fn piecewise_constant_operators_equal_brute_force_integration_of_their_own_zeta() {
    // HR's gather/push–pull and the uniform grid's blocks against ∫ ζ̃(s, t_i) / E' L ds by
    // dense midpoint sampling of their own ζ̃ (which jumps where a link or block ends inside
    // an element, so the sampling error is below jump / samples per element).
    let kernel = Kernel::new(bundled("fig3"));
    let mesh = Mesh::new(&kernel, 60).unwrap();
    let params = SolveParams::default();
    let hr = run_hr_at_budget(&kernel, 200, 1, &HrParams::default())
        .unwrap()
        .approx;
    let grid = UniformGrid::build(&kernel, 12, &UniformParams::default(), 1).unwrap();
    let k_grid = UniformGrid::build(
        &kernel,
        12,
        &UniformParams {
            block_value: BlockValue::ExactKernelMean,
            ..UniformParams::default()
        },
        1,
    )
    .unwrap();
    let inverse = inverse_source_weights(&mesh).unwrap();
    let reps: [&dyn Representation; 3] = [&hr, &grid, &k_grid];
    let samples = 4000;
    for rep in reps {
        let fast = solve(rep, &mesh, &params, &never).unwrap();
        let els = mesh.elements();
        let brute = DenseOperator::assemble(
            mesh.len(),
            |i, row| {
                for (j, e) in els.iter().enumerate() {
                    let sum: f64 = (0..samples)
                        .map(|q| {
                            let s = e.s[0] + (e.s[1] - e.s[0]) * (q as f64 + 0.5) / samples as f64;
                            rep.zeta(s, els[i].s_mid)
                        })
                        .sum();
                    row[j] = sum / samples as f64 * e.length * inverse[e.mesh_edge];
                }
            },
            &never,
        )
        .unwrap();
        let slow = solve_operator(&brute, &mesh, &params, &never).unwrap();
        let e = solve_errors(&mesh, &fast.radiosity, &slow.radiosity);
        assert!(e.rel_l2_reflected < 1e-3, "{e:?}");
    }
}

#[test]
fn representations_of_zeta_refuse_zero_source_weights_and_other_scenes() {
    let scene = bundled("fig3");
    let kernel = Kernel::with_params(
        scene.clone(),
        KernelParams {
            emission_floor: 0.0,
        },
    )
    .unwrap();
    let mesh = Mesh::new(&kernel, 64).unwrap();
    let grid = UniformGrid::build(&kernel, 4, &UniformParams::default(), 1).unwrap();
    let err = solve(&grid, &mesh, &SolveParams::default(), &never)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("surface edge 0 has source weight E' = 0"),
        "{err}"
    );
    // The exact kernel needs no E'.
    assert!(solve(&kernel, &mesh, &SolveParams::default(), &never).is_ok());
    // A mesh of another scene.
    let other = Mesh::new(&Kernel::new(bundled("box")), 64).unwrap();
    let err = solve(&kernel, &other, &SolveParams::default(), &never)
        .unwrap_err()
        .to_string();
    assert!(err.contains("fingerprint"), "{err}");
    // Stop.
    let err = solve(&kernel, &mesh, &SolveParams::default(), &|| true).unwrap_err();
    assert!(matches!(err, SolveError::Interrupted), "{err}");
    let bad = SolveParams {
        tolerance: 0.0,
        ..SolveParams::default()
    };
    assert!(
        solve(&kernel, &mesh, &bad, &never)
            .unwrap_err()
            .to_string()
            .contains("tolerance")
    );
}
