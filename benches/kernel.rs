//! Kernel sampling benchmarks (filled in by the geometry issue).
fn main() {}
