//! Dynamics benchmarks (issue 3; being built).
fn main() {}
