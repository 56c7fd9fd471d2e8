//! Integration tests of the `flatland` command line (one test binary for all subcommands).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use flatland_geom::{Kernel, Scene};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scene(name: &str) -> PathBuf {
    root().join("scenes").join(format!("{name}.ron"))
}

fn flatland(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_flatland"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run flatland")
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A fresh directory for one test's files.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flatland-cli-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Bad input: exit code 1, exactly one line on stderr starting with `error:`, no panic.
fn assert_one_line_error(out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "stderr: {err}");
    assert_eq!(err.lines().count(), 1, "not one line: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("backtrace"),
        "{err}"
    );
    for needle in needles {
        assert!(err.contains(needle), "`{needle}` missing from: {err}");
    }
}

fn as_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn parse_csv(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

#[test]
fn check_prints_the_summary_of_fig3() {
    let out = flatland(&["check", "--scene", as_str(&scene("fig3"))]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    for line in [
        "valid",
        "edges: 7 (6 surfaces, 1 blocker, 0 two-sided)",
        "emitters: edge 3 (E = 1)",
        "total length L: 14",
        "surface edge pairs: 15",
        "need visibility rays:",
        "0-3: against edges 6",
    ] {
        assert!(text.contains(line), "`{line}` missing from:\n{text}");
    }
}

#[test]
fn check_accepts_every_bundled_scene_and_the_json_copy() {
    for name in ["fig3", "box", "maze", "corners"] {
        let out = flatland(&["check", "--scene", as_str(&scene(name))]);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
    }
    let out = flatland(&[
        "check",
        "--scene",
        as_str(&root().join("tests/data/fig3.json")),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("edges: 7 "));
}

#[test]
fn the_json_copy_of_fig3_is_the_same_scene() {
    let json = Scene::load(root().join("tests/data/fig3.json")).unwrap();
    assert_eq!(
        json,
        Scene::load(scene("fig3")).unwrap(),
        "regenerate tests/data/fig3.json"
    );
}

#[test]
fn check_rejects_an_invalid_scene_naming_the_edge() {
    let dir = temp_dir("invalid");
    let path = dir.join("bad.ron");
    std::fs::write(
        &path,
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5), (a: (1, 0), b: (0, 1), reflectance: 1.5)])",
    )
    .unwrap();
    let out = flatland(&["check", "--scene", as_str(&path)]);
    assert_one_line_error(
        &out,
        &["bad.ron", "edge 1", "reflectance must be in [0, 1]", "1.5"],
    );
}

#[test]
fn check_reports_parse_errors_with_line_and_column() {
    let dir = temp_dir("parse");
    let path = dir.join("typo.json");
    std::fs::write(
        &path,
        "{\"edges\": [\n  {\"a\": [0, 0], \"b\": [1, 0] \"reflectance\": 0.5}]}",
    )
    .unwrap();
    let out = flatland(&["check", "--scene", as_str(&path)]);
    assert_one_line_error(&out, &[&format!("{}:2:", path.display())]);
}

#[test]
fn check_rejects_missing_files_and_unknown_formats() {
    let out = flatland(&["check", "--scene", "no/such/scene.ron"]);
    assert_one_line_error(&out, &["no/such/scene.ron"]);
    let out = flatland(&["check", "--scene", "Cargo.toml"]);
    assert_one_line_error(&out, &["Cargo.toml", "unknown scene format"]);
}

#[test]
fn kernel_writes_the_grid_as_csv() {
    let dir = temp_dir("csv");
    let out_path = dir.join("k.csv");
    let out = flatland(&[
        "kernel",
        "--scene",
        as_str(&scene("fig3")),
        "--res",
        "16",
        "--out",
        as_str(&out_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let rows = parse_csv(&std::fs::read_to_string(&out_path).unwrap());
    assert_eq!(rows.len(), 16);
    assert!(rows.iter().all(|r| r.len() == 16));
    // Line i is s = (i + 0.5)/R, column j is t = (j + 0.5)/R, the exact library values.
    let kernel = Kernel::new(Scene::load(scene("fig3")).unwrap());
    for (i, row) in rows.iter().enumerate() {
        for (j, &value) in row.iter().enumerate() {
            let (s, t) = ((i as f64 + 0.5) / 16.0, (j as f64 + 0.5) / 16.0);
            assert_eq!(value, kernel.k(s, t), "row {i} column {j}");
        }
    }
    // --weighted writes zeta, and the JSON copy of the scene gives the same numbers.
    let zeta_path = dir.join("zeta.csv");
    let json = root().join("tests/data/fig3.json");
    let out = flatland(&[
        "kernel",
        "--scene",
        as_str(&json),
        "--res",
        "16",
        "--weighted",
        "--out",
        as_str(&zeta_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let zeta = parse_csv(&std::fs::read_to_string(&zeta_path).unwrap());
    assert_eq!(zeta[3][11], kernel.zeta(3.5 / 16.0, 11.5 / 16.0));
    assert_ne!(zeta, rows);
}

#[test]
fn kernel_writes_a_png_heatmap_linear_or_log() {
    let dir = temp_dir("png");
    let (lin, log) = (dir.join("k.png"), dir.join("k-log.png"));
    let maze = scene("maze");
    for (path, extra) in [(&lin, None), (&log, Some("--log"))] {
        let mut args = vec!["kernel", "--scene", as_str(&maze), "--res", "48"];
        args.extend(extra);
        args.extend(["--out", as_str(path)]);
        let out = flatland(&args);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let a = image::open(&lin).unwrap().to_rgb8();
    let b = image::open(&log).unwrap().to_rgb8();
    assert_eq!(a.dimensions(), (48, 48));
    assert_ne!(a, b, "log scale must change the picture");
    // No temporary file is left next to the output.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn kernel_rejects_bad_arguments_without_writing() {
    let dir = temp_dir("bad-args");
    let out_path = dir.join("k.csv");
    let fig3 = scene("fig3");
    let out = flatland(&[
        "kernel",
        "--scene",
        as_str(&fig3),
        "--res",
        "0",
        "--out",
        as_str(&out_path),
    ]);
    assert_one_line_error(&out, &["--res must be in [1, 8192]", "0"]);
    let bad = dir.join("k.txt");
    let out = flatland(&["kernel", "--scene", as_str(&fig3), "--out", as_str(&bad)]);
    assert_one_line_error(&out, &["unknown output format"]);
    let out = flatland(&[
        "kernel",
        "--scene",
        "missing.ron",
        "--out",
        as_str(&out_path),
    ]);
    assert_one_line_error(&out, &["missing.ron"]);
    let nowhere = dir.join("no/such/dir/k.csv");
    let out = flatland(&[
        "kernel",
        "--scene",
        as_str(&fig3),
        "--res",
        "4",
        "--out",
        as_str(&nowhere),
    ]);
    assert_one_line_error(&out, &["no/such/dir/k.csv"]);
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing may be written"
    );
}

// ----- regressions: one test per fixed bug, saying what broke -----

/// The OS error of a missing scene file was printed twice ("...: No such file (os error 2): No
/// such file (os error 2)") because it was both in the message and the error's source chain.
#[test]
fn regression_missing_file_error_is_printed_once() {
    let out = flatland(&["check", "--scene", "missing.ron"]);
    let err = stderr(&out);
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

// ===== `flatland solve` (issue 11): the lit scene =====

/// Runs `flatland solve` with `args` and parses its `--json` object.
fn solve_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["solve"];
    all.extend(args);
    all.push("--json");
    let out = flatland(&all);
    assert!(out.status.success(), "{}", stderr(&out));
    serde_json::from_str(&stdout(&out)).expect("one JSON object")
}

#[test]
fn solve_json_reports_every_named_field() {
    let json = solve_json(&[
        "--scene",
        as_str(&scene("box")),
        "--elements",
        "128",
        "--reference-elements",
        "512",
    ]);
    assert_eq!(json["elements"], 128);
    assert_eq!(json["kernel"], "exact");
    assert!(json["basis_functions"].is_null(), "{json}");
    assert_eq!(json["reference_elements"], 512);
    for field in ["rel_l2_b", "rel_l2_reflected", "wall_s", "residual"] {
        let v = json[field].as_f64().unwrap_or(f64::NAN);
        assert!(v.is_finite() && v >= 0.0, "{field}: {json}");
    }
    // The exact kernel at 128 elements against 512: the discretisation only.
    assert!(json["rel_l2_reflected"].as_f64().unwrap() < 0.01, "{json}");
    assert!(json["iterations"].as_u64().unwrap() >= 1, "{json}");
}

#[test]
fn solve_writes_the_csv_one_row_per_element_in_order_of_s() {
    let dir = temp_dir("solve-csv");
    let path = dir.join("b.csv");
    let out = flatland(&[
        "solve",
        "--scene",
        as_str(&scene("fig3")),
        "--elements",
        "64",
        "--reference-elements",
        "256",
        "--out",
        as_str(&path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("edge,s,x,y,b"));
    let rows = parse_csv(&lines.collect::<Vec<_>>().join("\n"));
    assert_eq!(rows.len(), 64);
    let fig3 = Scene::load(scene("fig3")).unwrap();
    let mut last_s = -1.0;
    for row in &rows {
        let [edge, s, x, y, b] = row[..] else {
            panic!("five columns expected: {row:?}")
        };
        assert!(s > last_s, "rows not in order of s");
        last_s = s;
        // s is the kernel's parameter: it names the row's edge and point.
        let p = fig3.point(s);
        assert_eq!(p.edge as f64, edge);
        assert!(p.position.distance(flatland_geom::DVec2::new(x, y)) < 1e-9);
        // B includes emission, and the exact kernel only adds light.
        let e = fig3.edges()[p.edge].emission;
        assert!(b >= e && b.is_finite(), "b = {b} below E = {e}");
    }
}

#[test]
fn solve_gives_e_over_one_minus_rho_in_a_uniformly_glowing_room() {
    let dir = temp_dir("solve-glow");
    let room = dir.join("glow.ron");
    std::fs::write(
        &room,
        "(edges: [
            (a: (0, 0), b: (3, 0), reflectance: 0.6, emission: 2.0),
            (a: (3, 0), b: (2, 2), reflectance: 0.6, emission: 2.0),
            (a: (2, 2), b: (0, 1), reflectance: 0.6, emission: 2.0),
            (a: (0, 1), b: (0, 0), reflectance: 0.6, emission: 2.0),
        ])",
    )
    .unwrap();
    let path = dir.join("b.csv");
    let out = flatland(&[
        "solve",
        "--scene",
        as_str(&room),
        "--elements",
        "40",
        "--reference-elements",
        "80",
        "--out",
        as_str(&path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&path).unwrap();
    for line in text.lines().skip(1) {
        let b: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
        assert!((b - 5.0).abs() < 1e-8, "B = {b}, expected E / (1 − ρ) = 5");
    }
}

#[test]
fn solve_draws_the_lit_scene_beside_b_of_s() {
    let dir = temp_dir("solve-png");
    let path = dir.join("lit.png");
    let out = flatland(&[
        "solve",
        "--scene",
        as_str(&scene("corners")),
        "--kernel",
        "hr",
        "--basis",
        "100",
        "--elements",
        "128",
        "--reference-elements",
        "512",
        "--out",
        as_str(&path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("with the hr kernel"),
        "{}",
        stdout(&out)
    );
    let png = image::open(&path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (1600, 760));
    // The lit scene (left) has the colours of light: some pixel is bright orange-yellow.
    let lit = png
        .enumerate_pixels()
        .filter(|(x, _, _)| *x < 700)
        .any(|(_, _, p)| p[0] > 230 && p[1] > 150 && p[2] < 120);
    assert!(lit, "no lit edge drawn");
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(names.len(), 1, "a temporary file was left behind");
}

#[test]
fn solve_builds_every_baseline_and_reads_a_model() {
    let box_scene = scene("box");
    for (kernel, basis) in [("uniform", 100), ("uniform-exact", 100), ("hr", 100)] {
        let json = solve_json(&[
            "--scene",
            as_str(&box_scene),
            "--kernel",
            kernel,
            "--basis",
            &basis.to_string(),
            "--elements",
            "64",
            "--reference-elements",
            "256",
        ]);
        assert_eq!(json["kernel"], kernel);
        let b = json["basis_functions"].as_u64().unwrap();
        assert!(b.abs_diff(100) <= 10, "{kernel}: {json}");
        assert!(json["rel_l2_reflected"].as_f64().unwrap().is_finite());
    }
    // A model from `flatland fit --out`, solved on its own scene.
    let dir = temp_dir("solve-model");
    let model = dir.join("m.json");
    // (fig3: the default learner has something to learn there; on the box it would have none.)
    let out = flatland(&[
        "fit",
        "--scene",
        as_str(&scene("fig3")),
        "--cells",
        "12",
        "--out",
        as_str(&model),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json = solve_json(&[
        "--kernel",
        as_str(&model),
        "--elements",
        "32",
        "--reference-elements",
        "128",
    ]);
    assert_eq!(json["basis_functions"], 12);
    assert!(json["rel_l2_b"].as_f64().unwrap().is_finite());
    // ... and refused on another scene.
    let out = flatland(&[
        "solve",
        "--scene",
        as_str(&box_scene),
        "--kernel",
        as_str(&model),
    ]);
    assert_one_line_error(&out, &["box.ron", "fingerprint"]);
}

#[test]
fn solve_rejects_bad_arguments_with_one_line_and_writes_nothing() {
    let dir = temp_dir("solve-bad");
    let fig3 = scene("fig3");
    let csv = dir.join("b.csv");
    let run = |extra: &[&str]| {
        let mut args = vec!["solve", "--scene", as_str(&fig3)];
        args.extend(extra);
        flatland(&args)
    };
    assert_one_line_error(
        &run(&["--elements", "0", "--out", as_str(&csv)]),
        &["elements", "at least one per section"],
    );
    assert_one_line_error(
        &run(&["--elements", "100000"]),
        &["elements", "at most 8192"],
    );
    assert_one_line_error(&run(&["--kernel", "sgsc"]), &["`sgsc`", "exact, sgcs, hr"]);
    assert_one_line_error(
        &run(&["--kernel", "no/such/model.json"]),
        &["no/such/model.json"],
    );
    assert_one_line_error(&run(&["--kernel", "hr", "--basis", "0"]), &["--basis"]);
    assert_one_line_error(
        &run(&["--out", as_str(&dir.join("b.txt"))]),
        &["b.txt", "unknown output format"],
    );
    assert_one_line_error(
        &run(&["--out", as_str(&dir.join("no/such/b.csv"))]),
        &["does not exist"],
    );
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing may be written"
    );
}
