//! `rl model info | eval | bench` (issue 2).

use clap::Subcommand;

use super::{CliError, CliResult};

/// `rl model` subcommands.
#[derive(Subcommand, Debug)]
pub enum ModelCommand {
    /// Joints, DOF, mass and tools of a model file.
    Info,
}

/// Runs `rl model`.
pub fn run(_cmd: ModelCommand) -> CliResult {
    Err(CliError::failed("`rl model` is not built yet"))
}
