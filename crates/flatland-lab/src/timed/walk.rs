//! Relighting a moving lamp (`flatland bench --relight`): generated floor plans and halls lit
//! by one lamp carried along a walk through their rooms and doors (their own lamps off, no
//! emitting edge), every method relighting the scene at each position ([`Mover`]): the exact
//! re-solve at several tolerances, clustered HR (its links built once, re-solved per move with
//! the new source), the tracer given the exact re-solve's time at each move, and the learned
//! transport of the later bounces (built on the exact re-solve's operator). Each position is scored against a full, cold, independent exact solve
//! there ([`cold_solve`]), whose own time is the row the re-solves are measured against.
//!
//! The methods run in lockstep, position by position, so that one cold solve at a time is held
//! (a walk of 200 positions at 10⁵ edges would hold gigabytes of them).

mod movers;

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use flatland_baselines::ClusteredParams;
use flatland_geom::generate::{GenerateParams, SceneKind, generate_lit};
use flatland_geom::{Kernel, PointLight, Scene, WalkParams, walk};
use flatland_solve::{
    DEFAULT_ELEMENTS, Mesh, RelightParams, Relighter, SolveError, SolveErrors, SolveParams, Stop,
    WarmStart, cold_solve,
};
use flatland_transport::TransportParams;

pub use movers::{
    ClusteredMover, ExactMover, Moved, Mover, ProbeMover, TracerMover, TransportMover,
};

use super::Method;

/// Positions of a walk by default.
pub const POSITIONS: usize = 200;

/// The sizes (edges asked of the generator) measured by default; 10⁵ only when asked.
pub const DEFAULT_SIZES: [usize; 2] = [1_000, 10_000];

/// The exact re-solve's tolerances, one row each: the curve of its error against its time.
/// The first is the default ([`RelightParams::default`]), whose time per move the tracer is
/// given.
pub const EXACT_TOLERANCES: [f64; 4] = [1e-6, 1e-2, 1e-4, 1e-8];

/// The methods a relighting bench can run. The probe grid is given the transport's bytes, so
/// it runs after (and only with) the transport.
pub const METHODS: [Method; 5] = [
    Method::Exact,
    Method::Clustered,
    Method::Tracer,
    Method::Transport,
    Method::Probes,
];

/// What a relighting bench measures.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkPlan {
    /// Kinds of generated scene.
    pub kinds: Vec<SceneKind>,
    /// Sizes, in edges asked of the generator, ascending.
    pub sizes: Vec<usize>,
    /// The generator's seed (no default of the project was chosen on it).
    pub seed: u64,
    /// Positions of the lamp's walk.
    pub positions: usize,
    /// The walk's seed.
    pub walk_seed: u64,
    /// Methods, of [`METHODS`]; the exact re-solve always runs (the cold solves use its
    /// operator).
    pub methods: Vec<Method>,
    /// Clustered HR's parameters.
    pub clustered: ClusteredParams,
}

impl WalkPlan {
    /// Floor plans and halls of [`DEFAULT_SIZES`], every method, [`POSITIONS`] positions.
    pub fn new() -> WalkPlan {
        WalkPlan {
            kinds: vec![SceneKind::FloorPlan, SceneKind::Hall],
            sizes: DEFAULT_SIZES.to_vec(),
            seed: 2024,
            positions: POSITIONS,
            walk_seed: 7,
            methods: METHODS.to_vec(),
            clustered: ClusteredParams::default(),
        }
    }

    /// Checks the plan; errors name the parameter and the valid range.
    pub fn validate(&self) -> Result<(), crate::LabError> {
        let bad = |name, value: String, valid| {
            Err(crate::LabError::InvalidParameter { name, value, valid })
        };
        if self.kinds.is_empty() {
            return bad("kinds", "(none)".into(), "floorplan, hall or both");
        }
        if self.sizes.is_empty() || !self.sizes.windows(2).all(|w| w[0] < w[1]) {
            let sizes = format!("{:?}", self.sizes);
            return bad("sizes", sizes, "at least one, ascending without repeats");
        }
        if let Some(&size) = self.sizes.iter().find(|&&edges| {
            let params = GenerateParams {
                kind: self.kinds[0],
                edges,
                seed: self.seed,
            };
            params.check().is_err()
        }) {
            return bad("sizes", size.to_string(), "each in [24, 1000000]");
        }
        if !(1..=flatland_geom::MAX_POSITIONS).contains(&self.positions) {
            let positions = self.positions.to_string();
            return bad("positions", positions, "in [1, 1000000]");
        }
        if let Some(m) = self.methods.iter().find(|m| !METHODS.contains(m)) {
            let valid = "a comma-separated list of exact, clustered, tracer, transport, probes";
            return bad("methods", m.name().to_owned(), valid);
        }
        if self.methods.contains(&Method::Probes) && !self.methods.contains(&Method::Transport) {
            let valid = "with transport too: the probe grid is given the transport's bytes";
            return bad("methods", "probes without transport".to_owned(), valid);
        }
        Ok(())
    }
}

impl Default for WalkPlan {
    fn default() -> Self {
        WalkPlan::new()
    }
}

/// Elements of a relighting mesh of `scene`: four per section, at least [`DEFAULT_ELEMENTS`]
/// — what `flatland solve` chooses for a 1 % error of `B − E` on the generated plans and halls
/// (39 168 elements for 9 792 edges, 40 088 for 10 022).
#[must_use]
pub fn relight_elements(scene: &Scene) -> usize {
    (4 * Mesh::min_elements(scene)).max(DEFAULT_ELEMENTS)
}

/// A lamp of `power` carried along a walk of `positions` through `kernel`'s scene from `seed`
/// ([`walk`]): one move per position, each the one light.
pub fn lamp_moves(
    kernel: &Kernel,
    positions: usize,
    seed: u64,
    power: f64,
) -> Result<Vec<Vec<PointLight>>> {
    let walked = walk(kernel, &WalkParams::new(positions, seed))?;
    let moves = walked.positions.iter();
    Ok(moves.map(|&at| vec![PointLight::new(at, power)]).collect())
}

/// What one method did at one move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveRecord {
    /// Seconds the move took.
    pub seconds: f64,
    /// Its work (products with K, photons).
    pub work: u64,
    /// Its errors against the cold exact solve there, when checked.
    pub errors: Option<SolveErrors>,
}

/// A method's figures over a walk.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WalkFigures {
    /// Positions relit.
    pub positions: usize,
    /// Milliseconds per move: the median.
    pub ms_median: f64,
    /// The 95th percentile (nearest rank).
    pub ms_p95: f64,
    /// The mean work per move.
    pub work_mean: f64,
    /// Relative L2 error of B, mean over the positions checked.
    pub rel_l2_b_mean: Option<f64>,
    /// Its largest.
    pub rel_l2_b_max: Option<f64>,
    /// Relative L2 error of the indirect part `B − B₀` (B minus the lights' direct light and
    /// the emission), mean over the positions checked.
    pub rel_l2_indirect_mean: Option<f64>,
}

impl WalkFigures {
    /// The figures of `records` (errors over the records that have them).
    #[must_use]
    pub fn of(records: &[MoveRecord]) -> WalkFigures {
        let mut ms: Vec<f64> = records.iter().map(|r| 1e3 * r.seconds).collect();
        ms.sort_by(f64::total_cmp);
        let errors: Vec<SolveErrors> = records.iter().filter_map(|r| r.errors).collect();
        let mean = |f: fn(&SolveErrors) -> f64| {
            (!errors.is_empty()).then(|| errors.iter().map(f).sum::<f64>() / errors.len() as f64)
        };
        let max_b = errors.iter().map(|e| e.rel_l2_b).reduce(f64::max);
        let work = records.iter().map(|r| r.work as f64).sum::<f64>();
        WalkFigures {
            positions: records.len(),
            ms_median: nearest_rank(&ms, 0.5),
            ms_p95: nearest_rank(&ms, 0.95),
            work_mean: work / records.len().max(1) as f64,
            rel_l2_b_mean: mean(|e| e.rel_l2_b),
            rel_l2_b_max: max_b,
            rel_l2_indirect_mean: mean(|e| e.rel_l2_reflected),
        }
    }
}

/// The `q`-quantile of `sorted` by nearest rank (0 for none).
fn nearest_rank(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Relights `moves` one after another with `mover` (any method of `kernel`'s scene), timing
/// each [`Mover::relight`] alone; with `check`, each move against a cold exact solve there
/// ([`cold_solve`] with `exact`'s operator, not timed). `each(k, B)` sees every move's B (to
/// write it, not timed). Ends early when `stop` says so, with the moves done: their records,
/// and `true`.
pub fn relight_moves(
    mover: &mut dyn Mover,
    exact: &Relighter,
    kernel: &Kernel,
    moves: &[Vec<PointLight>],
    check: bool,
    stop: &Stop,
    mut each: impl FnMut(usize, &[f64]) -> Result<()>,
) -> Result<(Vec<MoveRecord>, bool)> {
    let mut records = Vec::with_capacity(moves.len());
    for (k, lights) in moves.iter().enumerate() {
        let errors = if check && !stop() {
            let solve = SolveParams::default();
            match cold_solve(
                kernel,
                exact.rows(),
                exact.mesh().len(),
                lights,
                &solve,
                stop,
            ) {
                Ok(cold) => Some(cold),
                Err(SolveError::Interrupted) => return Ok((records, true)),
                Err(e) => return Err(e).with_context(|| format!("the cold solve of move {k}")),
            }
        } else {
            None
        };
        if stop() {
            return Ok((records, true));
        }
        let started = Instant::now();
        let moved = match mover.relight(lights, 0.0, stop) {
            Ok(moved) => moved,
            Err(e) if interrupted(&e) => return Ok((records, true)),
            Err(e) => return Err(e.context(format!("move {k}"))),
        };
        let seconds = started.elapsed().as_secs_f64();
        records.push(MoveRecord {
            seconds,
            work: moved.work,
            errors: errors.map(|cold| cold.errors(moved.radiosity)),
        });
        each(k, moved.radiosity)?;
    }
    Ok((records, false))
}

/// Whether a mover's error is its stop flag's.
fn interrupted(e: &anyhow::Error) -> bool {
    matches!(e.downcast_ref(), Some(SolveError::Interrupted))
        || matches!(
            e.downcast_ref(),
            Some(flatland_transport::TransportError::Interrupted)
        )
}

/// One method on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkRow {
    /// The scene: `floorplan-10000`, the kind and the size asked for.
    pub scene: String,
    /// Its edges.
    pub edges: usize,
    /// Elements of the mesh.
    pub elements: usize,
    /// The method.
    pub method: Method,
    /// What it ran at, in words.
    pub setting: String,
    /// Seconds of its set-up.
    pub setup_s: f64,
    /// Bytes it held.
    pub bytes: usize,
    /// Its figures over the walk.
    pub figures: WalkFigures,
    /// Why it has no figures, or what else to know.
    pub note: String,
}

/// The setting of the cold solve's row.
pub const COLD: &str = "cold: from B0 to 1e-10";

/// After how many moves `row`'s set-up has paid for itself against a cold solve at every
/// position (`cold`, the same scene's [`COLD`] row): its set-up beyond the cold solve's (the
/// operator, which the cold solve needs too) over what a move saves, by the median ms per
/// move. `Some(1)` when nothing is set up beyond the operator; `None` when a move saves
/// nothing or the row was not measured.
#[must_use]
pub fn payoff_moves(row: &WalkRow, cold: &WalkRow) -> Option<u64> {
    if row.figures.positions == 0 || cold.figures.positions == 0 {
        return None;
    }
    let saved_s = 1e-3 * (cold.figures.ms_median - row.figures.ms_median);
    if saved_s <= 0.0 {
        return None;
    }
    let extra_s = (row.setup_s - cold.setup_s).max(0.0);
    Some(((extra_s / saved_s).ceil() as u64).max(1))
}

/// The [`COLD`] row of `scene` among `rows`.
#[must_use]
pub fn cold_row<'r>(rows: &'r [WalkRow], scene: &str) -> Option<&'r WalkRow> {
    rows.iter().find(|r| r.scene == scene && r.setting == COLD)
}

/// Runs the plan: per scene, every method along the walk; `progress` gets a line per stage,
/// `kept` the rows so far after each scene. Ctrl-C (`stop`) ends the walk at the position it
/// is at, with the positions done kept in the rows.
pub fn run_walks(
    plan: &WalkPlan,
    stop: &Stop,
    mut progress: impl FnMut(&str),
    mut kept: impl FnMut(&[WalkRow]) -> Result<()>,
) -> Result<Vec<WalkRow>> {
    plan.validate()?;
    let mut rows = Vec::new();
    for &kind in &plan.kinds {
        for &size in &plan.sizes {
            let kind_name = match kind {
                SceneKind::FloorPlan => "floorplan",
                SceneKind::Hall => "hall",
            };
            let name = format!("{kind_name}-{size}");
            let scene = generate_lit(&GenerateParams {
                kind,
                edges: size,
                seed: plan.seed,
            })
            .with_context(|| format!("generating {name}"))?;
            rows.extend(scene_rows(plan, &name, scene, stop, &mut progress)?);
            kept(&rows)?;
            if stop() {
                return Ok(rows);
            }
        }
    }
    Ok(rows)
}

/// What one scene's walk is measured with.
struct Walking<'k> {
    name: &'k str,
    kernel: &'k Arc<Kernel>,
    mesh: &'k Mesh,
}

impl Walking<'_> {
    fn row(&self, method: Method, setting: String, setup_s: f64, bytes: usize) -> WalkRow {
        WalkRow {
            scene: self.name.to_owned(),
            edges: self.kernel.scene().edges().len(),
            elements: self.mesh.len(),
            method,
            setting,
            setup_s,
            bytes,
            figures: WalkFigures::default(),
            note: String::new(),
        }
    }
}

/// Every method of `plan` along one walk through `scene`.
fn scene_rows(
    plan: &WalkPlan,
    name: &str,
    scene: Scene,
    stop: &Stop,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<WalkRow>> {
    let power = scene.lights().first().map_or(1.0, |l| l.power);
    let kernel = Arc::new(Kernel::new(scene));
    let mesh = Mesh::new(&kernel, relight_elements(kernel.scene()))?;
    let cx = Walking {
        name,
        kernel: &kernel,
        mesh: &mesh,
    };
    let moves = lamp_moves(&kernel, plan.positions, plan.walk_seed, power)?;
    progress(&format!(
        "{name}: {} edges, {} elements, a lamp of power {power} along {} positions; setting up",
        kernel.scene().edges().len(),
        mesh.len(),
        moves.len()
    ));
    let params = |tolerance| RelightParams {
        tolerance,
        warm_start: WarmStart::LaterBounces,
        ..RelightParams::default()
    };
    let first = ExactMover::new(&kernel, &mesh, params(EXACT_TOLERANCES[0]), stop)?;
    let mut exact = vec![];
    for &tolerance in &EXACT_TOLERANCES[1..] {
        exact.push(first.with_params(params(tolerance))?);
    }
    exact.insert(0, first);
    let (mut others, mut rows) = baselines(plan, &cx, &exact[0], stop);
    let records = walk_all(&moves, &mut exact, &mut others, &cx, stop, progress)?;
    let mut movers: Vec<&dyn Mover> = exact.iter().map(|m| m as &dyn Mover).collect();
    movers.extend(others.iter().map(|m| m.as_ref() as &dyn Mover));
    let mut measured = Vec::new();
    let relighter = exact[0].relighter();
    let mut cold = cx.row(
        Method::Exact,
        COLD.to_owned(),
        relighter.setup_s(),
        relighter.rows().memory_bytes(),
    );
    cold.figures = WalkFigures::of(&records[0]);
    measured.push(cold);
    for (mover, records) in movers.iter().zip(&records[1..]) {
        let mut row = cx.row(
            mover.method(),
            mover.setting(),
            mover.setup_s(),
            mover.bytes(),
        );
        row.figures = WalkFigures::of(records);
        measured.push(row);
    }
    measured.append(&mut rows);
    Ok(measured)
}

/// The baselines `plan` asks for, built; a row for each that failed or is not built yet.
fn baselines<'k>(
    plan: &WalkPlan,
    cx: &Walking<'k>,
    exact: &ExactMover,
    stop: &Stop,
) -> (Vec<Box<dyn Mover + 'k>>, Vec<WalkRow>) {
    let mut movers: Vec<Box<dyn Mover + 'k>> = Vec::new();
    let mut rows = Vec::new();
    // The transport's bytes, which the probe grid is given.
    let mut transport_bytes = None;
    // On the exact movers' operator (shared, not built again), at the default tolerance.
    let relighter = || exact.relighter().with_params(RelightParams::default());
    for &method in &plan.methods {
        let built: Result<Box<dyn Mover + 'k>> = match method {
            Method::Clustered => {
                let links =
                    flatland_baselines::DEFAULT_LINKS_PER_EDGE * cx.kernel.scene().edges().len();
                ClusteredMover::new(cx.kernel, cx.mesh, links, &plan.clustered, stop)
                    .map(|m| Box::new(m) as Box<dyn Mover + 'k>)
            }
            Method::Tracer => {
                TracerMover::new(cx.kernel, cx.mesh, 1).map(|m| Box::new(m) as Box<dyn Mover + 'k>)
            }
            Method::Transport => relighter()
                .map_err(anyhow::Error::from)
                .and_then(|r| {
                    TransportMover::build(cx.kernel, r, &TransportParams::default(), stop)
                })
                .map(|m| {
                    transport_bytes = Some(flatland_transport::LaterBounces::bytes(
                        m.relit().transport(),
                    ));
                    Box::new(m) as Box<dyn Mover + 'k>
                }),
            Method::Probes => match transport_bytes {
                Some(budget) => relighter()
                    .map_err(anyhow::Error::from)
                    .and_then(|r| ProbeMover::build(cx.kernel, r, budget, stop))
                    .map(|m| Box::new(m) as Box<dyn Mover + 'k>),
                None => Err(anyhow::anyhow!(
                    "no probe grid: it is given the transport's bytes, and the transport was \
                     not built"
                )),
            },
            _ => continue,
        };
        match built {
            Ok(mover) => movers.push(mover),
            Err(e) => {
                let mut row = cx.row(method, String::new(), 0.0, 0);
                row.note = format!("{e:#}");
                rows.push(row);
            }
        }
    }
    (movers, rows)
}

/// Every move: the cold solve, then each method, in lockstep. The records per method, the
/// cold solve's first (its errors are 0 by definition, so none are kept), then the exact
/// movers', then the others'. Ends early, with what is done, when `stop` says so.
fn walk_all(
    moves: &[Vec<PointLight>],
    exact: &mut [ExactMover],
    others: &mut [Box<dyn Mover + '_>],
    cx: &Walking<'_>,
    stop: &Stop,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<Vec<MoveRecord>>> {
    let mut records = vec![Vec::new(); 1 + exact.len() + others.len()];
    for (k, lights) in moves.iter().enumerate() {
        if stop() {
            progress(&format!("{}: stopped after {k} positions", cx.name));
            break;
        }
        let rows = exact[0].relighter().rows();
        let solve = SolveParams::default();
        let cold = cold_solve(cx.kernel, rows, cx.mesh.len(), lights, &solve, stop)?;
        records[0].push(MoveRecord {
            seconds: cold.solution.solve_s,
            // Its Krylov steps, the first residual and the one that confirms it.
            work: cold.solution.iterations as u64 + 2,
            errors: None,
        });
        let mut budget_s = 0.0;
        let all = exact
            .iter_mut()
            .map(|m| m as &mut dyn Mover)
            .chain(others.iter_mut().map(|m| m.as_mut() as &mut dyn Mover));
        for (slot, mover) in all.enumerate() {
            let started = Instant::now();
            let moved = mover.relight(lights, budget_s, stop)?;
            let seconds = started.elapsed().as_secs_f64();
            if slot == 0 {
                budget_s = seconds;
            }
            records[1 + slot].push(MoveRecord {
                seconds,
                work: moved.work,
                errors: Some(cold.errors(moved.radiosity)),
            });
        }
        if (k + 1) % 50 == 0 {
            progress(&format!(
                "{}: {} of {} positions",
                cx.name,
                k + 1,
                moves.len()
            ));
        }
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_solve::never;

    #[test]
    fn a_small_walk_gives_a_row_per_method_and_the_exact_rows_match_the_cold_solve() {
        let plan = WalkPlan {
            kinds: vec![SceneKind::FloorPlan],
            sizes: vec![100],
            positions: 6,
            ..WalkPlan::new()
        };
        let mut lines = Vec::new();
        let rows = run_walks(&plan, &never, |l| lines.push(l.to_owned()), |_| Ok(())).unwrap();
        let labels: Vec<(Method, &str)> = rows
            .iter()
            .map(|r| (r.method, r.setting.as_str()))
            .collect();
        assert_eq!(labels[0], (Method::Exact, COLD));
        assert_eq!(labels[1], (Method::Exact, "tolerance 1e-6"));
        assert_eq!(labels.len(), 1 + EXACT_TOLERANCES.len() + 4, "{labels:?}");
        // No edge of a lamp-lit plan emits; clustered HR weighs its senders by the lamps'
        // light (E', docs/ALGORITHM.md §2), so it builds links and relights like the others.
        let clustered = rows.iter().find(|r| r.method == Method::Clustered).unwrap();
        assert!(clustered.note.is_empty(), "{clustered:?}");
        assert!(clustered.setting.ends_with(" links"), "{clustered:?}");
        // The learned transport: within the bounds (2 % of B, 5 % of the indirect part).
        let transport = rows.iter().find(|r| r.method == Method::Transport).unwrap();
        assert!(transport.note.is_empty(), "{}", transport.note);
        assert!(
            transport.figures.rel_l2_b_mean.unwrap() < 0.02,
            "{transport:?}"
        );
        assert!(
            transport.figures.rel_l2_indirect_mean.unwrap() < 0.05,
            "{transport:?}"
        );
        // The probe grid holds about the transport's bytes for the later bounces (its grid's
        // spacing is chosen from a sample of probes) and answers every move.
        let probes = rows.iter().find(|r| r.method == Method::Probes).unwrap();
        assert!(probes.note.is_empty(), "{}", probes.note);
        assert!(probes.setting.contains(" probes "), "{probes:?}");
        for row in &rows {
            assert_eq!(row.figures.positions, 6, "{row:?}");
            assert!(row.figures.ms_p95 >= row.figures.ms_median);
        }
        // The exact re-solve at 1e-6 is within a few 1e-6 of the cold solve, B and indirect.
        let exact = &rows[1].figures;
        assert!(exact.rel_l2_b_max.unwrap() < 1e-5, "{exact:?}");
        assert!(exact.rel_l2_indirect_mean.unwrap() < 1e-5, "{exact:?}");
        // Looser tolerances are less accurate, and every error is finite.
        let loose = rows.iter().find(|r| r.setting == "tolerance 1e-2").unwrap();
        assert!(loose.figures.rel_l2_b_mean.unwrap() > exact.rel_l2_b_mean.unwrap());
        assert!(
            rows.iter()
                .all(|r| r.figures.rel_l2_b_mean.is_none_or(f64::is_finite))
        );
        assert!(lines[0].starts_with("floorplan-100: "), "{lines:?}");
    }

    #[test]
    fn a_set_up_pays_off_after_its_extra_seconds_over_the_milliseconds_a_move_saves() {
        let row = |setting: &str, setup_s, ms_median| WalkRow {
            scene: "hall-100".into(),
            edges: 97,
            elements: 512,
            method: Method::Transport,
            setting: setting.into(),
            setup_s,
            bytes: 0,
            figures: WalkFigures {
                positions: 4,
                ms_median,
                ..WalkFigures::default()
            },
            note: String::new(),
        };
        let cold = row(COLD, 2.0, 50.0);
        let rows = [cold.clone(), row("t", 6.0, 10.0)];
        assert_eq!(cold_row(&rows, "hall-100"), Some(&cold));
        assert_eq!(cold_row(&rows, "hall-1000"), None);
        // 4 s more than the operator, 40 ms saved a move: 100 moves.
        assert_eq!(payoff_moves(&rows[1], &cold), Some(100));
        // 4.01 s: the 101st move.
        assert_eq!(payoff_moves(&row("t", 6.01, 10.0), &cold), Some(101));
        // Nothing beyond the operator: the first move; slower than cold: never.
        assert_eq!(payoff_moves(&row("t", 1.0, 10.0), &cold), Some(1));
        assert_eq!(payoff_moves(&row("t", 1.0, 60.0), &cold), None);
    }

    #[test]
    fn quantiles_by_nearest_rank_and_bad_plans_named() {
        let sorted: Vec<f64> = (1..=200).map(f64::from).collect();
        assert_eq!(nearest_rank(&sorted, 0.5), 100.0);
        assert_eq!(nearest_rank(&sorted, 0.95), 190.0);
        assert_eq!(nearest_rank(&[3.0], 0.95), 3.0);
        assert_eq!(nearest_rank(&[], 0.5), 0.0);
        let bad = WalkPlan {
            methods: vec![Method::Hr],
            ..WalkPlan::new()
        };
        let err = bad.validate().unwrap_err().to_string();
        assert!(
            err.contains("hr") && err.contains("exact, clustered"),
            "{err}"
        );
        let bad = WalkPlan {
            methods: vec![Method::Exact, Method::Probes],
            ..WalkPlan::new()
        };
        let err = bad.validate().unwrap_err().to_string();
        assert!(err.contains("transport's bytes"), "{err}");
        let bad = WalkPlan {
            positions: 0,
            ..WalkPlan::new()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("positions")
        );
    }
}
