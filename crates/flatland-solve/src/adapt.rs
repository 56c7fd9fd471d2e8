//! A mesh chosen for a tolerance: rounds of [`FunctionSolve`] on meshes refined where its
//! estimate says the error of B as a function is, until the estimate meets the tolerance.

use std::time::Instant;

use flatland_geom::{Kernel, Scene};
use serde::{Deserialize, Serialize};

use crate::{
    DEFAULT_ELEMENTS, FUNCTION_SAFETY, FunctionSolve, MAX_MESH_ELEMENTS, MAX_NONZEROS, Mesh,
    SolveError, SolveParams, Stop, predicted_nonzeros,
};

/// What [`solve_to_tolerance`] is asked for, checked by [`ToleranceParams::check`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ToleranceParams {
    /// The relative L2 error of `B − E` as a function the estimate must meet. Valid: (0, 1).
    pub tolerance: f64,
    /// Most rounds (solve, estimate, refine). Valid: ≥ 1.
    pub max_rounds: usize,
    /// Most elements of the solve (its finer solve has three times as many). Valid: ≥ 1.
    pub max_elements: usize,
    /// Elements of the first round's mesh (spread evenly by length); `None`:
    /// [`initial_elements`].
    pub initial_elements: Option<usize>,
    /// Most non-zero numbers the finer solve's sparse operator may hold: a refinement
    /// predicted to pass it ([`predicted_nonzeros`]) is not made and the last round stands.
    /// Valid: 1 to [`MAX_NONZEROS`] (what a sparse operator can hold at all).
    pub max_nonzeros: usize,
}

impl Default for ToleranceParams {
    fn default() -> Self {
        ToleranceParams {
            tolerance: 0.01,
            max_rounds: 8,
            max_elements: MAX_MESH_ELEMENTS / 3,
            initial_elements: None,
            max_nonzeros: MAX_NONZEROS,
        }
    }
}

impl ToleranceParams {
    /// Checks every field; the error names it and its valid range.
    pub fn check(&self) -> Result<(), SolveError> {
        let bad =
            |name, value: String, valid| Err(SolveError::InvalidParameter { name, value, valid });
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("tolerance", self.tolerance.to_string(), "in (0, 1)");
        }
        if self.max_rounds == 0 {
            return bad("max_rounds", "0".into(), "at least 1");
        }
        if self.max_elements == 0 {
            return bad("max_elements", "0".into(), "at least 1");
        }
        if self.max_nonzeros == 0 || self.max_nonzeros > MAX_NONZEROS {
            return bad(
                "max_nonzeros",
                self.max_nonzeros.to_string(),
                "1 to 268435456 (2²⁸, what a sparse operator holds)",
            );
        }
        Ok(())
    }
}

/// One round: the mesh solved and what its estimate said.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefinementRound {
    /// Elements of its mesh.
    pub elements: usize,
    /// Its estimated error of `B − E` as a function.
    pub estimate: f64,
    /// Seconds it took (both solves, the gather and the estimate).
    pub seconds: f64,
}

/// The last round's solve and every round's figures.
#[derive(Clone, Debug)]
pub struct ToleranceSolve {
    /// The last round's solve, its function and estimate.
    pub solve: FunctionSolve,
    /// Every round, in order.
    pub rounds: Vec<RefinementRound>,
}

/// The first round's element count for `scene`: two per section of a surface edge, at least
/// [`DEFAULT_ELEMENTS`].
#[must_use]
pub fn initial_elements(scene: &Scene) -> usize {
    (2 * Mesh::min_elements(scene)).max(DEFAULT_ELEMENTS)
}

/// Rounds of [`FunctionSolve`] from an even mesh, each refining the last where its estimate
/// put the error ([`refine_for`]), until the estimate is within `params.tolerance`, the
/// rounds run out or the next mesh would exceed `params.max_elements` or its operator
/// `params.max_nonzeros` (predicted before it is built): the last round is returned, its
/// estimate saying by how much it misses.
pub fn solve_to_tolerance(
    kernel: &Kernel,
    params: &ToleranceParams,
    solve: &SolveParams,
    stop: &Stop,
) -> Result<ToleranceSolve, SolveError> {
    params.check()?;
    let start = params
        .initial_elements
        .unwrap_or_else(|| initial_elements(kernel.scene()));
    let mut mesh = Mesh::new(
        kernel,
        start
            .min(params.max_elements)
            .max(Mesh::min_elements(kernel.scene())),
    )?;
    let mut rounds = Vec::new();
    loop {
        let started = Instant::now();
        let solved = FunctionSolve::new(kernel, mesh, solve, stop)?;
        rounds.push(RefinementRound {
            elements: solved.coarse.mesh().len(),
            estimate: solved.estimate.estimate,
            seconds: started.elapsed().as_secs_f64(),
        });
        if solved.estimate.estimate <= params.tolerance || rounds.len() >= params.max_rounds {
            return Ok(ToleranceSolve {
                solve: solved,
                rounds,
            });
        }
        // A refinement past every mesh's limit (`Mesh::split` refuses it), past the element
        // budget, or whose finer operator would pass the sparse operator's limit is past the
        // budget: the last round stands.
        let current = solved.coarse.mesh().len();
        match refine_for(
            kernel,
            solved.coarse.mesh(),
            &solved.indicators,
            params.tolerance,
        ) {
            Ok(next)
                if next.len() <= params.max_elements
                    && next.len() > current
                    && predicted_nonzeros(solved.nonzeros, current, next.len())
                        <= params.max_nonzeros =>
            {
                mesh = next;
            }
            _ => {
                return Ok(ToleranceSolve {
                    solve: solved,
                    rounds,
                });
            }
        }
    }
}

/// How far below the tolerance the refinement aims, so one round usually suffices.
const AIM: f64 = 0.7;

/// Most pieces one round cuts an element into.
const MOST_PIECES: usize = 4;

/// `mesh` with each element cut into as many equal pieces as its share of the estimate asks:
/// the tolerance spread over the surfaces by length (`‖e‖² ≤ (AIM · tolerance)²` when each
/// element's share is at most its length's share of it), and a piece's share taken to fall
/// with the square of the count (the local error of B near a corner falls about as `h`).
pub fn refine_for(
    kernel: &Kernel,
    mesh: &Mesh,
    indicators: &[f64],
    tolerance: f64,
) -> Result<Mesh, SolveError> {
    let total = mesh.total_length();
    let allowed = (AIM * tolerance / FUNCTION_SAFETY).powi(2);
    let parts: Vec<usize> = mesh
        .elements()
        .iter()
        .zip(indicators)
        .map(|(e, &share)| {
            let budget = allowed * e.length / total;
            let ratio = (share / budget).sqrt();
            if ratio <= 1.0 {
                1
            } else {
                (ratio.ceil() as usize).clamp(2, MOST_PIECES)
            }
        })
        .collect();
    mesh.split(kernel, &parts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, floor_plan};
    use crate::{SamplePoints, never};

    #[test]
    fn tolerance_params_are_checked_one_by_one() {
        assert!(ToleranceParams::default().check().is_ok());
        for (params, name) in [
            (
                ToleranceParams {
                    tolerance: 0.0,
                    ..Default::default()
                },
                "tolerance",
            ),
            (
                ToleranceParams {
                    tolerance: f64::NAN,
                    ..Default::default()
                },
                "tolerance",
            ),
            (
                ToleranceParams {
                    max_rounds: 0,
                    ..Default::default()
                },
                "max_rounds",
            ),
            (
                ToleranceParams {
                    max_elements: 0,
                    ..Default::default()
                },
                "max_elements",
            ),
            (
                ToleranceParams {
                    max_nonzeros: MAX_NONZEROS + 1,
                    ..Default::default()
                },
                "max_nonzeros",
            ),
        ] {
            let err = params.check().unwrap_err().to_string();
            assert!(err.contains(name), "{err}");
        }
    }

    #[test]
    fn rounds_refine_where_the_error_is_until_the_tolerance_is_met() {
        // From one element per section of a floor plan: each round's mesh refines the last,
        // more where the error was, and the last meets the tolerance, which a solve 16 times
        // finer confirms.
        let kernel = Kernel::new(floor_plan(300));
        let params = ToleranceParams {
            initial_elements: Some(Mesh::min_elements(kernel.scene())),
            ..ToleranceParams::default()
        };
        let solve = SolveParams::default();
        let done = solve_to_tolerance(&kernel, &params, &solve, &never).unwrap();
        let rounds = &done.rounds;
        println!("{rounds:?}");
        assert!(rounds.len() >= 2, "{rounds:?}");
        assert!(rounds.windows(2).all(|w| w[0].elements < w[1].elements));
        let last = done.solve.estimate.estimate;
        assert!(last <= params.tolerance, "{last}");
        assert_eq!(rounds.last().unwrap().estimate, last);
        // Adapted, not doubled: the first mesh's elements were cut into unequal numbers.
        let mesh = done.solve.coarse.mesh();
        let first = Mesh::new(&kernel, rounds[0].elements).unwrap();
        let pieces: Vec<usize> = first
            .elements()
            .iter()
            .map(|e| {
                let inside = |f: &&crate::Element| f.s[0] >= e.s[0] && f.s[1] <= e.s[1];
                mesh.elements().iter().filter(inside).count()
            })
            .collect();
        assert_eq!(pieces.iter().sum::<usize>(), mesh.len());
        let (fewest, most) = (pieces.iter().min().unwrap(), pieces.iter().max().unwrap());
        assert!(*fewest == 1 && *most >= 8, "{fewest}..{most}");
        let finer = mesh.split(&kernel, &vec![16; mesh.len()]).unwrap();
        let reference = crate::ExactReference::on_mesh(&kernel, finer, &solve, &never).unwrap();
        let points = SamplePoints::evenly(mesh, 8);
        let exact = reference.radiosity_at(&points.s, &never).unwrap();
        let error = points
            .relative_l2_reflected(&done.solve.radiosity_at(&points.s, &never).unwrap(), &exact);
        println!("error {error:.2e}, estimate {last:.2e}");
        assert!(
            error <= params.tolerance && last / error > 1.0,
            "{error} {last}"
        );
    }

    #[test]
    fn refinement_cuts_only_the_elements_over_their_share() {
        let kernel = Kernel::new(bundled("maze"));
        let mesh = Mesh::new(&kernel, 100).unwrap();
        let allowed = (AIM * 0.01 / FUNCTION_SAFETY).powi(2) / mesh.total_length();
        // Element i's share: none, just within its budget, twice its square root, far over.
        let mut shares = vec![0.0; 100];
        let budget = |i: usize| allowed * mesh.elements()[i].length;
        shares[10] = 0.99 * budget(10);
        shares[20] = 3.9 * budget(20);
        shares[30] = 1e6 * budget(30);
        let refined = refine_for(&kernel, &mesh, &shares, 0.01).unwrap();
        assert_eq!(refined.len(), 100 + 1 + MOST_PIECES - 1);
        let count = |i: usize| {
            let e = &mesh.elements()[i];
            refined
                .elements()
                .iter()
                .filter(|f| f.s[0] >= e.s[0] && f.s[1] <= e.s[1])
                .count()
        };
        assert_eq!(
            [count(0), count(10), count(20), count(30)],
            [1, 1, 2, MOST_PIECES]
        );
        assert_eq!(
            refine_for(&kernel, &mesh, &[0.0; 100], 0.01).unwrap().len(),
            100
        );
    }

    #[test]
    fn a_budget_too_small_returns_the_last_mesh_that_fits() {
        let kernel = Kernel::new(floor_plan(300));
        let start = Mesh::min_elements(kernel.scene());
        let params = ToleranceParams {
            tolerance: 1e-4,
            initial_elements: Some(start),
            max_elements: start + start / 4,
            ..ToleranceParams::default()
        };
        let done = solve_to_tolerance(&kernel, &params, &SolveParams::default(), &never).unwrap();
        assert!(done.solve.coarse.mesh().len() <= params.max_elements);
        assert!(done.solve.estimate.estimate > params.tolerance);
        let stopped = solve_to_tolerance(&kernel, &params, &SolveParams::default(), &|| true);
        assert!(matches!(stopped, Err(SolveError::Interrupted)));
    }

    #[test]
    fn a_refinement_whose_operator_would_pass_the_limit_is_not_made() {
        // The lamp-lit plan asks for a second round at 1 %; with room for only the first
        // round's operator, the first round stands, its estimate saying by how much it misses.
        let kernel = Kernel::new(flatland_geom::generate::floor_plan_lit(300, 11).unwrap());
        let params = ToleranceParams {
            initial_elements: Some(300),
            ..Default::default()
        };
        let free = solve_to_tolerance(&kernel, &params, &SolveParams::default(), &never).unwrap();
        assert!(free.rounds.len() > 1, "{:?}", free.rounds);
        let first = free.rounds[0];
        let held = ToleranceParams {
            max_nonzeros: first_round_nonzeros(&kernel, 300) + 1,
            ..params
        };
        let stopped = solve_to_tolerance(&kernel, &held, &SolveParams::default(), &never).unwrap();
        assert_eq!(stopped.rounds.len(), 1);
        assert_eq!(stopped.rounds[0].elements, first.elements);
        assert!(stopped.solve.estimate.estimate > params.tolerance);
        assert!(stopped.solve.nonzeros < held.max_nonzeros);
        assert_eq!(predicted_nonzeros(100, 10, 20), 400);
    }

    fn first_round_nonzeros(kernel: &Kernel, elements: usize) -> usize {
        let mesh = Mesh::new(kernel, elements).unwrap();
        FunctionSolve::new(kernel, mesh, &SolveParams::default(), &never)
            .unwrap()
            .nonzeros
    }
}
