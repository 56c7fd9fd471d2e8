//! Headless UI tests (egui_kittest, no rendering, no display): the real app state and learner
//! thread, driven through its widgets where they exist.

use std::time::{Duration, Instant};

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use flatland_geom::DVec2;
use flatland_viewer::{Settings, ViewerApp};

/// Small, quick settings: few held-out points, a small S₀.
fn quick_settings() -> Settings {
    let mut s = Settings::default();
    s.params.heldout = 256;
    s.params.initial_samples = 200;
    s.params.eval_every = 500;
    s.params.target_cells = 60;
    s.unlimited = true;
    s
}

fn harness(settings: Settings) -> Harness<'static, ViewerApp> {
    let app = ViewerApp::headless(egui::Context::default(), settings);
    Harness::builder()
        .with_size([1280.0, 1500.0])
        .build_ui_state(|ui, app: &mut ViewerApp| app.show(ui), app)
}

/// Runs frames until `cond` holds (the learner is another thread), failing after 60 s.
fn wait_for(h: &mut Harness<'_, ViewerApp>, what: &str, cond: impl Fn(&ViewerApp) -> bool) {
    let start = Instant::now();
    h.run_steps(1);
    while !cond(h.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(5));
        h.run_steps(1);
    }
}

fn ready(app: &ViewerApp) -> bool {
    app.world_id() > 0 && app.reference_scene() == Some(app.scene())
}

#[test]
fn step_play_and_pause() {
    let mut h = harness(quick_settings());
    wait_for(&mut h, "the reference", ready);
    assert_eq!(h.state().steps(), 0);
    assert_eq!(h.state().scene_label(), "fig3");

    h.state_mut().settings_mut().step_size = 100;
    h.get_by_label("Step").click();
    wait_for(&mut h, "100 steps", |a| a.steps() == 100);
    std::thread::sleep(Duration::from_millis(100));
    h.run_steps(2);
    assert_eq!(
        h.state().steps(),
        100,
        "Step trains exactly step-size steps"
    );

    h.get_by_label("Play").click();
    wait_for(&mut h, "training", |a| a.running() && a.steps() > 1000);
    h.get_by_label("Pause").click();
    wait_for(&mut h, "the pause", |a| !a.running());
    let paused_at = h.state().steps();
    std::thread::sleep(Duration::from_millis(200));
    h.run_steps(3);
    assert_eq!(h.state().steps(), paused_at, "no training while paused");
    assert!(h.state().cells() > 3, "cells grew: {}", h.state().cells());
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
    std::thread::sleep(Duration::from_millis(100));
    h.run_steps(2);
    assert_eq!(h.state().cells(), 12, "growth stopped at the new target");
    h.get_by_label_contains("stopped (TargetCells)");

    // An out-of-range value typed in is clamped to the valid range by the widget.
    h.get_by_role_and_label(Role::SpinButton, "ψ")
        .set_value_accesskit(5.0);
    h.run_steps(2);
    assert_eq!(h.state().settings().params.psi, 1.0);
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
    let maze = flatland_geom::Scene::from_ron_str(flatland_viewer::BUNDLED_SCENES[2].1).unwrap();
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
