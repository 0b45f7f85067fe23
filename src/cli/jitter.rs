//! `rl jitter` and `rl preflight` (issue 5; not built yet).

use clap::Args;

use super::{CliError, CliResult};

/// Arguments of `rl jitter`.
#[derive(Args, Debug)]
pub struct JitterArgs {}

/// Arguments of `rl preflight`.
#[derive(Args, Debug)]
pub struct PreflightArgs {}

/// Runs `rl jitter`.
pub fn run_jitter(_args: JitterArgs) -> CliResult {
    Err(CliError::failed("`rl jitter` is not built yet (issue 5)"))
}

/// Runs `rl preflight`.
pub fn run_preflight(_args: PreflightArgs) -> CliResult {
    Err(CliError::failed("`rl preflight` is not built yet (issue 5)"))
}
