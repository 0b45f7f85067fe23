//! Trajectory benchmarks (issue 4; being built).
fn main() {}
