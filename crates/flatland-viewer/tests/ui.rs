//! Headless UI tests (egui_kittest, no rendering, no display): the real app state and learner
//! thread, driven through its widgets where they exist.
//!
//! The learner is another thread, so a test never sleeps and then asserts: it runs frames until
//! a condition on what the learner published holds, blocking on the learner's next publication
//! in between, with a generous deadline for a loaded machine. "Nothing happens" is checked by a
//! round trip: after [`ViewerApp::sync`], the learner's next status is made after every earlier
//! command, so if it still shows the same steps, the learner did not train meanwhile.

use std::time::{Duration, Instant};

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use flatland_geom::DVec2;
use flatland_viewer::{Learner, Options, Progress, Settings, ViewerApp};
use kernel_fit::ModelFile;
use kernel_fit::{Gating, StopReason, Target};
use sgcs::Insertion;

/// Longest wait for one condition; reached only if something is broken.
const DEADLINE: Duration = Duration::from_secs(120);

/// Small, quick settings: fig3, the visibility network, few held-out points, a small S₀,
/// growth as fast as it goes.
fn quick_settings() -> Settings {
    let mut s = Settings::default();
    s.choose_learner(Learner::Visibility);
    s.scene = flatland_viewer::SceneChoice::Bundled("fig3".into());
    s.params.heldout = 256;
    s.params.initial_samples = 200;
    s.params.eval_every = 500;
    s.params.target_cells = 60;
    s.unlimited = true;
    s
}

fn harness_of(app: ViewerApp) -> Harness<'static, ViewerApp> {
    Harness::builder()
        .with_size([1280.0, 1500.0])
        .build_ui_state(|ui, app: &mut ViewerApp| app.show(ui), app)
}

/// The app as the tests drive it: paused until they press Play or Step.
fn harness(settings: Settings) -> Harness<'static, ViewerApp> {
    harness_of(ViewerApp::headless(egui::Context::default(), settings))
}

/// Runs frames until `cond` holds, waiting on the learner's publications in between.
fn wait_until(
    h: &mut Harness<'_, ViewerApp>,
    what: &str,
    cond: impl Fn(&Harness<'_, ViewerApp>) -> bool,
) {
    let deadline = Instant::now() + DEADLINE;
    loop {
        h.run_steps(1);
        if cond(h) {
            return;
        }
        let left = deadline.saturating_duration_since(Instant::now());
        assert!(
            !left.is_zero(),
            "timed out after {DEADLINE:?} waiting for {what}"
        );
        h.state().wait_for_learner(left.min(Duration::from_secs(1)));
    }
}

/// [`wait_until`] on the app's state.
fn wait_for(h: &mut Harness<'_, ViewerApp>, what: &str, cond: impl Fn(&ViewerApp) -> bool) {
    wait_until(h, what, |h| cond(h.state()));
}

/// The learner's state once it has handled everything sent so far.
fn settled(h: &mut Harness<'_, ViewerApp>) -> (u64, usize) {
    h.state_mut().sync();
    wait_for(h, "the learner to catch up", ViewerApp::caught_up);
    (h.state().steps(), h.state().cells())
}

fn ready(app: &ViewerApp) -> bool {
    app.world_id() > 0 && app.reference_scene() == Some(app.scene())
}

#[test]
fn the_viewer_starts_learning_at_once_and_pause_is_one_click_away() {
    // What `cargo run --release` and `flatland view` do: default options. Many target cells
    // on the maze, so the fit is still growing whenever a loaded machine gets to look (on fig3
    // the visibility network is exact after a few dozen cells and stops).
    let mut settings = quick_settings();
    settings.params.target_cells = 5000;
    settings.scene = flatland_viewer::SceneChoice::Bundled("maze".into());
    let app = ViewerApp::with_options(egui::Context::default(), settings, &Options::default());
    let mut h = harness_of(app);
    wait_for(&mut h, "cells to grow without a click", |a| {
        a.running() && a.cells() > 10
    });
    h.get_by_label("Pause").click();
    wait_for(&mut h, "the pause", |a| a.caught_up() && !a.running());
    let paused = settled(&mut h);
    assert_eq!(settled(&mut h), paused, "no training while paused");
    h.get_by_label("Play");
}

#[test]
fn step_play_and_pause() {
    let mut settings = quick_settings();
    settings.params.target_cells = 5000; // still training when the test looks
    settings.scene = flatland_viewer::SceneChoice::Bundled("maze".into());
    let mut h = harness(settings);
    wait_for(&mut h, "the reference", ready);
    assert_eq!(settled(&mut h).0, 0, "the tests' app starts paused");
    assert_eq!(h.state().scene_label(), "maze");

    h.state_mut().settings_mut().step_size = 100;
    h.get_by_label("Step").click();
    wait_for(&mut h, "100 steps", |a| a.steps() == 100);
    assert_eq!(
        settled(&mut h).0,
        100,
        "Step trains exactly step-size steps"
    );

    h.get_by_label("Play").click();
    wait_for(&mut h, "training", |a| a.running() && a.steps() > 1000);
    h.get_by_label("Pause").click();
    wait_for(&mut h, "the pause", |a| a.caught_up() && !a.running());
    let (paused_at, cells) = settled(&mut h);
    assert_eq!(settled(&mut h).0, paused_at, "no training while paused");
    assert!(cells > 3, "cells grew: {cells}");
}

#[test]
fn a_parameter_changed_in_the_panel_reaches_the_learner() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    h.get_by_role_and_label(Role::SpinButton, "target cells")
        .set_value_accesskit(12.0);
    h.run_steps(2);
    assert_eq!(h.state().settings().params.target_cells, 12);
    h.get_by_label("Play").click();
    wait_for(&mut h, "the fit to stop at the target", |a| {
        !a.running() && a.cells() == 12
    });
    // The refit runs after the stop; the line says so once its errors are in.
    wait_until(&mut h, "the final errors in the status line", |h| {
        h.query_by_label_contains("stopped: target cell count reached; final rel. L2")
            .is_some()
    });
    assert!(h.state().final_errors().is_some());
    assert_eq!(settled(&mut h).1, 12, "growth stopped at the new target");

    // An out-of-range value typed in is clamped to the valid range by the widget.
    h.get_by_role_and_label(Role::SpinButton, "ψ")
        .set_value_accesskit(5.0);
    h.run_steps(2);
    assert_eq!(h.state().settings().params.psi, 1.0);
}

/// A scene where nothing emits: its relative errors are 0/0, shown as "undefined", not 0.
#[test]
fn errors_against_a_dark_scene_read_undefined() {
    let mut settings = quick_settings();
    settings.params.target_cells = 8;
    let mut h = harness(settings);
    wait_for(&mut h, "the reference", ready);
    let path =
        std::env::temp_dir().join(format!("flatland-viewer-dark-{}.ron", std::process::id()));
    std::fs::write(
        &path,
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5), (a: (1, 0), b: (1, 1), reflectance: \
         0.5), (a: (1, 1), b: (0, 1), reflectance: 0.5), (a: (0, 1), b: (0, 0), reflectance: 0.5)])",
    )
    .unwrap();
    h.state_mut().open_file(&path);
    let _ = std::fs::remove_file(&path);
    wait_for(&mut h, "the dark scene's reference", ready);
    h.get_by_label("Play").click();
    wait_until(&mut h, "the final errors", |h| {
        h.query_by_label_contains("final rel. L2 of ζ: grid undefined, held out undefined")
            .is_some()
    });
}

#[test]
fn picking_another_scene_starts_a_fresh_fit_on_it() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    h.state_mut().settings_mut().step_size = 500;
    h.get_by_label("Step").click();
    wait_for(&mut h, "some steps", |a| a.steps() == 500);
    let fig3_id = h.state().world_id();

    h.get_by_label("maze").click();
    wait_for(&mut h, "the maze reference", |a| {
        a.world_id() > fig3_id && ready(a)
    });
    let app = h.state();
    assert_eq!(app.scene_label(), "maze");
    let maze = flatland_geom::bundled::scene("maze").unwrap();
    assert_eq!(app.reference_scene().unwrap().edges(), maze.edges());
    wait_for(&mut h, "a fresh snapshot", |a| {
        a.steps() == 0 && a.cells() == 3
    });
}

#[test]
fn a_bad_scene_file_is_reported_and_the_scene_kept() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    let path = std::env::temp_dir().join(format!("flatland-viewer-bad-{}.ron", std::process::id()));
    std::fs::write(
        &path,
        "(edges: [(a: (0.0, 0.0), b: (0.0, 0.0), reflectance: 0.5)])",
    )
    .unwrap();
    h.state_mut().open_file(&path);
    h.run_steps(2);
    let _ = std::fs::remove_file(&path);
    let app = h.state();
    assert_eq!(app.scene_label(), "fig3");
    let (message, is_error) = app.message().expect("a message");
    assert!(
        is_error && message.contains("could not open") && message.contains("edge 0"),
        "{message}"
    );
    h.get_by_label_contains("could not open");
}

#[test]
fn moving_the_blocker_keeps_learning_from_the_current_network() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    h.state_mut().settings_mut().step_size = 3000;
    h.get_by_label("Step").click();
    wait_for(&mut h, "3000 steps", |a| a.steps() == 3000);
    let (cells, id) = (h.state().cells(), h.state().world_id());
    assert!(cells > 3);

    let (from, to) = (DVec2::new(1.2, 1.7), DVec2::new(1.0, 2.0));
    h.state_mut().move_point(from, to);
    wait_for(&mut h, "the new reference", |a| {
        a.world_id() > id && ready(a)
    });
    let app = h.state();
    assert!(app.scene_label().ends_with("(edited)"));
    assert!(
        app.reference_scene()
            .unwrap()
            .edges()
            .iter()
            .any(|e| e.a == to)
    );
    assert_eq!(app.steps(), 3000, "the network was kept, not restarted");
    assert_eq!(app.cells(), cells);

    h.get_by_label("Step").click();
    wait_for(&mut h, "more steps", |a| a.steps() == 6000);
}

#[test]
fn switching_learners_starts_a_new_fit_with_that_learner() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    settled(&mut h);
    let fit = h.state().fit_params().expect("a running fit");
    assert_eq!(fit.target, Target::Visibility, "the visibility network");
    assert_eq!(h.state().settings().learner, Learner::Visibility);
    let visibility_world = h.state().world_id();

    h.get_by_label("paper's network").click();
    wait_for(&mut h, "a fresh fit of the paper's network", |a| {
        a.world_id() > visibility_world
            && a.caught_up()
            && a.fit_params().is_some_and(|p| p.target == Target::Zeta)
    });
    let app = h.state();
    assert_eq!(app.settings().learner, Learner::Paper);
    let fit = app.fit_params().unwrap();
    assert_eq!(fit.gating, Gating::Off);
    assert_eq!(fit.network, sgcs::Params::default(), "the paper's network");
    assert_eq!(fit.target_cells, 60, "the run's target cells are kept");
    assert_eq!((app.steps(), app.occupied_faces()), (0, None));
    // Its lit scene: the quadrature operator on fewer elements.
    wait_for(&mut h, "the paper network's lit scene", |a| {
        a.lit().is_some_and(|l| {
            l.setup.world == a.world_id()
                && l.setup.mesh().len() == flatland_viewer::lit::NETWORK_ELEMENTS
        })
    });

    let paper_world = h.state().world_id();
    h.get_by_label("visibility network").click();
    wait_for(&mut h, "a fresh fit of the visibility network", |a| {
        a.world_id() > paper_world
            && a.caught_up()
            && a.fit_params()
                .is_some_and(|p| p.target == Target::Visibility && p.gating == Gating::Faces)
    });
    assert_eq!(h.state().settings().learner, Learner::Visibility);
    assert!(h.state().settings().is_preset());

    // The light-driven learner, and back: the visibility network as it was.
    let visibility_world = h.state().world_id();
    h.get_by_label("light-driven learner").click();
    h.get_by_label("Step").click();
    wait_for(&mut h, "a round of the light-driven learner", |a| {
        a.world_id() > visibility_world
            && a.caught_up()
            && a.shown().is_some_and(|m| round_of(m) == Some(1))
    });
    assert_eq!(h.state().settings().learner, Learner::Light);
    assert_eq!(h.state().fit_learner(), Learner::Light);
    assert!(!h.state().running(), "a step is one round");
    let light_world = h.state().world_id();
    h.get_by_label("visibility network").click();
    wait_for(&mut h, "the visibility network again", |a| {
        a.world_id() > light_world
            && a.caught_up()
            && a.shown()
                .is_some_and(|m| matches!(m.status.growth.progress, Progress::Steps { .. }))
    });
    assert_eq!(h.state().settings().learner, Learner::Visibility);
    assert_eq!(h.state().fit_params().unwrap().target, Target::Visibility);
}

/// A live parameter (a rate of the network) reaches the running fit; a fixed one (a rule of
/// the network, what it learns) starts a new fit with it, and what only the visibility learner
/// has goes when the target changes.
#[test]
fn live_options_reach_the_running_fit_and_the_others_start_a_new_one() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    settled(&mut h);
    let world = h.state().world_id();

    h.get_by_role_and_label(Role::SpinButton, "η")
        .set_value_accesskit(0.05);
    wait_for(&mut h, "η in the running fit", |a| {
        a.caught_up() && a.fit_params().is_some_and(|p| p.network.eta == 0.05)
    });
    assert_eq!(h.state().world_id(), world, "no new fit for a live option");
    h.get_by_label("(changed)");

    h.get_by_label("midpoint").click();
    wait_for(&mut h, "a new fit with midpoint insertion", |a| {
        a.world_id() > world
            && a.caught_up()
            && a.fit_params()
                .is_some_and(|p| p.network.insertion == Insertion::Midpoint)
    });
    let world = h.state().world_id();
    let fit = h.state().fit_params().unwrap();
    assert_eq!((fit.network.eta, fit.target), (0.05, Target::Visibility));

    h.get_by_label("ζ").click();
    wait_for(&mut h, "a new fit learning ζ", |a| {
        a.world_id() > world
            && a.caught_up()
            && a.fit_params().is_some_and(|p| p.target == Target::Zeta)
    });
    let fit = h.state().fit_params().unwrap();
    assert_eq!(
        (fit.gating, fit.importance, fit.weighted, fit.refit),
        (Gating::Off, 0.0, false, true),
        "the paper's learner of ζ, without what only the visibility learner has"
    );
    assert_eq!(fit.network.insertion, Insertion::Midpoint, "kept");
    assert!(h.state().message().is_none(), "{:?}", h.state().message());
}

#[test]
fn the_lit_scene_publishes_b_and_its_error_while_the_cells_grow() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    wait_for(&mut h, "the lit scene of the first cells", |a| {
        a.lit().is_some_and(|l| l.setup.world == a.world_id())
    });
    let first = h.state().lit().unwrap();
    let (elements, start_error) = (
        first.setup.mesh().len(),
        first.solve.errors.rel_l2_reflected,
    );
    assert_eq!(first.solve.b.len(), elements);
    assert_eq!(first.setup.exact().len(), elements);
    assert!(first.solve.b.iter().all(|b| b.is_finite()));
    assert!(
        start_error.is_finite() && start_error > 0.05,
        "three cells do not know the shadows yet: {start_error}"
    );

    // fig3: the visibility network finds every face it needs and stops, converged; the lit
    // scene follows it to the exact solution (up to the mesh: 512 elements against 2048).
    h.get_by_label("Play").click();
    wait_for(&mut h, "convergence", |a| {
        a.stopped() == Some(StopReason::Converged)
    });
    wait_for(&mut h, "the converged model's lit scene", |a| {
        a.lit().is_some_and(|l| l.steps == a.steps())
    });
    let app = h.state();
    let last = app.lit().unwrap();
    assert!(
        last.solve.errors.rel_l2_reflected < 1e-3,
        "{:?}",
        last.solve.errors
    );
    assert!(last.history.len() >= 2, "{:?}", last.history);
    assert_eq!(last.history[0].rel_l2_reflected, start_error);
    assert!(app.occupied_faces().is_some_and(|f| f > 0));
    h.get_by_label_contains(" faces  samples");
    h.get_by_label_contains("solved B−E");
    wait_until(&mut h, "the stop in words", |h| {
        h.query_by_label_contains("stopped: converged").is_some()
    });
}

#[test]
fn a_scene_without_occluders_is_exact_at_once() {
    let mut settings = quick_settings();
    settings.scene = flatland_viewer::SceneChoice::Bundled("box".into());
    let mut h = harness(settings);
    wait_for(&mut h, "the reference", ready);
    wait_for(&mut h, "the stop before any step", |a| {
        a.stopped() == Some(StopReason::Exact) && a.final_errors().is_some()
    });
    let errors = h.state().final_errors().unwrap();
    assert!(errors.grid < 1e-12 && errors.heldout < 1e-12, "{errors:?}");
    wait_until(&mut h, "the stop in words", |h| {
        h.query_by_label_contains("stopped: exact").is_some()
    });
    // Play changes nothing, and a parameter change does not wake it.
    h.get_by_role_and_label(Role::SpinButton, "target cells")
        .set_value_accesskit(30.0);
    h.get_by_label("Play").click();
    assert_eq!(settled(&mut h).0, 0);
    assert_eq!(h.state().stopped(), Some(StopReason::Exact));
    wait_for(&mut h, "the lit scene", |a| a.lit().is_some());
    let lit = h.state().lit().unwrap();
    assert!(
        lit.solve.errors.rel_l2_reflected < 1e-3,
        "{:?}",
        lit.solve.errors
    );
}

/// A fresh folder for one test's files.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("flatland-viewer-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn the_first_launch_grows_a_floor_plan_at_the_pace_not_at_the_machines_speed() {
    // The defaults of a first launch (the floor plan, 20 cells per second) with the visibility
    // network chosen, and a smaller held-out set so the reference is quick.
    let mut settings = Settings::default();
    settings.choose_learner(Learner::Visibility);
    settings.params.heldout = 256;
    assert!(!settings.unlimited);
    let pace = settings.growth;
    let app = ViewerApp::with_options(egui::Context::default(), settings, &Options::default());
    assert_eq!(app.scene_label(), flatland_viewer::scenes::DEFAULT);
    let mut h = harness_of(app);
    wait_for(&mut h, "cells to grow without a click", |a| {
        a.running() && a.cells() > 12
    });
    // Every moment so far: no more cells than the pace allows (3 to start, one at once, a
    // second's credit saved up), however fast the machine is.
    for p in 0..h.state().moments() {
        h.state_mut().scrub_to(p);
        let m = h.state().shown().unwrap();
        let allowed = 3.0 + 1.0 + pace * (m.at().as_secs_f64() + 1.0);
        assert!(
            m.cells() as f64 <= allowed,
            "{} cells after {:?} of training at {pace} cells/s",
            m.cells(),
            m.at()
        );
    }
    assert!(h.state().stopped().is_none(), "still growing");
}

/// The light-driven learner's round of the moment shown, if it is the one learning.
fn round_of(m: &flatland_viewer::Moment) -> Option<u64> {
    match m.status.growth.progress {
        Progress::Rounds { .. } => Some(m.steps()),
        Progress::Steps { .. } => None,
    }
}

#[test]
fn the_light_learner_publishes_rounds_its_cells_grow_and_the_timeline_scrubs_to_round_1() {
    // A first launch: the light-driven learner on the floor plan, revealing each round's cells
    // over time (a smaller held-out set so the reference is quick).
    let mut settings = Settings::default();
    settings.params.heldout = 256;
    assert_eq!(settings.learner, Learner::Light);
    let app = ViewerApp::with_options(egui::Context::default(), settings, &Options::default());
    let mut h = harness_of(app);
    h.get_by_label("light-driven learner");
    wait_for(&mut h, "three rounds without a click", |a| {
        a.running() && a.lit().is_some_and(|l| l.steps >= 3)
    });
    let app = h.state();
    let lit = app.lit().unwrap();
    assert!(app.cells() > 100, "{} cells", app.cells());
    // Probes sweep whole views: the light-driven learner casts no ray.
    assert_eq!(app.rays(), 0);
    // One point per round on the error curves: the measured B − E and the learner's estimate.
    assert!(lit.history.len() >= 3, "{:?}", lit.history);
    assert!(lit.history.iter().all(|p| p.estimated.is_some()));
    assert!(
        lit.history.windows(2).all(|p| p[0].steps < p[1].steps),
        "{:?}",
        lit.history
    );
    let last = lit.history.last().unwrap();
    assert!(
        last.rel_l2_reflected < lit.history[0].rel_l2_reflected,
        "the lit scene converges: {:?}",
        lit.history
    );

    // Every moment: cells only grow, and the lit B changes from one round to the next.
    let mut cells = 0;
    let mut by_round: Vec<(u64, Vec<f64>)> = Vec::new();
    let mut round_1 = None;
    for p in 0..app.moments() {
        let m = app.timeline().get(p).unwrap();
        assert!(m.cells() >= cells, "cells shrank at moment {p}");
        cells = m.cells();
        if round_1.is_none() && round_of(m) == Some(1) {
            round_1 = Some(p);
        }
        if let Some(l) = &m.lit
            && by_round.last().is_none_or(|(r, _)| *r != l.steps)
        {
            by_round.push((l.steps, l.solve.b.clone()));
        }
    }
    assert!(cells > app.timeline().get(0).unwrap().cells(), "cells grew");
    assert!(by_round.len() >= 2, "{} rounds lit", by_round.len());
    assert!(
        by_round.windows(2).all(|p| p[0].1 != p[1].1),
        "the lit B changes between rounds"
    );

    // The timeline back to round 1: its cells (fewer than now) and its lit scene.
    let round_1 = round_1.expect("a moment of round 1");
    h.get_by_role_and_label(Role::Slider, "timeline")
        .set_value_accesskit(round_1 as f64);
    h.run_steps(2);
    let app = h.state();
    assert!(!app.is_live());
    let shown = app.shown().unwrap();
    assert_eq!(round_of(shown), Some(1));
    assert!(shown.cells() < app.cells(), "an earlier state");
    assert_eq!(shown.lit.as_ref().map(|l| l.steps), Some(1));
    assert!(
        shown.status.growth.cells.iter().all(|c| !c.seen.is_empty()),
        "one cell per probe, each with what it sees"
    );
    h.get_by_label("Live").click();
    h.run_steps(1);
    assert!(h.state().is_live());
}

#[test]
fn scrubbing_the_timeline_shows_an_earlier_state_and_live_returns() {
    let mut settings = quick_settings();
    settings.params.target_cells = 5000; // still growing while the test looks
    settings.scene = flatland_viewer::SceneChoice::Bundled("maze".into());
    let mut h = harness(settings);
    wait_for(&mut h, "the reference", ready);
    h.get_by_label("Play").click();
    wait_for(&mut h, "growth over several moments", |a| {
        a.cells() > 20 && a.moments() > 8
    });
    assert!(h.state().is_live());
    let live_cells = h.state().shown().unwrap().cells();

    // To the start: the first cells, step 0, and the label says which moment.
    h.get_by_role_and_label(Role::Slider, "timeline")
        .set_value_accesskit(0.0);
    h.run_steps(2);
    let app = h.state();
    assert!(!app.is_live());
    assert_eq!(app.shown_position(), Some(0));
    let first = app.shown().unwrap();
    assert_eq!((first.steps(), first.cells()), (0, 3), "the first cells");
    assert!(
        first.status.growth.cells.iter().all(|c| c.st.is_some()),
        "drawn where they are, before they have won a sample"
    );
    assert!(app.cells() >= live_cells, "the learner went on meanwhile");
    h.get_by_label_contains("moment 1/");

    // Halfway: an earlier state than live, later than the start.
    let half = h.state().moments() / 2;
    h.get_by_role_and_label(Role::Slider, "timeline")
        .set_value_accesskit(half as f64);
    h.run_steps(2);
    let mid = h.state().shown().unwrap();
    assert!(
        mid.steps() > 0 && mid.steps() < h.state().steps(),
        "{}",
        mid.steps()
    );

    // Live follows the learner again.
    h.get_by_label("Live").click();
    h.run_steps(1);
    assert!(h.state().is_live());
    wait_for(&mut h, "the newest moment", |a| {
        a.shown().is_some_and(|m| m.steps() == a.steps())
    });

    // Replay at ×8 from the start walks forward through the moments, then goes live (the
    // learner paused, so the replay has an end to reach on a slow machine too).
    h.get_by_label("Pause").click();
    wait_for(&mut h, "the pause", |a| a.caught_up() && !a.running());
    h.state_mut().scrub_to(0);
    h.get_by_label("×8").click();
    h.get_by_label("Replay").click();
    h.run_steps(1);
    assert!(h.state().replaying());
    // Forward in training time at every frame, until it reaches the newest moment.
    let deadline = Instant::now() + DEADLINE;
    let mut last = std::time::Duration::ZERO;
    while h.state().replaying() {
        h.run_steps(1);
        let at = h.state().shown().unwrap().at();
        assert!(at >= last, "{at:?} after {last:?}");
        last = at;
        assert!(Instant::now() < deadline, "the replay never ended");
    }
    assert!(h.state().is_live());
    assert!(!h.state().replaying());
}

#[test]
fn the_edges_overlay_can_be_switched_off_and_only_joins_cells_of_one_face() {
    // The visibility network's S₀ and cells on fig3: some faces end up with more than one cell.
    let mut settings = quick_settings();
    settings.params.initial_samples = Settings::default().params.initial_samples;
    settings.params.target_cells = Settings::default().params.target_cells;
    let mut h = harness(settings);
    wait_for(&mut h, "the reference", ready);
    // Grown to the end: early on every cell has a face of its own, later some faces get more.
    h.state_mut().settings_mut().step_size = 30_000;
    h.get_by_label("Step").click();
    wait_for(&mut h, "the fit to stop", |a| {
        a.stopped().is_some() && a.caught_up() && a.shown().is_some_and(|m| m.steps() == a.steps())
    });
    let m = h.state().shown().unwrap();
    let growth = &m.status.growth;
    assert!(
        !growth.face_edges.is_empty(),
        "cells of one face are joined"
    );
    assert!(h.state().settings().show_edges);

    h.get_by_label("network edges within a face").click();
    h.run_steps(2);
    assert!(!h.state().settings().show_edges, "edges off");
    assert!(h.state().settings().show_cells, "cells stay");
    h.get_by_label_contains("cells (size ~ δ_c").click();
    h.run_steps(2);
    assert!(!h.state().settings().show_cells);
    h.get_by_label("network edges within a face").click();
    h.run_steps(2);
    assert!(h.state().settings().show_edges, "edges on again");
}

#[test]
fn the_view_and_the_model_are_saved_named_after_scene_learner_and_step() {
    let dir = temp_dir("export");
    let options = Options {
        paused: true,
        export_dir: Some(dir.clone()),
        ..Options::default()
    };
    // The visibility network (its S₀ too), so the files are named after it.
    let mut settings = quick_settings();
    settings.params.initial_samples = Settings::default().params.initial_samples;
    let app = ViewerApp::with_options(egui::Context::default(), settings, &options);
    let mut h = harness_of(app);
    wait_for(&mut h, "the reference", ready);
    h.state_mut().settings_mut().step_size = 500;
    h.get_by_label("Step").click();
    wait_for(&mut h, "500 steps", |a| a.steps() == 500 && a.caught_up());
    wait_for(&mut h, "the moment of step 500", |a| {
        a.shown().is_some_and(|m| m.steps() == 500)
    });

    // The view: the app asks egui for a screenshot; the harness has no renderer, so the test
    // answers it with a picture, as eframe does with the window's pixels.
    h.get_by_label("Save view").click();
    let mut answered = false;
    for _ in 0..5 {
        h.run_steps(1);
        for command in h
            .output()
            .viewport_output
            .values()
            .flat_map(|v| v.commands.iter())
        {
            if let egui::ViewportCommand::Screenshot(callback) = command {
                let image = egui::ColorImage::filled([8, 6], egui::Color32::from_rgb(1, 2, 3));
                callback.clone().complete(std::sync::Arc::new(image));
                answered = true;
            }
        }
        if answered {
            break;
        }
    }
    assert!(answered, "Save view asks for a screenshot");
    let png = dir.join("fig3-visibility-step500.png");
    wait_until(&mut h, "the PNG", |h| {
        h.state()
            .message()
            .is_some_and(|(m, _)| m.starts_with("saved the view"))
    });
    let back = image::open(&png)
        .unwrap_or_else(|e| panic!("{e}: {:?}", h.state().message()))
        .to_rgba8();
    assert_eq!(back.dimensions(), (8, 6));

    // The model: the running fit, as `flatland eval` reads it.
    h.get_by_label("Save model").click();
    wait_until(&mut h, "the model file", |h| {
        h.state()
            .message()
            .is_some_and(|(m, _)| m.starts_with("saved the model"))
    });
    let model = ModelFile::load(&dir.join("fig3-visibility-step500.model.json")).unwrap();
    assert_eq!(model.model.network().len(), h.state().cells());
    let fig3 = flatland_geom::bundled::scene("fig3").unwrap();
    model
        .check_scene(&fig3, std::path::Path::new("fig3"))
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

/// A file dropped on the window, as the windowing backend hands it to egui.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

/// Drops `path` on the window and runs the frame that takes it.
fn drop_file(h: &mut Harness<'_, ViewerApp>, path: &std::path::Path) {
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(path.to_path_buf())));
    h.run_steps(1);
}

/// A drawing of the repository's `scenes/svg/`.
fn svg_scene(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/svg")
        .join(name)
}

#[test]
fn an_svg_drawing_opens_from_the_file_box_and_dropped_on_the_window() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    let fig3_world = h.state().world_id();

    // The file box: the drawing's path typed in, then Open.
    let floorplan = svg_scene("floorplan.svg");
    // The scene file box: the text input whose hint names scene files (it is empty).
    let file_box = egui_kittest::kittest::by()
        .role(Role::TextInput)
        .predicate(|node| {
            node.placeholder()
                .is_some_and(|p| p.starts_with("scene file"))
        });
    h.get(file_box)
        .set_text_value_accesskit(&floorplan.display().to_string());
    h.run_steps(1);
    h.get_by_label("Open").click();
    wait_for(&mut h, "the drawing's reference", |a| {
        a.world_id() > fig3_world && ready(a)
    });
    let drawing =
        flatland_svg::import_file(&floorplan, &flatland_svg::ImportParams::default()).unwrap();
    let warnings = drawing.warnings().len();
    let imported = drawing.into_scene().unwrap();
    let app = h.state();
    assert_eq!(app.scene_label(), "floorplan.svg");
    assert_eq!(app.scene(), &imported);
    assert_eq!(app.reference_scene().unwrap().edges(), imported.edges());
    assert_eq!(
        app.message().is_some(),
        warnings > 0,
        "its warnings, if any, on the message line: {:?}",
        app.message()
    );
    assert_eq!(
        app.settings().scene,
        flatland_viewer::SceneChoice::File(floorplan.clone()),
        "remembered"
    );
    let floorplan_world = app.world_id();

    // Dropped on the window: a drawing with something the import skips, said on the message
    // line and listed under the scene.
    let dir = temp_dir("svg");
    let room = dir.join("room.svg");
    std::fs::write(
        &room,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 4 3">
  <rect width="4" height="3" fill="none" stroke="black" data-flatland-faces="in"/>
  <line x1="1" y1="2.9" x2="3" y2="2.9" stroke="gold" data-flatland-emission="1"
        data-flatland-faces="left"/>
  <rect x="1.5" y="1" width="1" height="1"/>
  <text x="0.5" y="0.5">kitchen</text>
</svg>"#,
    )
    .unwrap();
    drop_file(&mut h, &room);
    wait_for(&mut h, "the dropped drawing's reference", |a| {
        a.world_id() > floorplan_world && ready(a)
    });
    let app = h.state();
    assert_eq!(app.scene_label(), "room.svg");
    assert_eq!(app.scene().edges().len(), 4 + 1 + 4);
    let (message, is_error) = app.message().expect("the import's warning");
    assert!(
        !is_error && message.contains("room.svg") && message.contains("text is not geometry"),
        "{message}"
    );
    h.get_by_label_contains("text is not geometry");
    h.get_by_label("1 import warning");
    let room_world = h.state().world_id();

    // A drawing that does not import: reported, the scene kept.
    let broken = dir.join("broken.svg");
    std::fs::write(&broken, "<svg xmlns=\"http://www.w3.org/2000/svg\"><rect").unwrap();
    drop_file(&mut h, &broken);
    h.run_steps(2);
    let app = h.state();
    let (message, is_error) = app.message().expect("why it did not open");
    assert!(
        is_error && message.contains("could not open") && message.contains("broken.svg"),
        "{message}"
    );
    assert!(message.contains("(kept room.svg)"), "{message}");
    assert_eq!(
        (app.scene_label(), app.world_id()),
        ("room.svg", room_world)
    );
    h.get_by_label_contains("could not open");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_learner_named_on_the_command_line_runs_and_names_the_exports() {
    let dir = temp_dir("learner");
    let options = Options {
        paused: true,
        learner: Some(Learner::parse("paper").unwrap()),
        export_dir: Some(dir.clone()),
        ..Options::default()
    };
    let mut settings = quick_settings();
    settings.choose_learner(Learner::Light);
    let app = ViewerApp::with_options(egui::Context::default(), settings, &options);
    let mut h = harness_of(app);
    wait_for(&mut h, "the paper's network", |a| {
        ready(a) && a.caught_up() && a.fit_params().is_some_and(|p| p.target == Target::Zeta)
    });
    assert_eq!(h.state().settings().learner, Learner::Paper);
    assert_eq!(h.state().fit_learner(), Learner::Paper);
    h.get_by_label_contains("paper's network (ζ)");
    h.get_by_label("Save model").click();
    wait_until(&mut h, "the model file", |h| {
        h.state()
            .message()
            .is_some_and(|(m, _)| m.starts_with("saved the model"))
    });
    assert!(dir.join("fig3-paper-step0.model.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// [`wait_until`] on the app's state, waiting on the relighting thread in between.
fn wait_relit(h: &mut Harness<'_, ViewerApp>, what: &str, cond: impl Fn(&ViewerApp) -> bool) {
    let deadline = Instant::now() + DEADLINE;
    loop {
        h.run_steps(1);
        if cond(h.state()) {
            return;
        }
        let left = deadline.saturating_duration_since(Instant::now());
        assert!(
            !left.is_zero(),
            "timed out after {DEADLINE:?} waiting for {what}"
        );
        h.state().wait_for_relit(left.min(Duration::from_secs(1)));
    }
}

fn button(pos: egui::Pos2, button: egui::PointerButton, pressed: bool) -> egui::Event {
    egui::Event::PointerButton {
        pos,
        button,
        pressed,
        modifiers: Default::default(),
    }
}

#[test]
fn a_dragged_light_follows_the_pointer_b_follows_it_and_a_right_click_deletes_it() {
    let mut settings = quick_settings();
    settings.wander = false;
    let mut h = harness(settings);
    wait_relit(&mut h, "the first relit B and its light's mark", |a| {
        a.relit().is_some_and(|f| f.lights.len() == 1) && a.light_marks().len() == 1
    });
    let first_b = h.state().relit().unwrap().b.clone();
    let from = h.state().lights()[0].at;
    let p = h.state().light_marks()[0];
    h.event(egui::Event::PointerMoved(p));
    h.run_steps(1);
    h.event(button(p, egui::PointerButton::Primary, true));
    h.run_steps(1);
    for k in 1..=4 {
        h.event(egui::Event::PointerMoved(
            p + egui::vec2(-3.0 * k as f32, -2.0 * k as f32),
        ));
        h.run_steps(1);
    }
    h.event(button(
        p + egui::vec2(-12.0, -8.0),
        egui::PointerButton::Primary,
        false,
    ));
    wait_relit(&mut h, "B lit by the light where it was dragged", |a| {
        let at = a.lights()[0].at;
        at != from && a.relit().is_some_and(|f| f.lights[0].at == at)
    });
    let to = h.state().lights()[0].at;
    assert!(to.x < from.x && to.y > from.y, "left and up: {from} → {to}");
    assert_ne!(h.state().relit().unwrap().b, first_b, "B follows the light");
    let p = h.state().light_marks()[0];
    h.event(egui::Event::PointerMoved(p));
    h.run_steps(1);
    h.event(button(p, egui::PointerButton::Secondary, true));
    h.run_steps(1);
    h.event(button(p, egui::PointerButton::Secondary, false));
    wait_relit(&mut h, "B without the deleted light", |a| {
        a.lights().is_empty() && a.relit().is_some_and(|f| f.lights.is_empty())
    });
    assert_ne!(h.state().relit().unwrap().b, first_b);
}

#[test]
fn on_first_launch_the_light_wanders_by_itself() {
    let mut h = harness(quick_settings());
    assert!(h.state().settings().wander, "on by default");
    wait_relit(&mut h, "the first relit B", |a| a.relit().is_some());
    let start = h.state().relit().unwrap().lights[0].at;
    wait_relit(&mut h, "B lit by the light somewhere else", |a| {
        a.relit().is_some_and(|f| f.lights[0].at != start)
    });
}
