//! Cost of one full control step (issue 7; being built).
fn main() {}
