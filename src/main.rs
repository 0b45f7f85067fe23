//! The `rl` command line tool: look into robot models, sample trajectories, measure real-time
//! jitter, run fake robots, and run a complete controller (`rl run`, the default).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
    /// Sample a trajectory through waypoints from a CSV file.
    Traj(cli::traj::TrajArgs),
    /// Measure wake-up jitter of this crate's real-time loop (cyclictest-equivalent).
    Jitter(cli::jitter::JitterArgs),
    /// Report what stands between this machine and hard real time.
    Preflight(cli::jitter::PreflightArgs),
    /// Run a fake robot controller on loopback until Ctrl-C.
    #[command(subcommand)]
    FakeRobot(cli::fake_robot::FakeRobotCommand),
    /// Run a complete controller against a robot (the default: a fake robot on loopback).
    Run(cli::run::RunArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Model(cmd)) => cli::model::run(cmd),
        Some(Command::Traj(args)) => cli::traj::run(args),
        Some(Command::Jitter(args)) => cli::jitter::run_jitter(args),
        Some(Command::Preflight(args)) => cli::jitter::run_preflight(args),
        Some(Command::FakeRobot(cmd)) => cli::fake_robot::run(cmd),
        Some(Command::Run(args)) => cli::run::run(args),
        None => cli::run::run(cli::run::RunArgs::default()),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("rl: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
