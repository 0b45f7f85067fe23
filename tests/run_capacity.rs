//! The controller at the `rl` tool's largest capacity (issue 13: "the run loop and planner take
//! the same capacity choice"): `rl run` gives a model the smallest of the tool's capacities
//! (16, 64, 256 bodies and joints) and runs `ControlRun<_, N, N>` on it. Here a 101-joint arm
//! (tiago_dual's joint count) is planned, supervised and run to its end at `N = 256` against the
//! simulated robot; the CLI side (capacity messages, tiago_dual reaching the device) is in
//! `tests/model_cli.rs`.

mod common;
mod late;

use std::time::{Duration, Instant};

use common::sim::SimRobot;
use rl::controller::{ControlRun, RunEnd, RunOptions};
use rl::core::loader::{self, LoadOptions};
use rl::drivers::State;

const JOINTS: usize = 101;

/// A chain of `n` revolute joints alternating between z and y axes, 0.1 m apart, ±2 rad,
/// 1.5 rad/s, 1 kg links.
fn chain(n: usize) -> String {
    let mut text = String::from("<robot name=\"chain101\"><link name=\"l0\"/>");
    for k in 1..=n {
        let axis = if k % 2 == 0 { "0 1 0" } else { "0 0 1" };
        text += &format!(
            "<link name=\"l{k}\"><inertial><origin xyz=\"0 0 0.05\"/><mass value=\"1\"/>\
             <inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.005\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>\
             </inertial></link><joint name=\"j{k}\" type=\"revolute\"><parent link=\"l{}\"/>\
             <child link=\"l{k}\"/><origin xyz=\"0 0 0.1\"/><axis xyz=\"{axis}\"/>\
             <limit lower=\"-2\" upper=\"2\" velocity=\"1.5\" effort=\"1e6\"/></joint>",
            k - 1
        );
    }
    text + "</robot>"
}

/// Set-up at capacity 256 builds the planner's and the controller's 1.3 MB model workspaces, each
/// on the stack before it is boxed, beside `ControlRun::start`'s own 0.7 MB: more than a test
/// thread's 2 MB. It runs here on a thread with a program main thread's 8 MB, as in `rl run`.
#[test]
fn a_101_joint_arm_runs_at_the_largest_capacity() {
    std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(run_101_joints)
        .expect("thread")
        .join()
        .expect("the run at capacity 256 passed");
}

fn run_101_joints() {
    // Too big for the tool's smaller capacities: the loader says so, as the tool expects.
    let text = chain(JOINTS);
    assert!(loader::load_str_options::<64>(&text, &LoadOptions::default()).is_err());
    let loaded =
        loader::load_str_options::<256>(&text, &LoadOptions::default()).expect("loads at 256");
    assert_eq!(loaded.model.dof(), JOINTS);
    let period = Duration::from_millis(4);
    let lower = vec![-2.0; JOINTS];
    let upper = vec![2.0; JOINTS];
    let options = RunOptions {
        speed: 0.5,
        lock_memory: false,
        priority: 50,
        ..RunOptions::default()
    }
    .duration(Duration::from_millis(800));
    // Again while the run failed from the machine's lateness (the host held the loop's CPU).
    let attempt = || {
        let sim = SimRobot::new(&vec![0.0; JOINTS], &lower, &upper, period, 2);
        let status = sim.status();
        let mut run =
            ControlRun::<_, 256, 256>::start(sim, loaded.clone(), options.clone()).expect("starts");
        assert_eq!(run.joints().len(), JOINTS);
        let deadline = Instant::now() + Duration::from_secs(60);
        while run.poll(Duration::from_millis(20)).is_some() {
            assert!(Instant::now() < deadline, "the run did not end within 60 s");
        }
        (run.join(), status)
    };
    let Some((report, status)) = late::while_late("a 101-joint arm", attempt, |(report, _)| {
        late::failed_late(report)
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    let st = status.lock().expect("status");
    assert_eq!(st.stopped_from, Some(State::Running));
    assert_eq!(st.last_command.len(), JOINTS);
    // Every joint was commanded along the tour, the last one too.
    assert!(
        st.largest_step.iter().all(|&s| s > 0.0),
        "joints never moved: {:?}",
        st.largest_step
            .iter()
            .enumerate()
            .filter(|(_, s)| **s == 0.0)
            .map(|(k, _)| k)
            .collect::<Vec<_>>()
    );
}
