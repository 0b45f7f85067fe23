//! `rl view MODEL... [--env SCENE] [--srdf FILE] [--path FILE] [--http ADDR] [--coach ADDR]`:
//! the robot viewer (RL's rlCoachMdl) as a local web page. Parses the arguments, starts
//! [`rl_view::Viewer`], prints the address and waits for Ctrl-C; the server is in rl-view.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use rl_rt::StopFlag;
use rl_view::{LoadOptions, ModelSource, Viewer, ViewerOptions};

use super::output::{errln, outln};
use super::{CliError, CliResult};

/// Arguments of `rl view`.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// Robots to show (URDF or RL XML), in Coach model order (the first is model 0). None: the
    /// embedded RV-6SL that `rl run` drives.
    pub models: Vec<PathBuf>,
    /// Obstacles: a MoveIt planning scene (.yaml, as `rl plan --scene`), an RL scene (rlsg XML
    /// or .wrl) or a URDF.
    #[arg(long, value_name = "SCENE")]
    pub env: Option<PathBuf>,
    /// Allowed collision pairs of the first model (SRDF; default: adjacent links are not
    /// checked against each other).
    #[arg(long, value_name = "FILE")]
    pub srdf: Option<PathBuf>,
    /// A path to play back for the first model: the CSV of `rl plan --out` or
    /// `--trajectory`.
    #[arg(long, value_name = "FILE")]
    pub path: Option<PathBuf>,
    /// An RL scene (rlsg XML) among the models: the rlmdl files of its first models, in order
    /// (repeatable), as RL's `rlCoachMdl scene.xml model.xml …`; its other models are
    /// obstacles.
    #[arg(long, value_name = "FILE")]
    pub kinematics: Vec<PathBuf>,
    /// Where `package://` URIs are looked up (repeatable).
    #[arg(long = "package-dir", value_name = "DIR")]
    pub package_dirs: Vec<PathBuf>,
    /// Address of the page (HTTP and WebSocket); port 0 picks a free one. The page has no
    /// authentication: keep it on loopback unless the network is trusted.
    #[arg(long, value_name = "ADDR", default_value_t = rl_view::DEFAULT_HTTP)]
    pub http: SocketAddr,
    /// Address of the Coach listener (RL's visualisation protocol).
    #[arg(long, value_name = "ADDR", default_value_t = rl_view::DEFAULT_COACH)]
    pub coach: SocketAddr,
    /// No Coach listener.
    #[arg(long)]
    pub no_coach: bool,
    /// Stop after this many seconds instead of waiting for Ctrl-C.
    #[arg(long)]
    pub seconds: Option<u64>,
}

/// Runs `rl view`.
pub fn run(args: ViewArgs) -> CliResult {
    let models = if args.models.is_empty() {
        vec![ModelSource::Text {
            name: "the embedded RV-6SL".into(),
            text: rl::controller::RV6SL_XML.to_string(),
        }]
    } else {
        let mut scenes = 0;
        let models: Vec<ModelSource> = args
            .models
            .iter()
            .map(|m| {
                if rl_view::load::is_rl_scene(m) {
                    scenes += 1;
                    ModelSource::RlScene {
                        scene: m.clone(),
                        kinematics: args.kinematics.clone(),
                    }
                } else {
                    ModelSource::File(m.clone())
                }
            })
            .collect();
        if scenes > 1 {
            return Err(CliError::usage("give at most one RL scene (rlsg XML)"));
        }
        models
    };
    if !args.kinematics.is_empty()
        && !models
            .iter()
            .any(|m| matches!(m, ModelSource::RlScene { .. }))
    {
        return Err(CliError::usage(
            "--kinematics goes with an RL scene (rlsg XML) among the models",
        ));
    }
    let options = ViewerOptions {
        load: LoadOptions {
            models,
            env: args.env.clone(),
            srdf: args.srdf.clone(),
            path: args.path.clone(),
            package_dirs: args.package_dirs.clone(),
        },
        http: args.http,
        coach: (!args.no_coach).then_some(args.coach),
    };
    // Signals are blocked before the server's threads start, so the watcher gets them.
    let stop = StopFlag::new();
    stop.raise_on_termination_signals()
        .map_err(|e| CliError::failed(format!("cannot watch SIGINT/SIGTERM: {e}")))?;
    let mut viewer = Viewer::start(&options).map_err(|e| CliError::usage(e.to_string()))?;
    for w in viewer.warnings() {
        errln!("rl view: note: {w}");
    }
    if !rl_view::is_loopback(&viewer.http_addr()) {
        errln!(
            "rl view: warning: the page listens on {} beyond this machine and has no \
             authentication: anyone who reaches it can move the models shown",
            viewer.http_addr()
        );
    }
    if let Some(c) = viewer.coach_addr() {
        if !rl_view::is_loopback(&c) {
            errln!("rl view: warning: the Coach listener on {c} accepts anyone who reaches it");
        }
    }
    outln!("rl view: open {}", viewer.url())?;
    if let Some(c) = viewer.coach_addr() {
        outln!("rl view: Coach listening on {c}")?;
    }
    let start = std::time::Instant::now();
    while !stop.is_stop_requested() {
        if args
            .seconds
            .is_some_and(|s| start.elapsed() >= Duration::from_secs(s))
        {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    viewer.shutdown();
    Ok(ExitCode::SUCCESS)
}
