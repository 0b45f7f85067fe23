//! `rl fake-robot`: run a fake robot controller on loopback until Ctrl-C, printing one status
//! line per second, so RL's programs or ours can be pointed at it without hardware.

use std::fmt::Write as _;
use std::net::SocketAddr;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::{Args, Subcommand};
use nix::sys::signal::{SigSet, Signal};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};

use super::{CliError, CliResult};

/// Which fake robot to run.
#[derive(Subcommand, Debug)]
pub enum FakeRobotCommand {
    /// A fake Mitsubishi H7 controller (UDP real-time packets + R3 over TCP).
    H7(H7Args),
    /// A Coach server (RL's visualisation protocol).
    Coach(CoachArgs),
}

/// Arguments of `rl fake-robot h7`.
#[derive(Args, Debug)]
pub struct H7Args {
    /// UDP address for real-time packets.
    #[arg(long, default_value = "127.0.0.1:10000")]
    pub bind: SocketAddr,
    /// TCP address of the R3 command responder.
    #[arg(long, default_value = "127.0.0.1:10001")]
    pub r3_bind: SocketAddr,
    /// Number of simulated joints (1 to 8; taken from --model when one is given).
    #[arg(long, default_value_t = 6)]
    pub dof: usize,
    /// A robot model (URDF or RL XML) whose joint count and position and speed limits the
    /// simulated arm takes.
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// Time constant of the controller's filter, in 7.11 ms cycles.
    #[arg(long, default_value_t = 2)]
    pub filter_cycles: u32,
    /// Stop after this many seconds instead of waiting for Ctrl-C.
    #[arg(long)]
    pub seconds: Option<u64>,
}

/// Arguments of `rl fake-robot coach`.
#[derive(Args, Debug)]
pub struct CoachArgs {
    /// TCP address to listen on.
    #[arg(long, default_value = "127.0.0.1:11235")]
    pub bind: SocketAddr,
    /// Stop after this many seconds instead of waiting for Ctrl-C.
    #[arg(long)]
    pub seconds: Option<u64>,
}

/// Runs `rl fake-robot`.
pub fn run(cmd: FakeRobotCommand) -> CliResult {
    // Block SIGINT/SIGTERM before any thread starts (threads inherit the mask), and let one
    // thread wait for them synchronously: no signal handler, no unsafe code.
    let stop = interrupt_flag()?;
    match cmd {
        FakeRobotCommand::H7(args) => run_h7(&args, &stop),
        FakeRobotCommand::Coach(args) => run_coach(&args, &stop),
    }
}

fn interrupt_flag() -> Result<Arc<AtomicBool>, CliError> {
    let mut set = SigSet::empty();
    set.add(Signal::SIGINT);
    set.add(Signal::SIGTERM);
    set.thread_block()
        .map_err(|e| CliError::failed(format!("cannot block SIGINT: {e}")))?;
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if set.wait().is_ok() {
                f.store(true, Ordering::Relaxed);
            }
        })
        .map_err(|e| CliError::failed(format!("cannot start the signal thread: {e}")))?;
    Ok(flag)
}

/// Calls `status` once per second until Ctrl-C or `seconds` have passed.
fn every_second(stop: &AtomicBool, seconds: Option<u64>, mut status: impl FnMut(u64)) {
    let start = Instant::now();
    let mut next = 1;
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(50));
        let elapsed = start.elapsed().as_secs();
        if elapsed >= next {
            status(elapsed);
            next = elapsed + 1;
        }
        if seconds.is_some_and(|s| elapsed >= s) {
            break;
        }
    }
}

fn joints(q: &[f64]) -> String {
    let mut s = String::from("[");
    for (i, v) in q.iter().enumerate() {
        let _ = write!(s, "{}{v:.4}", if i > 0 { ", " } else { "" });
    }
    s.push(']');
    s
}

fn run_h7(args: &H7Args, stop: &AtomicBool) -> CliResult {
    let mut limits = None;
    let mut dof = args.dof;
    if let Some(path) = &args.model {
        let file = super::model::ModelFile {
            file: path.clone(),
            floating_base: false,
            joint_order: super::model::Order::File,
            mimic_independent: false,
        };
        let loaded = super::model::load(&file)?;
        let m = &loaded.model;
        if m.nq() != m.dof() {
            return Err(CliError::usage(format!(
                "--model {}: the fake H7 simulates plain joints; this model has quaternion joints",
                path.display()
            )));
        }
        dof = m.dof();
        let lower: Vec<f64> = (0..dof).map(|k| m.limits(k).lower).collect();
        let upper: Vec<f64> = (0..dof).map(|k| m.limits(k).upper).collect();
        // A model without a speed limit (RL writes 0 for "none") leaves the joint unlimited.
        let speed: Vec<f64> = (0..dof)
            .map(|k| m.limits(k).velocity)
            .map(|v| if v > 0.0 { v } else { f64::INFINITY })
            .collect();
        limits = Some((lower, upper, speed));
    }
    if dof == 0 || dof > 8 {
        return Err(CliError::usage(format!("--dof {dof}: must be 1 to 8")));
    }
    let mut config = FakeH7Config::loopback(dof);
    if let Some((lower, upper, speed)) = limits {
        let bad = |e: std::io::Error| CliError::usage(format!("--model: {e}"));
        config = config.with_limits(&lower, &upper).map_err(bad)?;
        config = config.with_speed_limits(&speed).map_err(bad)?;
    }
    config.udp_bind = args.bind;
    config.r3_bind = Some(args.r3_bind);
    config.filter_cycles = args.filter_cycles;
    let mut fake = FakeH7::spawn(config).map_err(|e| {
        CliError::failed(format!("fake H7 on {} / {}: {e}", args.bind, args.r3_bind))
    })?;
    println!(
        "fake H7 controller ({} joints): real-time UDP on {}, R3 on {}; Ctrl-C to stop",
        dof,
        fake.udp_addr(),
        fake.r3_addr()
    );
    let mut last = 0;
    every_second(stop, args.seconds, |t| {
        let s = fake.status();
        let rate = s.packets - last;
        last = s.packets;
        println!(
            "t={t}s packets={} ({rate}/s) moves={} ends={} bad={} servo={} program={} commanded={} actual={}",
            s.packets,
            s.moves,
            s.ends,
            s.bad_packets,
            if s.servo_on { "on" } else { "off" },
            if s.program_running {
                "running"
            } else {
                "stopped"
            },
            joints(&s.commanded_rad[..s.dof]),
            joints(&s.actual_rad[..s.dof]),
        );
    });
    fake.shutdown();
    println!("fake H7 controller stopped");
    Ok(ExitCode::SUCCESS)
}

fn run_coach(args: &CoachArgs, stop: &AtomicBool) -> CliResult {
    let config = CoachServerConfig {
        bind: args.bind,
        ..CoachServerConfig::loopback()
    };
    let mut server = CoachServer::spawn(config)
        .map_err(|e| CliError::failed(format!("Coach server on {}: {e}", args.bind)))?;
    println!("Coach server on {}; Ctrl-C to stop", server.addr());
    every_second(stop, args.seconds, |t| {
        let s = server.status();
        let mut models: Vec<_> = s.joints.iter().collect();
        models.sort_by_key(|(m, _)| **m);
        let mut line = format!(
            "t={t}s clients={} lines={} requests={} bad={} bodies={} shapes={}",
            s.clients,
            s.lines,
            s.requests,
            s.bad_lines,
            s.bodies.len(),
            s.shapes.len()
        );
        for (m, q) in models {
            let _ = write!(line, " model{m}={}", joints(q));
        }
        println!("{line}");
    });
    server.shutdown();
    println!("Coach server stopped");
    Ok(ExitCode::SUCCESS)
}
