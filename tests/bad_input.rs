//! Bad scene files never panic: truncated, binary, huge, deeply nested, wrong-typed
//! and randomly mutated files give a one-line error naming the file and a position (parse
//! errors) or the edge (validation errors), through the library and through the CLI; a file
//! that is accepted gives a finite, non-negative kernel. The same property as the cargo-fuzz
//! target `fuzz/fuzz_targets/scene.rs`, run with proptest inside the normal test suite.
//!
//! Model and checkpoint files the tools wrote and a user edited: any field replaced,
//! removed, emptied or duplicated loads with a one-line error naming the file, or loads and
//! then evaluates (a model) or trains and finishes (a checkpoint) to finite errors — never a
//! panic or an allocation abort.

use std::path::{Path, PathBuf};
use std::process::Command;

use flatland_geom::{GeomError, Kernel, Scene};
use proptest::prelude::*;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The bundled scenes' text, and the JSON copy of fig3: `(file name, text)`.
fn valid_files() -> Vec<(String, String)> {
    let mut files: Vec<(String, String)> = ["fig3", "box", "maze", "corners"]
        .iter()
        .map(|name| {
            let path = root().join("scenes").join(format!("{name}.ron"));
            (
                format!("{name}.ron"),
                std::fs::read_to_string(path).unwrap(),
            )
        })
        .collect();
    let json = root().join("tests/data/fig3.json");
    files.push(("fig3.json".into(), std::fs::read_to_string(json).unwrap()));
    files
}

/// A fresh directory for one test's files.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flatland-bad-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn parse(text: &str, json: bool) -> Result<Scene, GeomError> {
    if json {
        Scene::from_json_str(text)
    } else {
        Scene::from_ron_str(text)
    }
}

/// The property every input must satisfy: an accepted scene has a finite, non-negative kernel;
/// a rejected one has a one-line message, with a 1-based position inside the text (plus one
/// line for an error at the very end) for a parse error. `location` is the expected prefix.
fn check_outcome(result: Result<Scene, GeomError>, text_lines: usize, location: &str) {
    match result {
        Ok(scene) => {
            let kernel = Kernel::new(scene);
            for s in [0.0, 0.13, 0.5, 0.77, 0.999_999] {
                for t in [0.01, 0.4, 0.62, 0.95] {
                    let (k, z) = (kernel.k(s, t), kernel.zeta(s, t));
                    assert!(k.is_finite() && k >= 0.0, "k({s}, {t}) = {k}");
                    assert!(z.is_finite() && z >= 0.0, "zeta({s}, {t}) = {z}");
                }
            }
        }
        Err(err) => {
            let message = err.to_string();
            assert!(!message.contains('\n'), "multi-line error: {message:?}");
            assert!(
                message.starts_with(location),
                "`{message}` does not start with `{location}`"
            );
            match err {
                GeomError::Parse { line, column, .. } => {
                    assert!(line >= 1 && column >= 1, "0 in position: {message}");
                    assert!(line <= text_lines + 1, "line past the end: {message}");
                }
                GeomError::InvalidFile { .. } => {
                    assert!(
                        message.contains(": edge ") || message.contains("no surface edge"),
                        "validation error names no edge: {message}"
                    );
                }
                other => {
                    let in_file = location.is_empty() || matches!(other, GeomError::Io { .. });
                    assert!(in_file, "unexpected error kind: {message}");
                }
            }
        }
    }
}

/// Loads `bytes` from a file named `name` and checks the property, including that the message
/// starts with the file name and, for a parse error, `file:line:column:`.
fn check_file(dir: &Path, name: &str, bytes: &[u8]) -> Result<Scene, String> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let lines = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
    let result = Scene::load(&path);
    let outcome = result.as_ref().map(|_| ()).map_err(|e| e.to_string());
    check_outcome(result, lines, &format!("{}:", path.display()));
    match outcome {
        Ok(()) => Ok(Scene::load(&path).unwrap()),
        Err(message) => Err(message),
    }
}

/// `file:L:C: ` at the start of a parse error message.
fn assert_position(message: &str, path_prefix: &str) {
    let rest = message
        .strip_prefix(path_prefix)
        .unwrap_or_else(|| panic!("`{message}` does not name {path_prefix}"));
    let mut parts = rest.splitn(3, ':');
    let line: usize = parts.next().unwrap().parse().expect("a line number");
    let column: usize = parts
        .next()
        .unwrap_or_else(|| panic!("no column in {message}"))
        .parse()
        .unwrap_or_else(|_| panic!("no column in {message}"));
    assert!(line >= 1 && column >= 1, "{message}");
}

#[test]
fn every_truncation_of_a_valid_file_is_a_clean_error() {
    for (name, text) in valid_files() {
        let json = name.ends_with(".json");
        let lines = text.lines().count();
        let cuts: Vec<usize> = (0..text.len())
            .filter(|&i| text.is_char_boundary(i))
            .collect();
        for &cut in &cuts {
            check_outcome(parse(&text[..cut], json), lines, "");
        }
        // Through files too, for a spread of cut points: the message names the file.
        let dir = temp_dir(&format!("truncated-{name}"));
        for &cut in cuts.iter().step_by(41) {
            if let Err(message) = check_file(&dir, &name, &text.as_bytes()[..cut])
                && !message.contains(": edge ")
                && !message.contains("no surface edge")
            {
                assert_position(&message, &format!("{}:", dir.join(&name).display()));
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn binary_files_are_parse_errors_with_a_position() {
    let dir = temp_dir("binary");
    // Not UTF-8 at all (a PNG header), UTF-8 with NUL bytes, and invalid UTF-8 after a valid
    // first line.
    let cases: [(&str, &[u8], &str); 4] = [
        (
            "png.json",
            b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR",
            ":1:1: not a text file",
        ),
        (
            "png.ron",
            b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR",
            ":1:1: not a text file",
        ),
        (
            "late.ron",
            b"(edges: [\n  (a: (0, 0), \xff\xfe",
            ":2:15: not a text file",
        ),
        ("nul.json", b"\0\0\0\0{\"edges\": []}", ":1:1:"),
    ];
    for (name, bytes, needle) in cases {
        let message = check_file(&dir, name, bytes).unwrap_err();
        let expected = format!("{}{needle}", dir.join(name).display());
        assert!(message.starts_with(&expected), "{message} vs {expected}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn deeply_nested_files_are_refused_without_overflowing_the_stack() {
    let dir = temp_dir("nested");
    for depth in [200, 100_000] {
        let cases = [
            ("deep.json", format!("{{\"edges\": {}", "[".repeat(depth))),
            (
                "deep2.json",
                "{\"edges\": [{\"a\": ".to_owned() + &"[".repeat(depth),
            ),
            ("deep.ron", format!("(edges: {}", "[".repeat(depth))),
            ("deep2.ron", "(edges: [(a: ".to_owned() + &"(".repeat(depth)),
            ("deep3.ron", "Some(".repeat(depth)),
        ];
        for (name, text) in cases {
            let message = check_file(&dir, name, text.as_bytes()).unwrap_err();
            assert_position(&message, &format!("{}:", dir.join(name).display()));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn huge_files_and_numbers() {
    let dir = temp_dir("huge");
    // 100 000 valid edges (a zig-zag floor under a ceiling) load, and the kernel is finite.
    let n = 100_000;
    let mut text = String::from("{\"edges\": [");
    for i in 0..n {
        let x = i as f64 * 1e-3;
        let (ya, yb) = if i % 2 == 0 { (0.0, 1e-4) } else { (1e-4, 0.0) };
        text.push_str(&format!(
            "{{\"a\": [{x}, {ya}], \"b\": [{}, {yb}], \"reflectance\": 0.5}},",
            x + 1e-3
        ));
    }
    text.push_str(&format!(
        "{{\"a\": [{}, 1], \"b\": [0, 1], \"reflectance\": 0.5, \"emission\": 1}}]}}",
        n as f64 * 1e-3
    ));
    let scene = check_file(&dir, "huge.json", text.as_bytes()).unwrap();
    assert_eq!(scene.edges().len(), n + 1);
    // Numbers beyond f64: JSON refuses them with a position; RON reads them as infinite and
    // validation names the edge.
    let json = r#"{"edges": [{"a": [1e400, 0], "b": [1, 0], "reflectance": 0.5}]}"#;
    let message = check_file(&dir, "big.json", json.as_bytes()).unwrap_err();
    assert_position(&message, &format!("{}:", dir.join("big.json").display()));
    let ron = "(edges: [(a: (1e400, 0), b: (1, 0), reflectance: 0.5)])";
    let message = check_file(&dir, "big.ron", ron.as_bytes()).unwrap_err();
    assert!(message.contains("edge 0: a.x must be finite"), "{message}");
    // A very long line of digits.
    let long = format!(
        "{{\"edges\": [{{\"a\": [{}, 0], \"b\": [1, 0], \"reflectance\": 0.5}}]}}",
        "9".repeat(1_000_000)
    );
    let _ = check_file(&dir, "digits.json", long.as_bytes());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn wrong_types_and_shapes_are_parse_errors_naming_the_position() {
    let dir = temp_dir("typed");
    let edge = r#""a": [0, 0], "b": [1, 0], "reflectance": 0.5"#;
    let json_cases = [
        "null".to_owned(),
        "[]".to_owned(),
        r#"{"edges": {}}"#.to_owned(),
        r#"{"edges": [1, 2]}"#.to_owned(),
        r#"{"edges": [{"a": "zero", "b": [1, 0], "reflectance": 0.5}]}"#.to_owned(),
        r#"{"edges": [{"a": [0, 0, 0], "b": [1, 0], "reflectance": 0.5}]}"#.to_owned(),
        r#"{"edges": [{"a": [0], "b": [1, 0], "reflectance": 0.5}]}"#.to_owned(),
        format!(r#"{{"edges": [{{{edge}, "reflectance": 0.5}}]}}"#),
        format!(r#"{{"edges": [{{{edge}, "role": 3}}]}}"#),
        format!(r#"{{"edges": [{{{edge}, "role": "wall"}}]}}"#),
        format!(r#"{{"edges": [{{{edge}, "two_sided": "yes"}}]}}"#),
        format!(r#"{{"edges": [{{{edge}, "emission": null}}]}}"#),
        format!(r#"{{"edges": [{{{edge}, "colour": 1}}]}}"#),
        format!(r#"{{"edges": [{{{edge}}}], "lights": [{{"at": "here", "power": 1}}]}}"#),
        format!(r#"{{"edges": [{{{edge}}}], "lights": [{{"at": [0, 1], "watts": 1}}]}}"#),
        r#"{"edges": [{"a": [NaN, 0], "b": [1, 0], "reflectance": 0.5}]}"#.to_owned(),
        format!(r#"{{"edges": [{{{edge}}}]}} trailing"#),
    ];
    for (i, text) in json_cases.iter().enumerate() {
        let name = format!("case{i}.json");
        let message = check_file(&dir, &name, text.as_bytes()).unwrap_err();
        assert_position(&message, &format!("{}:", dir.join(&name).display()));
    }
    let ron_cases = [
        "()",
        "(edges: ())",
        "(edges: [(a: \"zero\", b: (1, 0), reflectance: 0.5)])",
        "(edges: [(a: (0, 0, 0), b: (1, 0), reflectance: 0.5)])",
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: true)])",
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5, role: wall)])",
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5, two_sided: 1)])",
        "(edges: [(a: (0, 0), b: (1, 0))])",
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5)], extra: 1)",
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5)]) trailing",
        "/* unterminated comment",
        "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5, role: \"sur\nface\")])",
    ];
    for (i, text) in ron_cases.iter().enumerate() {
        let name = format!("case{i}.ron");
        let message = check_file(&dir, &name, text.as_bytes()).unwrap_err();
        assert_position(&message, &format!("{}:", dir.join(&name).display()));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Regression (found by the fuzz target, crash-7773a49b): a raw line break inside a JSON string
/// was reported at column 0 of the next line (`13:0:`), not a 1-based position.
#[test]
fn regression_json_error_at_a_line_break_has_a_1_based_position() {
    let text = "{\"edges\": [{\"a\": [0, 0], \"b\": [1, 0], \"r\n\": 0.5}]}";
    let err = Scene::from_json_str(text).unwrap_err();
    match err {
        GeomError::Parse { line, column, .. } => {
            assert_eq!((line, column), (1, 41), "{err}");
        }
        other => panic!("not a parse error: {other}"),
    }
    assert!(
        Scene::from_json_str("")
            .unwrap_err()
            .to_string()
            .starts_with("1:1: ")
    );
}

/// Regression: a line break inside a quoted name that the parser's message repeats (an
/// unknown variant or field) made the error two lines long.
#[test]
fn regression_a_newline_in_a_quoted_name_keeps_the_error_on_one_line() {
    let json =
        r#"{"edges": [{"a": [0, 0], "b": [1, 0], "reflectance": 0.5, "role": "sur\nface"}]}"#;
    let message = Scene::from_json_str(json).unwrap_err().to_string();
    assert!(
        !message.contains('\n') && message.contains("sur\\nface"),
        "{message}"
    );
    let json = r#"{"edges": [{"a": [0, 0], "b": [1, 0], "reflectance": 0.5, "x\ny": 1}]}"#;
    let message = Scene::from_json_str(json).unwrap_err().to_string();
    assert!(!message.contains('\n'), "{message}");
    let ron = "(edges: [(a: (0, 0), b: (1, 0), reflectance: 0.5, role: \"sur\\nface\")])";
    let message = Scene::from_ron_str(ron).unwrap_err().to_string();
    assert!(!message.contains('\n'), "{message}");
}

/// Random single-byte mutations of a valid file.
fn mutated() -> impl Strategy<Value = (bool, Vec<u8>)> {
    let files = valid_files();
    (
        0..files.len(),
        prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..4), 1..8),
    )
        .prop_map(move |(f, edits)| {
            let (name, text) = &files[f];
            let mut bytes = text.clone().into_bytes();
            for (at, byte, op) in edits {
                if bytes.is_empty() {
                    break;
                }
                let i = at.index(bytes.len());
                match op {
                    0 => bytes[i] = byte,
                    1 => {
                        bytes.insert(i, byte);
                    }
                    2 => {
                        bytes.remove(i);
                    }
                    // A printable token from the schema's alphabet, so parsing gets deep.
                    _ => {
                        let tokens: &[&[u8]] = &[
                            b"(", b")", b"[", b"]", b"{", b"}", b",", b":", b"\"", b"-", b"1e308",
                            b"NaN", b"inf", b"0", b"role", b"blocker", b"true",
                        ];
                        bytes.splice(
                            i..i,
                            tokens[usize::from(byte) % tokens.len()].iter().copied(),
                        );
                    }
                }
            }
            (name.ends_with(".json"), bytes)
        })
}

/// Small syntactically valid scenes with arbitrary numbers, including the extreme ones.
fn numeric() -> impl Strategy<Value = String> {
    let number = prop_oneof![
        -10.0f64..10.0,
        Just(0.0),
        Just(-0.0),
        Just(1e-300),
        Just(1e300),
        Just(-1e308),
        Just(5e-324),
        Just(2.0),
        Just(1.0),
    ];
    let edge = (
        [
            number.clone(),
            number.clone(),
            number.clone(),
            number.clone(),
        ],
        number.clone(),
        number,
        any::<bool>(),
        any::<bool>(),
    );
    prop::collection::vec(edge, 0..6).prop_map(|edges| {
        let items: Vec<String> = edges
            .iter()
            .map(|([ax, ay, bx, by], rho, e, blocker, two)| {
                format!(
                    r#"{{"a": [{ax:e}, {ay:e}], "b": [{bx:e}, {by:e}], "reflectance": {rho:e}, "emission": {e:e}, "role": "{}", "two_sided": {two}}}"#,
                    if *blocker { "blocker" } else { "surface" }
                )
            })
            .collect();
        format!("{{\"edges\": [{}]}}", items.join(", "))
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_never_panic((json, bytes) in mutated()) {
        if let Ok(text) = std::str::from_utf8(&bytes) {
            check_outcome(parse(text, json), text.lines().count(), "");
        }
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..256), json: bool) {
        let text = String::from_utf8_lossy(&bytes);
        check_outcome(parse(&text, json), text.lines().count(), "");
    }

    #[test]
    fn extreme_numbers_validate_or_name_the_edge(text in numeric()) {
        // Either a valid scene (finite kernel) or a validation error naming an edge / no surface.
        match Scene::from_json_str(&text) {
            Ok(scene) => check_outcome(Ok(scene), 1, ""),
            Err(err) => {
                let message = err.to_string();
                prop_assert!(
                    message.starts_with("edge ") || message.contains("no surface edge")
                        || message.contains("total length"),
                    "{message}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// The same through files: the message names the file.
    #[test]
    fn mutated_files_on_disk_never_panic((json, bytes) in mutated()) {
        let dir = temp_dir("prop");
        let _ = check_file(&dir, if json { "m.json" } else { "m.ron" }, &bytes);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

fn flatland(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_flatland"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run flatland")
}

#[test]
fn cli_reports_bad_files_in_one_line_without_panicking() {
    let dir = temp_dir("cli");
    let cases: [(&str, Vec<u8>, &str); 5] = [
        (
            "binary.json",
            b"\x89PNG\r\n\x1a\n".to_vec(),
            ":1:1: not a text file",
        ),
        (
            "truncated.ron",
            b"(edges: [(a: (0, 0), b: (1".to_vec(),
            ":1:",
        ),
        ("nested.json", "[".repeat(100_000).into_bytes(), ":1:"),
        ("typed.json", br#"{"edges": [{"a": "x"}]}"#.to_vec(), ":1:"),
        (
            "newline.json",
            b"{\"edges\": [{\"a\n\": 1}]}".to_vec(),
            ":1:",
        ),
    ];
    for (name, bytes, needle) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let csv = dir.join("out.csv");
        let csv = csv.to_str().unwrap();
        let subcommands: [&[&str]; 3] = [
            &["check", "--scene"],
            &["kernel", "--res", "16", "--out", csv, "--scene"],
            &["fit", "--cells", "3", "--scene"],
        ];
        for sub in subcommands {
            let mut args: Vec<&str> = sub.to_vec();
            args.push(path.to_str().unwrap());
            let out = flatland(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: not one line: {err}");
            assert!(!err.contains("panicked"), "{err}");
            let expected = format!("error: {}{needle}", path.display());
            assert!(err.starts_with(&expected), "{err} vs {expected}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene file with a two-sided surface: every command that loads it refuses it in one line
/// naming the file and the edge and saying how to draw a thin wall; a two-sided blocker and
/// the same wall as two faces back to back load.
#[test]
fn cli_refuses_a_two_sided_surface_saying_how_to_draw_a_thin_wall() {
    let dir = temp_dir("two-sided");
    let room = r#"{"a": [0, 0], "b": [4, 0], "reflectance": 0.5},
        {"a": [4, 0], "b": [4, 3], "reflectance": 0.5},
        {"a": [4, 3], "b": [0, 3], "reflectance": 0.5, "emission": 1},
        {"a": [0, 3], "b": [0, 0], "reflectance": 0.5}"#;
    let wall = r#"{"a": [2, 0], "b": [2, 2], "reflectance": 0.5"#;
    let files = [
        (
            "wall.json",
            format!(r#"{{"edges": [{room}, {wall}, "two_sided": true}}]}}"#),
        ),
        (
            "wall.ron",
            "(edges: [(a: (0, 0), b: (4, 0), reflectance: 0.5), (a: (4, 0), b: (4, 3), \
             reflectance: 0.5, emission: 1), (a: (4, 3), b: (0, 3), reflectance: 0.5), \
             (a: (0, 3), b: (0, 0), reflectance: 0.5), \
             (a: (2, 0), b: (2, 2), reflectance: 0.5, two_sided: true)])"
                .to_owned(),
        ),
    ];
    let csv = dir.join("out.csv");
    let csv = csv.to_str().unwrap();
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let subcommands: [&[&str]; 4] = [
            &["check", "--scene"],
            &["kernel", "--res", "16", "--out", csv, "--scene"],
            &["solve", "--scene"],
            &["fit", "--cells", "3", "--scene"],
        ];
        for sub in subcommands {
            let mut args: Vec<&str> = sub.to_vec();
            args.push(path.to_str().unwrap());
            let out = flatland(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: not one line: {err}");
            let expected = format!(
                "error: {}: edge 4: a surface cannot be two-sided",
                path.display()
            );
            assert!(err.starts_with(&expected), "{err} vs {expected}");
            assert!(
                err.contains("a box") && err.contains("two one-sided edges back to back"),
                "{err}"
            );
        }
    }
    // Allowed: the wall as two faces back to back, and a two-sided blocker.
    let back_to_back = r#"{"a": [2, 2], "b": [2, 0], "reflectance": 0.5}"#;
    let blocker =
        r#"{"a": [1, 1], "b": [1, 2], "reflectance": 0, "role": "blocker", "two_sided": true}"#;
    let path = dir.join("thin.json");
    std::fs::write(
        &path,
        format!(r#"{{"edges": [{room}, {wall}}}, {back_to_back}, {blocker}]}}"#),
    )
    .unwrap();
    let out = flatland(&["check", "--scene", path.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("1 two-sided"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ----- model and checkpoint files, edited -----

/// A model (ζ target), a model (factored emission) and a checkpoint of small fig3 fits, as JSON.
fn tool_written_files() -> &'static [(&'static str, serde_json::Value)] {
    use std::ops::ControlFlow;
    use std::sync::{Arc, OnceLock};

    use flatland_solve::Reference;
    use kernel_fit::{Fit, FitParams, ModelFile, REFERENCE_SEED, Target};

    static FILES: OnceLock<Vec<(&'static str, serde_json::Value)>> = OnceLock::new();
    FILES.get_or_init(|| {
        let dir = temp_dir("tool-written");
        let kernel = Arc::new(Kernel::new(
            Scene::load(root().join("scenes/fig3.ron")).unwrap(),
        ));
        let reference = Arc::new(Reference::new(&kernel, 16, 64, REFERENCE_SEED));
        let mut files = Vec::new();
        for (name, target) in [
            ("zeta.json", Target::Zeta),
            ("factored.json", Target::FactoredEmission),
        ] {
            let params = FitParams {
                target_cells: 10,
                initial_samples: 40,
                heldout: 64,
                refit: false,
                ..FitParams::default().learning(target)
            };
            let mut fit = Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params).unwrap();
            let summary = fit.run(1000, |_| ControlFlow::Continue(())).unwrap();
            let path = dir.join(name);
            ModelFile::new(fit.model().clone(), params, Some(summary))
                .save(&path)
                .unwrap();
            files.push((
                name,
                serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap(),
            ));
            if target == Target::Zeta {
                let path = dir.join("fit.ckpt");
                fit.save_checkpoint(&path).unwrap();
                files.push((
                    "fit.ckpt",
                    serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap(),
                ));
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
        files
    })
}

/// Every place in a JSON document: a path of keys and indices.
fn places(value: &serde_json::Value, at: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    out.push(at.clone());
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                at.push(Step::Key(k.clone()));
                places(v, at, out);
                at.pop();
            }
        }
        serde_json::Value::Array(items) => {
            // A few elements of long arrays are enough: they are all alike.
            for (i, v) in items.iter().enumerate().take(3) {
                at.push(Step::Index(i));
                places(v, at, out);
                at.pop();
            }
        }
        _ => {}
    }
}

#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

fn get_mut<'a>(value: &'a mut serde_json::Value, path: &[Step]) -> &'a mut serde_json::Value {
    path.iter().fold(value, |v, step| match step {
        Step::Key(k) => &mut v[k.as_str()],
        Step::Index(i) => &mut v[*i],
    })
}

/// Values a hand edit might leave: extremes of every JSON number type, wrong types, empties.
fn replacement(pick: usize) -> serde_json::Value {
    use serde_json::json;
    let pool = [
        json!(0),
        json!(-1),
        json!(1),
        json!(0.5),
        json!(-0.5),
        json!(2),
        json!(1e308),
        json!(-1e308),
        json!(1e-308),
        json!(5e-324),
        json!(1e20),
        json!(u64::MAX),
        json!(i64::MIN),
        json!(9_007_199_254_740_993u64),
        json!(100_000),
        json!("x"),
        json!(true),
        json!(null),
        json!([]),
        json!({}),
    ];
    pool[pick % pool.len()].clone()
}

/// One hand edit: replace, remove, empty, shorten or duplicate what is at a place.
fn edit(value: &mut serde_json::Value, path: &[Step], op: u8, pick: usize) {
    if path.is_empty() {
        *value = replacement(pick);
        return;
    }
    let (last, parent_path) = path.split_last().unwrap();
    let parent = get_mut(value, parent_path);
    match (op % 4, last, parent) {
        (0, Step::Key(k), serde_json::Value::Object(map)) => {
            map.remove(k);
        }
        (1, Step::Index(i), serde_json::Value::Array(items)) => {
            items.remove(*i);
        }
        (2, Step::Index(i), serde_json::Value::Array(items)) => {
            let copy = items[*i].clone();
            items.insert(*i, copy);
        }
        (3, _, parent) => {
            let target = match last {
                Step::Key(k) => &mut parent[k.as_str()],
                Step::Index(i) => &mut parent[*i],
            };
            if let serde_json::Value::Array(items) = target {
                items.truncate(pick % 2);
            } else {
                *target = replacement(pick);
            }
        }
        (_, last, parent) => {
            let target = match last {
                Step::Key(k) => &mut parent[k.as_str()],
                Step::Index(i) => &mut parent[*i],
            };
            *target = replacement(pick);
        }
    }
}

/// Loads the edited file as the tools do and checks the property.
fn check_edited(name: &str, value: &serde_json::Value) {
    use flatland_solve::{Reference, Representation};
    use kernel_fit::{Fit, ModelFile, REFERENCE_SEED};

    let dir = temp_dir("edited");
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(value).unwrap()).unwrap();
    let one_line = |message: String| {
        assert!(!message.contains('\n'), "multi-line error: {message}");
        assert!(message.contains(name), "`{message}` does not name the file");
    };
    if name.ends_with(".ckpt") {
        match Fit::resume(&path, flatland_geom::KernelParams::default()) {
            Ok(mut fit) => {
                fit.train(100, |f| {
                    if f.steps() % 100 == 0 && f.steps() > 0 {
                        std::ops::ControlFlow::Break(())
                    } else {
                        std::ops::ControlFlow::Continue(())
                    }
                });
                let summary = fit.finish().unwrap();
                assert!(summary.errors.grid.is_finite() && summary.errors.heldout.is_finite());
            }
            Err(e) => one_line(e.to_string()),
        }
    } else {
        match ModelFile::load(&path) {
            Ok(file) => {
                let kernel = Kernel::new(file.model.scene().clone());
                let reference = Reference::new(&kernel, 16, 64, REFERENCE_SEED);
                let errors = reference.errors(&file.model);
                // Finite: an edited weight may make the model bad, never the numbers undefined.
                assert!(
                    errors.grid.is_finite() && errors.heldout.is_finite(),
                    "{errors:?}"
                );
                assert!(file.model.zeta(0.3, 0.7).is_finite());
            }
            Err(e) => one_line(e.to_string()),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn edited_models_and_checkpoints_never_panic(
        file in 0usize..3,
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0u8..5, any::<usize>()), 1..4),
    ) {
        let (name, original) = &tool_written_files()[file];
        let mut value = original.clone();
        for (at, op, pick) in edits {
            let mut all = Vec::new();
            places(&value, &mut Vec::new(), &mut all);
            let path = all[at.index(all.len())].clone();
            edit(&mut value, &path, op, pick);
        }
        check_edited(name, &value);
    }
}
