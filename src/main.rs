//! The `flatland` command line.
fn main() {}
