//! `rl run` (the default): a complete controller against a fake robot (issue 7; not built yet).

use clap::Args;

use super::{CliError, CliResult};

/// Arguments of `rl run`.
#[derive(Args, Debug, Default)]
pub struct RunArgs {}

/// Runs `rl run`.
pub fn run(_args: RunArgs) -> CliResult {
    Err(CliError::failed("`rl run` is not built yet (issue 7)"))
}
