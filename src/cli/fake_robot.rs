//! `rl fake-robot`: run a fake robot controller on loopback (issue 6; not built yet).

use clap::Subcommand;

use super::{CliError, CliResult};

/// Which fake robot to run.
#[derive(Subcommand, Debug)]
pub enum FakeRobotCommand {
    /// A fake Mitsubishi H7 controller (UDP real-time packets + R3 over TCP).
    H7,
    /// A Coach server (RL's visualisation protocol).
    Coach,
}

/// Runs `rl fake-robot`.
pub fn run(_cmd: FakeRobotCommand) -> CliResult {
    Err(CliError::failed("`rl fake-robot` is not built yet (issue 6)"))
}
