//! The `rl` command line tool: look into robot models, sample trajectories, measure real-time
//! jitter, run fake robots, and run a complete controller (`rl run`, the default).

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

mod cli;

/// rl-rs: kinematics, dynamics, trajectories, devices and real-time loops for robots.
#[derive(Parser)]
#[command(name = "rl", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Inspect, evaluate and benchmark a robot model (URDF or RL XML).
    #[command(subcommand)]
    Model(cli::model::ModelCommand),
    /// Scene geometry: collision, distance and timing for a robot and its surroundings.
    #[command(subcommand)]
    Scene(cli::scene::SceneCommand),
    /// Sample a trajectory through waypoints from a CSV file.
    Traj(cli::traj::TrajArgs),
    /// Online trajectory generation from any state to any target state (JSONL jobs).
    Otg(cli::otg::OtgArgs),
    /// Measure wake-up jitter of this crate's real-time loop (cyclictest-equivalent).
    Jitter(cli::jitter::JitterArgs),
    /// Report what stands between this machine and hard real time.
    Preflight(cli::jitter::PreflightArgs),
    /// Run a fake robot controller on loopback until Ctrl-C.
    #[command(subcommand)]
    FakeRobot(cli::fake_robot::FakeRobotCommand),
    /// Plan a collision-free path (MoveIt scene and request, or an RL scenario); `plan bench`
    /// runs a MotionBenchMaker set.
    Plan(Box<cli::plan::PlanArgs>),
    /// Run a complete controller against a robot (the default: a fake robot on loopback).
    Run(Box<cli::run::RunArgs>),
    /// Show robots in a web browser, live over RL's Coach protocol (rlCoachMdl).
    View(cli::view::ViewArgs),
    /// A cell of machines over Zenoh (ROS 2's rmw_zenoh): `cell watch` prints what runs publish.
    #[command(subcommand)]
    Cell(cli::cell::CellCommand),
}

/// `command` and all its subcommands, recursively, with negative numbers accepted as values
/// (`--rate -5` reaches the range check instead of clap's "unexpected argument" tip).
fn allow_negative_numbers(command: clap::Command) -> clap::Command {
    let names: Vec<String> = command
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .collect();
    names
        .into_iter()
        .fold(command.allow_negative_numbers(true), |command, name| {
            command.mut_subcommand(name, allow_negative_numbers)
        })
}

fn main() -> ExitCode {
    let command = allow_negative_numbers(Cli::command());
    let matches = command.clone().get_matches();
    cli::record_given(&command, &matches);
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Some(Command::Model(cmd)) => cli::model::run(cmd),
        Some(Command::Scene(cmd)) => cli::scene::run(cmd),
        Some(Command::Traj(args)) => cli::traj::run(args),
        Some(Command::Otg(args)) => cli::otg::run(args),
        Some(Command::Jitter(args)) => cli::jitter::run_jitter(args),
        Some(Command::Preflight(args)) => cli::jitter::run_preflight(args),
        Some(Command::FakeRobot(cmd)) => cli::fake_robot::run(cmd),
        Some(Command::Plan(args)) => cli::plan::run(*args),
        Some(Command::Run(args)) => cli::run::run(*args),
        Some(Command::View(args)) => cli::view::run(args),
        Some(Command::Cell(cmd)) => cli::cell::run(cmd),
        None => cli::run::run(cli::run::RunArgs::default()),
    };
    match result {
        Ok(code) => code,
        Err(e) if e.is_closed_output() => ExitCode::from(e.exit_code()),
        Err(e) => {
            cli::output::errln!("rl: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
