//! `rl run --plan` from a program of your own: plan a collision-free path for a MotionBenchMaker
//! Panda problem (rl-plan), and follow it with the supervised real-time controller on a fake H7
//! standing at the problem's start. Ctrl-C cancels planning, or brings the arm to rest.
//!
//! `cargo run --release --example planned_run [PROBLEM]` (PROBLEM: a directory of
//! `tests/data/mbm/panda/problems`, default `box_panda`)

use std::path::Path;
use std::time::Duration;

use rl::controller::{ControlRun, RunOptions, planned};
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_plan::PlanOptions;
use rl_plan::problem::Robot;
use rl_plan::problem::moveit::MotionRequest;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "box_panda".into());
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mbm/panda");
    let urdf = data.join("panda.urdf");
    let problem = data.join("problems").join(&name);

    // The problem: the robot with its collision geometry, SRDF and spheres, the obstacles, and
    // the start and goal of the request.
    let robot = Robot::load_urdf(&urdf, None, None)?;
    let scene = rl::sg::load::moveit::load_environment(&problem.join("scene0001.yaml"))?;
    let (start, goal) =
        MotionRequest::load(&problem.join("request0001.yaml"))?.configurations(&robot.space)?;

    // Plan before anything starts; the run's stop flag (Ctrl-C) cancels planning too.
    let options = RunOptions {
        model_name: format!("Panda ({})", urdf.display()),
        device_name: "fake H7 in-process".into(),
        ..RunOptions::default().speed(0.5)
    };
    options.stop.raise_on_termination_signals()?;
    let loaded = rl::core::loader::load_file::<16>(&urdf)?;
    let mut checker = robot.hybrid_checker(&scene)?;
    let planned = planned::plan_motion::<16, 8>(
        &loaded.model,
        &robot.space,
        &mut checker,
        &start,
        &goal,
        &PlanOptions::default(),
        options.speed,
        Some(&options.stop),
    )?;
    eprintln!(
        "{name}: {} waypoints, {:.2} s trajectory ({:.2} s stopping at every waypoint)",
        planned.waypoints.len(),
        planned.duration_s,
        planned.stop_duration_s
    );
    if let Some(blend) = &planned.blend {
        eprintln!("{name}: {blend}");
    }

    // The fake arm stands at the start; a real one would have to (the run checks).
    let fake = FakeH7::spawn(FakeH7Config::for_model(&loaded.model, &start)?)?;
    let h7 = MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr()))?;
    let mut run = ControlRun::<_, 16, 8>::start_with(h7, loaded, options, planned.motion)?;
    while let Some(p) = run.poll(Duration::from_millis(500)) {
        eprintln!(
            "t {:5.2} s  tracking error {:.4} rad",
            p.time_s, p.error_max_rad
        );
    }
    let report = run.join();
    println!("{report}");
    std::process::exit(report.exit_code());
}
