//! `rl run --view [ADDR]`: the run's robot in the viewer's page (rl-view), served by this
//! process while the run goes. The library does the work ([`rl::controller::ViewHook`]: the
//! viewer on ordinary threads, the real-time loop publishing through its lock-free mailbox);
//! this starts it for the run's model, prints the address and, with `--view-hold`, keeps
//! serving after the report until Ctrl-C.

use std::time::Duration;

use rl::controller::ViewHook;
use rl_rt::{StopFlag, StopLevel};
use rl_view::ModelSource;

use super::RunArgs;
use crate::cli::CliError;

/// Starts the viewer for the run's model when `--view` is given, and prints its address.
pub(super) fn start(args: &RunArgs) -> Result<Option<ViewHook>, CliError> {
    let Some(http) = args.view else {
        return Ok(None);
    };
    let robot = match &args.model {
        Some(path) => ModelSource::File(path.clone()),
        // Drawn with RL's visual meshes.
        None => crate::cli::view::embedded_rv6sl(),
    };
    // A planned run shows its obstacles too; a URDF robot's allowed pairs are the SRDF's it
    // plans with (--srdf, else the one beside the URDF: rl-sg's one rule).
    let srdf = args
        .model
        .as_deref()
        .and_then(|m| rl_sg::load::srdf::for_robot(m, args.srdf.as_deref()));
    let load = rl_view::LoadOptions {
        models: vec![robot],
        env: args.scene.clone().filter(|_| args.plan),
        srdf,
        ..rl_view::LoadOptions::default()
    };
    let hook =
        ViewHook::start_with(load, http).map_err(|e| CliError::usage(format!("--view: {e}")))?;
    let viewer = hook.viewer();
    for w in viewer.warnings() {
        eprintln!("rl run: view: note: {w}");
    }
    if !rl_view::is_loopback(&viewer.http_addr()) {
        eprintln!(
            "rl run: warning: the view listens on {} beyond this machine and has no \
             authentication",
            viewer.http_addr()
        );
    }
    eprintln!("rl run: view: open {}", viewer.url());
    Ok(Some(hook))
}

/// Tells the page how the run ended (the report's end and failure, in one line), and that it
/// is running until then.
pub(super) fn ended(view: &Option<ViewHook>, report: &rl::controller::RunReport) {
    let Some(view) = view else { return };
    let how = match (&report.failure, &report.end) {
        (Some(why), _) => format!("failed: {why}"),
        (None, Some(end)) => end.to_string(),
        (None, None) => "the loop did not report how it ended".into(),
    };
    let ok = report.exit_code() == 0;
    view.viewer().set_run_status(rl_view::RunStatus {
        ended: true,
        ok,
        summary: format!(
            "{how} after {:.2} s ({:.2} of {:.2} s of the trajectory), exit code {}",
            report.wall_time_s,
            report.trajectory_time_s,
            report.plan_duration_s,
            report.exit_code()
        ),
    });
}

/// Tells the page a run is going.
pub(super) fn running(view: &Option<ViewHook>) {
    let Some(view) = view else { return };
    view.viewer().set_run_status(rl_view::RunStatus {
        ended: false,
        ok: true,
        summary: "running".into(),
    });
}

/// With `--view-hold`, keeps the viewer serving after the report until a (further) Ctrl-C;
/// otherwise it stops with the run.
pub(super) fn hold(view: Option<ViewHook>, hold: bool, stop: &StopFlag) {
    let Some(view) = view else { return };
    if !hold {
        return;
    }
    let level = stop.level();
    if level == StopLevel::Now {
        return;
    }
    eprintln!(
        "rl run: view: still serving {} (Ctrl-C to end)",
        view.viewer().url()
    );
    while stop.level() == level {
        std::thread::sleep(Duration::from_millis(50));
    }
}
