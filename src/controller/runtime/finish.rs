//! Phase three of a run, after the loop: the device is brought to a safe state (stopped, from a
//! fault too, and closed) and everything the run measured is gathered into the [`RunReport`]:
//! how and when it ended, the loop's timing, the link, tracking, the inputs.

use std::thread;

use super::RunInfo;
use super::rt_loop::LoopOutcome;
use crate::controller::control::RunEnd;
use crate::controller::lateness::HostActivity;
use crate::controller::law::ControlLaw;
use crate::controller::plan::UNKNOWN_SPEED;
use crate::controller::report::{RunReport, Shutdown};
use crate::controller::robot::JointRobot;
use crate::controller::safety::SafetyReport;

/// The report of a run whose thread ended with `joined`; `dropped`: telemetry records the
/// queue could not take.
pub(super) fn report<R: JointRobot, const B: usize, const J: usize, L: ControlLaw<B, J>>(
    joined: thread::Result<Option<LoopOutcome<R, B, J, L>>>,
    mut info: RunInfo,
    dropped: Option<u64>,
) -> RunReport {
    let outcome = match joined {
        Ok(Some(o)) => o,
        Ok(None) | Err(_) => {
            let mut report = RunReport::failed_early(
                info.model,
                info.device,
                info.joints,
                "the control thread panicked; the device was not stopped by the run",
            );
            report.trajectory_source = info.trajectory_source;
            report.trajectory_description = info.trajectory_description;
            return report;
        }
    };
    let LoopOutcome {
        mut controller,
        stats,
        loop_error,
        run_delay,
    } = outcome;
    // What else ran: the host's times over the run, other programs' real-time threads seen
    // at its start or its end.
    let mut rt = std::mem::take(&mut info.rt_before);
    rt.extend(rl_rt::preflight::rt_threads::other_rt_threads());
    let host = HostActivity {
        loop_run_delay: run_delay,
        host: info
            .host_before
            .zip(rl_rt::HostTimes::read())
            .map(|(before, after)| after.since(&before)),
        other_rt: HostActivity::other_programs(&rt),
    };
    let shutdown = shut_down(controller.robot_mut());
    // The drives are off: the chain's brake output drops, its watchdog holds; it goes back to
    // its handle for the next run.
    let safety = controller.detach_safety().map(|chain| {
        let seen = SafetyReport::of(chain.as_ref());
        if let Some(handle) = &info.safety {
            handle.put_back(chain);
        }
        seen
    });
    let end = controller.end();
    let mut failure = loop_error.map(|e| format!("control loop: {e}"));
    match end {
        Some(RunEnd::Fault(f)) => {
            failure.get_or_insert(f.describe(&info.joints));
        }
        Some(e) if e.is_failure() => {
            failure.get_or_insert(e.to_string());
        }
        _ => {}
    }
    if let Some(s) = safety.filter(|s| s.brake_energised) {
        failure.get_or_insert(format!(
            "the safety chain's brake output stayed energised after the run ({:?})",
            s.state
        ));
    }
    if !shutdown.stopped {
        failure.get_or_insert(format!(
            "the device did not stop cleanly: {}",
            shutdown.error.as_deref().unwrap_or("unknown")
        ));
    }
    let tracking = controller.tracking();
    let bounds = controller.supervisor().bounds();
    let dof = info.joints.len();
    let summary = controller.law().summary();
    if let Some(why) = summary.as_ref().and_then(|s| s.failure.clone()) {
        failure.get_or_insert(why);
    }
    let assumed = (!info.assumed_speed.is_empty()).then_some((UNKNOWN_SPEED, info.assumed_speed));
    RunReport {
        model: info.model,
        device: info.device,
        joints: info.joints,
        period_s: info.period.as_secs_f64(),
        device_period_s: info.device_period.as_secs_f64(),
        scheduling: info.scheduling,
        warnings: info.warnings,
        memory_locked: info.memory_locked,
        plan_duration_s: info.plan_duration_s,
        trajectory_source: info.trajectory_source,
        trajectory_description: info.trajectory_description,
        trajectory_time_s: controller.time_s(),
        wall_time_s: info.started.elapsed().as_secs_f64(),
        end,
        fault_at: controller.fault_at(),
        stats,
        link: controller.link_statistics(),
        lost_packets: controller.failed_steps(),
        tracking_max: tracking.max_per_joint().to_vec(),
        tracking_rms: tracking.rms_per_joint()[..dof].to_vec(),
        tracking_final: tracking.last_error().to_vec(),
        tracking_bound: bounds.tracking[..dof].to_vec(),
        peak_feed_forward: tracking.peak_feed_forward().to_vec(),
        tracking_error_max: tracking.max_error(),
        tracking_error_rms: tracking.rms_error(),
        limit_violations: tracking.violations(),
        first_violation: tracking.first_violation(),
        supervised: controller.supervisor().is_enabled(),
        assumed_speed: assumed,
        torque_clamped: controller.torque_clamped(),
        inputs: controller.input_report().filter(|r| r.is_used()),
        law: summary.as_ref().map(|s| s.json.clone()),
        law_headline: summary.as_ref().map(|s| s.headline.clone()),
        safety,
        shutdown,
        telemetry_rows: None,
        telemetry_dropped: dropped,
        notes: summary.map(|s| s.lines).unwrap_or_default(),
        peer_lateness: None,
        host,
        failure,
    }
}

/// Stops the device (end of motion, power off; from a fault too) and closes it.
fn shut_down<R: JointRobot>(robot: &mut R) -> Shutdown {
    let mut shutdown = Shutdown {
        description: robot.stop_description().to_owned(),
        fault_before_stop: robot.fault().map(|e| e.to_string()),
        ..Shutdown::default()
    };
    match robot.stop() {
        Ok(()) => shutdown.stopped = true,
        Err(e) => shutdown.error = Some(e.to_string()),
    }
    if let Err(e) = robot.close() {
        shutdown.error.get_or_insert(e.to_string());
    }
    shutdown
}
