//! Import time of drawings of about 10⁴ segments: a generated floor plan written as SVG (solids
//! and faced lines), 10⁴ `<line>` elements (a CAD export), and one filled path of 10⁴ pieces
//! (a fine outline: the crossing check's worst realistic case); and usvg's reading alone.

use std::fmt::Write as _;
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::generate;
use flatland_svg::{ImportParams, import, scene_svg};

fn lines(n: usize) -> String {
    let mut svg = String::from(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 1000 1000\"><g stroke=\"black\" fill=\"none\">",
    );
    // A grid of short walls with gaps, none overlapping.
    let side = (n as f64).sqrt().ceil() as usize;
    for k in 0..n {
        let (i, j) = ((k % side) as f64, (k / side) as f64);
        let _ = write!(
            svg,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
            i * 10.0,
            j * 10.0,
            i * 10.0 + 7.0,
            j * 10.0 + 3.0
        );
    }
    svg.push_str("</g></svg>");
    svg
}

fn star(n: usize) -> String {
    let mut d = String::new();
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        let r = if k % 2 == 0 { 400.0 } else { 380.0 };
        let _ = write!(
            d,
            "{}{} {} ",
            if k == 0 { 'M' } else { 'L' },
            500.0 + r * a.cos(),
            500.0 + r * a.sin()
        );
    }
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 1000 1000\"><path d=\"{d}Z\" data-flatland-emission=\"1\"/></svg>"
    )
}

fn bench(c: &mut Criterion) {
    let plan = scene_svg(&generate::floor_plan(10_000, 1).unwrap(), "plan");
    let cases = [
        ("import/floor_plan_10k", plan),
        ("import/lines_10k", lines(10_000)),
        ("import/one_path_10k", star(10_000)),
    ];
    let params = ImportParams::default();
    for (name, svg) in &cases {
        let edges = import(svg.as_bytes(), &params)
            .unwrap()
            .scene()
            .edges()
            .len();
        eprintln!("{name}: {} bytes, {edges} edges", svg.len());
        c.bench_function(name, |b| {
            b.iter(|| import(black_box(svg.as_bytes()), &params).unwrap())
        });
    }
    // What the SVG reader alone takes, for comparison.
    let options = usvg::Options::default();
    for (name, svg) in &cases {
        let name = name.replace("import/", "usvg_only/");
        c.bench_function(&name, |b| {
            b.iter(|| usvg::Tree::from_str(black_box(svg), &options).unwrap())
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
