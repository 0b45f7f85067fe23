//! `rl traj`: sample a trajectory through waypoints (issue 4; not built yet).

use clap::Args;

use super::{CliError, CliResult};

/// Arguments of `rl traj`.
#[derive(Args, Debug)]
pub struct TrajArgs {}

/// Runs `rl traj`.
pub fn run(_args: TrajArgs) -> CliResult {
    Err(CliError::failed("`rl traj` is not built yet (issue 4)"))
}
