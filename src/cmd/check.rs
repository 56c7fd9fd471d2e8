//! `flatland check`: validate a scene file and print a summary.

use flatland_geom::{Kernel, PairClass, Role, Scene};

/// Pairs listed one by one at most; larger scenes print counts only.
const MAX_LISTED: usize = 40;
/// Emitters, or a pair's occluders, named on one line at most; the rest are counted, so a
/// scene of thousands of edges still prints lines a terminal shows whole.
const MAX_NAMED: usize = 4;
/// Above this many surface edges the pair classification is skipped (it is quadratic).
const MAX_CLASSIFIED: usize = 512;

/// Arguments of `flatland check`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: super::SceneArgs,
}

/// Loads and validates the scene, then prints the summary to stdout.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let (scene, label) = args.scene.load()?;
    print!("{}", summary(&label, &scene));
    Ok(())
}

/// The summary `flatland check` prints.
pub fn summary(name: &str, scene: &Scene) -> String {
    use std::fmt::Write as _;
    let edges = scene.edges();
    let surfaces = scene.surface_edges();
    let blockers = edges.iter().filter(|e| e.role == Role::Blocker).count();
    let emitters: Vec<usize> = (0..edges.len())
        .filter(|&i| edges[i].emission > 0.0)
        .collect();
    let (lo, hi) = scene.bounds();
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(w, "scene {name}: valid");
    let _ = writeln!(
        w,
        "edges: {} ({}, {}, {} two-sided)",
        edges.len(),
        plural(surfaces.len(), "surface"),
        plural(blockers, "blocker"),
        edges.iter().filter(|e| e.two_sided).count()
    );
    lighting(w, scene, &emitters);
    overlaps(w, scene);
    let _ = writeln!(w, "total length L: {}", scene.total_length());
    let _ = writeln!(w, "bounds: ({}, {}) .. ({}, {})", lo.x, lo.y, hi.x, hi.y);
    let _ = writeln!(w, "fingerprint: {:016x}", scene.fingerprint());
    if surfaces.len() > MAX_CLASSIFIED {
        let _ = writeln!(
            w,
            "visibility: {} surfaces, pair classification skipped",
            surfaces.len()
        );
        return out;
    }
    visibility(w, scene, surfaces);
    out
}

/// A warning per pair of overlapping surface edges (the first [`MAX_LISTED`]).
fn overlaps(w: &mut String, scene: &Scene) {
    use std::fmt::Write as _;
    let overlaps = scene.overlapping_surface_edges();
    for (a, b) in overlaps.iter().take(MAX_LISTED) {
        let _ = writeln!(
            w,
            "warning: surface edges {a} and {b} overlap: each carries its own light, so the \
             shared stretch counts twice (delete one, or make it a blocker)"
        );
    }
    if overlaps.len() > MAX_LISTED {
        let _ = writeln!(
            w,
            "warning: ... and {} more overlapping pairs",
            overlaps.len() - MAX_LISTED
        );
    }
}

/// The surface edge pairs by how their visibility is known, and the pairs that need rays with
/// the edges that may block them (the first [`MAX_LISTED`]).
fn visibility(w: &mut String, scene: &Scene, surfaces: &[flatland_geom::EdgeId]) {
    use std::fmt::Write as _;
    let kernel = Kernel::new(scene.clone());
    let (mut same, mut never, mut clear, mut blocked) = (0, 0, 0, 0);
    let mut rays = Vec::new();
    let rank = |e| scene.surface_rank(e).expect("a surface edge has a rank");
    for (i, &a) in surfaces.iter().enumerate() {
        for &b in &surfaces[i + 1..] {
            let (ra, rb) = (rank(a), rank(b));
            if ra == rb {
                same += 1; // pieces of one parent edge
                continue;
            }
            match kernel.pair_class(ra, rb) {
                PairClass::Zero => never += 1,
                PairClass::Visible => clear += 1,
                PairClass::Hidden => blocked += 1,
                PairClass::Varies => rays.push((a, b, kernel.pair_occluders(ra, rb))),
            }
        }
    }
    let total = same + never + clear + blocked + rays.len();
    let _ = writeln!(w, "surface edge pairs: {total}");
    let _ = writeln!(w, "  same parent edge (k = 0):        {same}");
    let _ = writeln!(w, "  never facing (k = 0, no ray):    {never}");
    let _ = writeln!(w, "  clear (V = 1, no ray):           {clear}");
    let _ = writeln!(w, "  fully blocked (V = 0, no ray):   {blocked}");
    let _ = writeln!(w, "  need visibility rays:            {}", rays.len());
    for (a, b, occluders) in rays.iter().take(MAX_LISTED) {
        let names = named(occluders.iter().map(ToString::to_string));
        let _ = writeln!(w, "    {a}-{b}: against edges {names}");
    }
    if rays.len() > MAX_LISTED {
        let _ = writeln!(w, "    ... and {} more", rays.len() - MAX_LISTED);
    }
}

/// The first [`MAX_NAMED`] of `items`, comma-separated, and how many more there are.
/// The emitters, the point lights, and a warning when nothing lights the scene.
fn lighting(w: &mut String, scene: &Scene, emitters: &[usize]) {
    use std::fmt::Write;
    let edges = scene.edges();
    let list = named(
        emitters
            .iter()
            .map(|&i| format!("edge {i} (E = {})", edges[i].emission)),
    );
    let _ = match emitters.len() {
        0 => writeln!(w, "emitters: none"),
        1 => writeln!(w, "emitters: {list}"),
        n => writeln!(w, "emitters: {n}: {list}"),
    };
    let lights = scene.lights();
    if !lights.is_empty() {
        let list = named(
            lights
                .iter()
                .map(|l| format!("({}, {}) power {}", short(l.at.x), short(l.at.y), l.power)),
        );
        let _ = writeln!(w, "lights: {}: {list}", lights.len());
    }
    if !scene.is_lit() {
        let _ = writeln!(
            w,
            "warning: nothing emits, so zeta = 0 everywhere (relative errors are undefined)"
        );
    }
}

fn named(items: impl ExactSizeIterator<Item = String>) -> String {
    let more = items.len().saturating_sub(MAX_NAMED);
    let list: Vec<String> = items.take(MAX_NAMED).collect();
    match more {
        0 => list.join(", "),
        _ => format!("{} and {more} more", list.join(", ")),
    }
}

fn plural(n: usize, word: &str) -> String {
    if n == 1 {
        format!("1 {word}")
    } else {
        format!("{n} {word}s")
    }
}

/// `x` as written: a coordinate read from a drawing is an `f32` (SVG's precision), printed as
/// the shortest decimal of that `f32` (`8.2`, not `8.199999809265137`); any other as it is.
fn short(x: f64) -> String {
    // Rounding to f32 and back changes nothing only for a value that came from an f32.
    #[allow(clippy::cast_possible_truncation)]
    let single = x as f32;
    if f64::from(single) == x {
        single.to_string()
    } else {
        x.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 20: a floor plan of 10⁴ edges listed each of its 264 emitters on one line of 5288
    /// characters. Every line stays short on plans with many emitters, classified (under 512
    /// surfaces: pairs seen past many occluders) or not.
    #[test]
    fn large_scenes_print_short_lines() {
        for (edges, seed) in [(400, 5), (2000, 5)] {
            let scene = flatland_geom::generate::floor_plan(edges, seed).unwrap();
            let text = summary("plan", &scene);
            assert!(text.contains("emitters: "), "{text}");
            assert!(
                text.contains(" more"),
                "something is counted, not listed:\n{text}"
            );
            for line in text.lines() {
                assert!(
                    line.chars().count() <= 120,
                    "{} characters: {line}",
                    line.len()
                );
            }
        }
    }

    #[test]
    fn lists_name_the_first_items_and_count_the_rest() {
        let items = |n: usize| {
            (0..n)
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .into_iter()
        };
        assert_eq!(named(items(0)), "");
        assert_eq!(named(items(3)), "0, 1, 2");
        assert_eq!(named(items(MAX_NAMED)), "0, 1, 2, 3");
        assert_eq!(named(items(12)), "0, 1, 2, 3 and 8 more");
    }

    #[test]
    fn coordinates_from_a_drawing_print_as_drawn() {
        assert_eq!(short(f64::from(8.2_f32)), "8.2");
        assert_eq!(short(-10.5), "-10.5");
        // A value no f32 holds keeps every digit it has.
        assert_eq!(short(0.1), "0.1");
        assert_eq!(short(1.0 / 3.0), (1.0_f64 / 3.0).to_string());
    }
}
