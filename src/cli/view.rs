//! `rl view MODEL... [--env SCENE] [--srdf [I=]FILE] [--place [I=]POSE] [--path FILE] [--http
//! ADDR] [--coach ADDR]`: the robot viewer (RL's rlCoachMdl, and rlPlanDemo's view of an rlplan
//! scenario) as a local web page. Parses the arguments, starts [`rl_view::Viewer`], prints the
//! address and waits for Ctrl-C; the server is in rl-view.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use clap::Args;
use rl_rt::StopFlag;
use rl_sg::load::EmbeddedFiles;
use rl_view::{LoadOptions, ModelSource, RobotOptions, Viewer, ViewerOptions};

use super::output::{errln, outln};
use super::placement::{ScenarioRobot, is_scenario, parse_place, per_model};
use super::{CliError, CliResult};

/// RL's visual RV-6SL (its VRML meshes, byte for byte), compiled in: the default robot is drawn
/// as RL draws it.
const RV6SL_MESHES: [(&str, &str); 8] = [
    (
        "mitsubishi-rv6sl/mitsubishi-rv6sl.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/mitsubishi-rv6sl.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link0.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link0.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link1.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link1.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link2.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link2.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link3.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link3.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link4.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link4.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link5.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link5.wrl"),
    ),
    (
        "mitsubishi-rv6sl/link6.wrl",
        include_str!("../../tests/data/rlsg/mitsubishi-rv6sl/link6.wrl"),
    ),
];

/// The scene of the default robot alone (RL's rlsg and VRML conventions: the robot is the
/// scene's model `mitsubishi-rv6sl`, its bodies `link0`…`link6` as in RL's
/// `mitsubishi-rv6sl_boxes.xml`).
const RV6SL_SCENE_XML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<rlsg>
	<scene href="rv6sl.wrl">
		<model name="mitsubishi-rv6sl">
			<body name="link0"/><body name="link1"/><body name="link2"/><body name="link3"/>
			<body name="link4"/><body name="link5"/><body name="link6"/>
		</model>
	</scene>
</rlsg>
"#;
const RV6SL_SCENE_WRL: &str = r#"#VRML V2.0 utf8
Transform {
	children [
		DEF mitsubishi-rv6sl Transform {
			children [
				Inline { url "mitsubishi-rv6sl/mitsubishi-rv6sl.wrl" }
			]
		}
	]
}
"#;

/// The embedded RV-6SL that `rl run` drives, drawn with RL's visual meshes.
pub fn embedded_rv6sl() -> ModelSource {
    let mut files = EmbeddedFiles::new();
    files.add("rv6sl.xml", RV6SL_SCENE_XML);
    files.add("rv6sl.wrl", RV6SL_SCENE_WRL);
    for (path, text) in RV6SL_MESHES {
        files.add(path, text);
    }
    ModelSource::Embedded {
        name: "the embedded RV-6SL".into(),
        kinematics: rl::controller::RV6SL_XML.to_string(),
        scene: PathBuf::from("rv6sl.xml"),
        files: Arc::new(files),
    }
}

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
    /// A robot's SRDF: its allowed collision pairs and the named state it starts at (`home`,
    /// else `ready`, else the first `<group_state>`) [default: the .srdf beside a URDF (same
    /// stem); without one, adjacent links are not checked against each other]. `I=FILE` for
    /// robot I; without it, the first --srdf is robot 0's, the next robot 1's, … (repeatable).
    #[arg(long, value_name = "[I=]FILE")]
    pub srdf: Vec<String>,
    /// Where a robot's world frame stands in the scene: x,y,z (m) or x,y,z,rx,ry,rz (m,
    /// degrees about x, y, z applied as Rz·Ry·Rx, as RL's rlplan <world>); `I=POSE` for robot
    /// I, else in order (repeatable).
    #[arg(long, value_name = "[I=]POSE", allow_hyphen_values = true)]
    pub place: Vec<String>,
    /// URDF robots get a six-DOF root joint (q starts with x, y, z, qx, qy, qz, qw).
    #[arg(long)]
    pub floating_base: bool,
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
    #[arg(long, conflicts_with = "coach")]
    pub no_coach: bool,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// `I=FILE` or `FILE` (a path whose text before `=` is not a number is a path).
fn srdf_values(values: &[String]) -> Result<Vec<(usize, PathBuf)>, CliError> {
    let mut out: Vec<(usize, PathBuf)> = Vec::with_capacity(values.len());
    for (k, v) in values.iter().enumerate() {
        let (i, file) = match v.split_once('=') {
            Some((i, f)) if !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()) => {
                (i.parse::<usize>().unwrap_or(usize::MAX), f)
            }
            _ => (k, v.as_str()),
        };
        if out.iter().any(|(j, _)| *j == i) {
            return Err(CliError::usage(format!("--srdf: model {i} given twice")));
        }
        out.push((i, PathBuf::from(file)));
    }
    Ok(out)
}

/// The models, per-robot options and planning goal `args` give.
fn load_options(args: &ViewArgs) -> Result<LoadOptions, CliError> {
    let mut robots: Vec<RobotOptions> = Vec::new();
    let mut goal = None;
    let models = if args.models.is_empty() {
        vec![embedded_rv6sl()]
    } else {
        let mut scenes = 0;
        let mut models = Vec::with_capacity(args.models.len());
        for m in &args.models {
            if is_scenario(m) {
                models.push(scenario_model(
                    m,
                    args.models.len(),
                    &mut robots,
                    &mut goal,
                )?);
            } else if rl_view::load::is_rl_scene(m) {
                scenes += 1;
                models.push(ModelSource::RlScene {
                    scene: m.clone(),
                    kinematics: args.kinematics.clone(),
                });
            } else {
                models.push(ModelSource::File(m.clone()));
            }
        }
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
    fn robot(robots: &mut Vec<RobotOptions>, i: usize) -> &mut RobotOptions {
        if robots.len() <= i {
            robots.resize(i + 1, RobotOptions::default());
        }
        &mut robots[i]
    }
    for (i, x) in per_model(&args.place, "--place", |t| parse_place(t, "--place"))? {
        let r = robot(&mut robots, i);
        if r.place.is_some() {
            return Err(CliError::usage(format!(
                "--place: robot {i} comes from an RL scenario, which places it (<world>)"
            )));
        }
        r.place = Some(x);
    }
    for (i, f) in srdf_values(&args.srdf)? {
        robot(&mut robots, i).srdf = Some(f);
    }
    // URDF robots without --srdf take the SRDF beside them (rl-sg's one rule); robot indices
    // count an RL scene's robots (one per --kinematics).
    let mut index = 0;
    for m in &models {
        match m {
            ModelSource::File(path) => {
                if robots.get(index).is_none_or(|r| r.srdf.is_none()) {
                    if let Some(f) = rl_sg::load::srdf::for_robot(path, None) {
                        robot(&mut robots, index).srdf = Some(f);
                    }
                }
                index += 1;
            }
            ModelSource::RlScene { kinematics, .. } => index += kinematics.len(),
            _ => index += 1,
        }
    }
    Ok(LoadOptions {
        models,
        env: args.env.clone(),
        srdf: None,
        path: args.path.clone(),
        path_data: None,
        package_dirs: args.package_dirs.clone(),
        robots,
        floating_base: args.floating_base,
        goal,
    })
}

/// An RL planning scenario among the models: the scene and kinematics rlPlanDemo shows (its
/// viewer's model, RL's visual meshes), placed by its `<world>`, starting at its start, with
/// its goal as a ghost. Only as the only model.
fn scenario_model(
    path: &Path,
    count: usize,
    robots: &mut Vec<RobotOptions>,
    goal: &mut Option<Vec<f64>>,
) -> Result<ModelSource, CliError> {
    if count > 1 {
        return Err(CliError::usage(format!(
            "{}: an RL scenario is shown alone (it names its robot and scene)",
            path.display()
        )));
    }
    let s = ScenarioRobot::load(path, true)?;
    robots.push(RobotOptions {
        place: Some(s.place),
        srdf: None,
        start: Some(s.start),
    });
    *goal = Some(s.goal);
    Ok(ModelSource::RlScene {
        scene: s.scene,
        kinematics: vec![s.kinematics],
    })
}

/// Runs `rl view`.
pub fn run(args: ViewArgs) -> CliResult {
    let load = load_options(&args)?;
    let options = ViewerOptions {
        load,
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
        if args.duration.is_some_and(|d| start.elapsed() >= d) {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    viewer.shutdown();
    Ok(ExitCode::SUCCESS)
}
