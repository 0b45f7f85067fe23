//! `rl run --zenoh ENDPOINT` / `--zenoh-listen ENDPOINT` (a run joined to a cell over Zenoh,
//! rl-cell's bridge) and `rl cell watch` (what a cell publishes). Built with the `zenoh`
//! feature; without it the flags are refused with the way to get them.

#[cfg(feature = "zenoh")]
use std::process::ExitCode;
use std::time::Duration;
#[cfg(feature = "zenoh")]
use std::time::Instant;

use clap::{Args, Subcommand};

use super::{CliError, CliResult};

/// Zenoh flags of `rl run`.
#[derive(Args, Debug, Default, Clone)]
#[command(next_help_heading = "Cell (Zenoh, ROS 2 over rmw_zenoh)")]
pub struct ZenohArgs {
    /// Join a cell: connect to this Zenoh endpoint (tcp/HOST:PORT; HOST:PORT means TCP),
    /// retried until it answers; repeatable. The run publishes its joint states (ROS 2
    /// sensor_msgs/JointState), run state, faults and report, and takes stop requests.
    #[arg(long = "zenoh", value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// Join a cell by listening on this endpoint (a bare PORT listens on 127.0.0.1);
    /// repeatable.
    #[arg(long = "zenoh-listen", value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// ROS namespace of the run's topics [default: /].
    #[arg(long = "zenoh-namespace", value_name = "NS")]
    pub namespace: Option<String>,
    /// ROS domain (the first part of every key) [default: $ROS_DOMAIN_ID or 0].
    #[arg(long = "zenoh-domain", value_name = "ID")]
    pub domain: Option<u32>,
    /// Publish the joint states of every N-th cycle [default: 1, every cycle].
    #[arg(long = "zenoh-decimate", value_name = "N")]
    pub decimate: Option<u32>,
    /// Before moving, wait up to this long (e.g. 5s) for a subscriber of the joint states, so
    /// a recorder on another machine sees the whole run [default: do not wait].
    #[arg(long = "zenoh-wait", value_name = "DURATION", value_parser = super::parse_duration)]
    pub wait: Option<Duration>,
}

impl ZenohArgs {
    /// Whether a cell was asked for.
    pub fn wanted(&self) -> bool {
        !self.connect.is_empty() || !self.listen.is_empty()
    }

    /// The flags that need a cell, given without `--zenoh` or `--zenoh-listen`.
    fn stray(&self) -> Option<&'static str> {
        [
            ("--zenoh-namespace", self.namespace.is_some()),
            ("--zenoh-domain", self.domain.is_some()),
            ("--zenoh-decimate", self.decimate.is_some()),
            ("--zenoh-wait", self.wait.is_some()),
        ]
        .into_iter()
        .find(|(_, on)| *on)
        .map(|(flag, _)| flag)
    }

    /// Checks the flags before anything starts.
    pub fn check(&self) -> Result<(), CliError> {
        if let Some(flag) = self.stray().filter(|_| !self.wanted()) {
            return Err(CliError::usage(format!(
                "{flag} configures a cell: add --zenoh ENDPOINT or --zenoh-listen ENDPOINT"
            )));
        }
        if self.wanted() && !cfg!(feature = "zenoh") {
            return Err(CliError::usage(
                "--zenoh/--zenoh-listen: this rl was built without Zenoh (build with \
                 `--features zenoh`)",
            ));
        }
        Ok(())
    }
}

/// `rl cell` subcommands.
#[derive(Subcommand, Debug)]
pub enum CellCommand {
    /// Print what a cell publishes: controllers and ROS nodes coming and going (liveliness),
    /// run states, faults and reports as they come, and joint states once a second per topic
    /// (rate, sequence gaps, latest positions).
    Watch(WatchArgs),
}

/// `rl cell watch`.
#[derive(Args, Debug)]
pub struct WatchArgs {
    /// Connect to this Zenoh endpoint (repeatable) [default: tcp/127.0.0.1:7447 when
    /// --listen is not given].
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// Listen on this endpoint instead (repeatable; a bare PORT is 127.0.0.1).
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// ROS domain [default: $ROS_DOMAIN_ID or 0].
    #[arg(long)]
    pub domain: Option<u32>,
    /// Watch only this namespace [default: / (all)].
    #[arg(long, default_value = "/")]
    pub namespace: String,
    /// Stop after this long (e.g. 10s) [default: until Ctrl-C].
    #[arg(long, value_parser = super::parse_duration)]
    pub duration: Option<Duration>,
    /// One JSON object per line instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The ROS domain from `--…-domain` or `$ROS_DOMAIN_ID` (0 if neither).
#[cfg(feature = "zenoh")]
fn domain(flag: Option<u32>) -> Result<u32, CliError> {
    match flag {
        Some(d) => Ok(d),
        None => match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) if !v.trim().is_empty() => v.trim().parse().map_err(|_| {
                CliError::usage(format!("ROS_DOMAIN_ID=`{v}` is not a domain number"))
            }),
            _ => Ok(0),
        },
    }
}

/// Runs `rl cell …`.
pub fn run(cmd: CellCommand) -> CliResult {
    match cmd {
        CellCommand::Watch(args) => watch(args),
    }
}

#[cfg(not(feature = "zenoh"))]
fn watch(_: WatchArgs) -> CliResult {
    Err(CliError::usage(
        "rl cell watch: this rl was built without Zenoh (build with `--features zenoh`)",
    ))
}

#[cfg(feature = "zenoh")]
fn watch(args: WatchArgs) -> CliResult {
    use std::collections::BTreeMap;

    use rl_cell::watch::{Body, Event, Watch};
    use rl_rt::StopFlag;

    use super::output::outln;

    let domain = domain(args.domain)?;
    let mut connect = args.connect.clone();
    if connect.is_empty() && args.listen.is_empty() {
        connect.push("tcp/127.0.0.1:7447".into());
    }
    let stop = StopFlag::new();
    stop.raise_on_termination_signals()
        .map_err(|e| CliError::failed(format!("cannot watch SIGINT/SIGTERM: {e}")))?;
    let w = Watch::open(&connect, &args.listen, domain, &args.namespace)
        .map_err(|e| CliError::usage(e.to_string()))?;
    eprintln!(
        "rl cell watch: zenoh session {} on {}, domain {domain}, namespace {}",
        w.zid(),
        if args.listen.is_empty() {
            format!("connect {}", connect.join(", "))
        } else {
            format!("listen {}", args.listen.join(", "))
        },
        args.namespace
    );
    /// A joint-state topic's last second.
    #[derive(Default)]
    struct Rate {
        count: u64,
        total: u64,
        gaps: u64,
        last_seq: Option<i64>,
        last: Option<rl_cell::ros2::msg::JointState>,
    }
    let mut rates: BTreeMap<String, Rate> = BTreeMap::new();
    let started = Instant::now();
    let mut summary_due = Instant::now() + Duration::from_secs(1);
    // One JSON object per line, each with the version key (docs/json.md).
    let versioned = |v: serde_json::Value| rl::json::versioned("cell.watch", 1, v).to_string();
    let json_token = |t: &rl_cell::ros2::names::Token| {
        serde_json::json!({"kind": t.kind, "namespace": t.namespace, "node": t.node,
            "topic": t.topic, "type": t.type_name, "zid": t.zid})
    };
    loop {
        if stop.is_stop_requested() || args.duration.is_some_and(|d| started.elapsed() >= d) {
            break;
        }
        let wait = summary_due
            .saturating_duration_since(Instant::now())
            .min(Duration::from_millis(100));
        if let Some(event) = w.next(wait) {
            let line = match event {
                Event::Joined(t) | Event::Left(t) if t.kind != "NN" && !args.json => {
                    // Publishers and subscriptions: one line each, the node's line says who.
                    let _ = t;
                    None
                }
                Event::Joined(t) => Some(if args.json {
                    versioned(serde_json::json!({"event": "joined", "entity": json_token(&t)}))
                } else {
                    format!(
                        "joined: node {} in {} (zenoh {})",
                        t.node, t.namespace, t.zid
                    )
                }),
                Event::Left(t) => Some(if args.json {
                    versioned(serde_json::json!({"event": "left", "entity": json_token(&t)}))
                } else {
                    format!("left: node {} in {} (zenoh {})", t.node, t.namespace, t.zid)
                }),
                Event::Message {
                    topic,
                    type_name,
                    attachment,
                    received_unix_ns,
                    body,
                } => match body {
                    Body::JointState(js) => {
                        let r = rates.entry(topic).or_default();
                        r.count += 1;
                        r.total += 1;
                        if let (Some(a), Some(last)) = (attachment, r.last_seq) {
                            if a.sequence_number > last + 1 {
                                r.gaps += (a.sequence_number - last - 1) as u64;
                            }
                        }
                        r.last_seq = attachment.map(|a| a.sequence_number);
                        r.last = Some(js);
                        None
                    }
                    Body::Text(text) => Some(if args.json {
                        versioned(
                            serde_json::json!({"event": "message", "topic": topic, "type": type_name,
                            "sequence": attachment.map(|a| a.sequence_number),
                            "age_s": attachment.map(|a| (received_unix_ns - a.source_timestamp) as f64 * 1e-9),
                            "text": text}),
                        )
                    } else {
                        format!("{topic}: {text}")
                    }),
                    other => Some(if args.json {
                        versioned(
                            serde_json::json!({"event": "message", "topic": topic, "type": type_name,
                            "sequence": attachment.map(|a| a.sequence_number),
                            "body": format!("{other:?}")}),
                        )
                    } else {
                        format!("{topic} ({type_name}): {other:?}")
                    }),
                },
            };
            if let Some(line) = line {
                outln!("{line}")?;
            }
        }
        if Instant::now() >= summary_due {
            summary_due += Duration::from_secs(1);
            for (topic, r) in rates.iter_mut().filter(|(_, r)| r.count > 0) {
                let positions = r
                    .last
                    .as_ref()
                    .map(|j| j.position.clone())
                    .unwrap_or_default();
                let line = if args.json {
                    versioned(
                        serde_json::json!({"event": "joint_states", "topic": topic, "per_s": r.count,
                        "total": r.total, "lost": r.gaps, "sequence": r.last_seq,
                        "names": r.last.as_ref().map(|j| j.name.clone()), "position": positions}),
                    )
                } else {
                    let shown: Vec<String> = positions.iter().map(|v| format!("{v:.4}")).collect();
                    format!(
                        "{topic}: {}/s, {} in all, {} lost, position [{}]",
                        r.count,
                        r.total,
                        r.gaps,
                        shown.join(", ")
                    )
                };
                outln!("{line}")?;
                r.count = 0;
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// A run joined to a cell (feature `zenoh`), or nothing.
#[cfg(feature = "zenoh")]
pub struct RunCell<const J: usize> {
    // The drain sink and the progress loop both hold it; only `forward` needs it mutably.
    cell: std::cell::RefCell<rl_cell::Cell<J>>,
    targets: std::sync::Arc<std::sync::OnceLock<rl::controller::InputSender<J, ()>>>,
    obstacles: std::sync::Arc<std::sync::OnceLock<ObstacleSink<J>>>,
}

/// Where the cell's obstacles go: the task-space law's input channel, each a sphere.
#[cfg(feature = "zenoh")]
struct ObstacleSink<const J: usize> {
    sender: rl::controller::InputSender<J, rl::controller::task_space::TaskInput>,
    radius: f64,
}

/// The longest gap between two poses of one obstacle over which its velocity is estimated
/// from their stamps, s (a longer one: at rest).
#[cfg(feature = "zenoh")]
const VELOCITY_GAP_S: f64 = 0.5;
/// The shortest such gap, s: two poses stamped closer say nothing reliable about a speed (a
/// tracker's jitter over microseconds is kilometres per second); the last velocity is kept.
#[cfg(feature = "zenoh")]
const VELOCITY_MIN_GAP_S: f64 = 0.005;

/// The cell's inbound for a run: targets to the run's input channel (`--follow zenoh`),
/// obstacles to the task-space law's (`--law … --obstacle zenoh`), each refused with the
/// reason otherwise.
#[cfg(feature = "zenoh")]
struct ToRun<const J: usize> {
    targets: std::sync::Arc<std::sync::OnceLock<rl::controller::InputSender<J, ()>>>,
    follows: bool,
    obstacles: std::sync::Arc<std::sync::OnceLock<ObstacleSink<J>>>,
    avoids: bool,
    /// Each obstacle's last position, its message's stamp (ns) and the velocity sent with it.
    last: [Option<(glam::DVec3, i64, glam::DVec3)>; rl_cell::inbound::MAX_OBSTACLES],
}

#[cfg(feature = "zenoh")]
impl<const J: usize> rl_cell::Inbound<J> for ToRun<J> {
    fn target(&mut self, target: &rl_cell::Target<J>, _: &rl_cell::Arrival) -> Result<(), String> {
        if !self.follows {
            return Err(
                "this run takes no streamed targets: it follows its planned motion (start it \
                 with --follow zenoh)"
                    .into(),
            );
        }
        let Some(sender) = self.targets.get() else {
            return Err("the run has not started yet".into());
        };
        let target = match *target {
            rl_cell::Target::Position { position, velocity } => {
                rl::controller::Target::Position { position, velocity }
            }
            rl_cell::Target::Velocity { velocity } => rl::controller::Target::Velocity { velocity },
        };
        sender.send_target(target).map_err(|e| e.to_string())
    }

    fn obstacle(&mut self, o: &rl_cell::Obstacle, _: &rl_cell::Arrival) -> Result<(), String> {
        use rl::controller::task_space::{Obstacle, TaskInput};
        if !self.avoids {
            return Err(
                "this run's law takes no obstacles (start it with --law cartesian-impedance \
                 --obstacle zenoh)"
                    .into(),
            );
        }
        let Some(sink) = self.obstacles.get() else {
            return Err("the run has not started yet".into());
        };
        use rl::controller::task_space::MAX_OBSTACLE_SPEED;
        let id = usize::from(o.id);
        let position = glam::DVec3::from_array(o.position);
        // The velocity from this obstacle's last pose, by the messages' own stamps, at most
        // the law's fastest; a pose stamped before the last one is refused.
        let last = self.last.get(id).copied().flatten();
        let velocity = match last {
            Some((_, stamp, _)) if o.stamp_ns < stamp => {
                return Err(format!(
                    "obstacle pose stamped {} ns before the last one of its name",
                    stamp - o.stamp_ns
                ));
            }
            Some((before, stamp, velocity)) => {
                let dt = (o.stamp_ns - stamp) as f64 * 1e-9;
                if dt < VELOCITY_MIN_GAP_S {
                    velocity
                } else if dt <= VELOCITY_GAP_S {
                    ((position - before) / dt).clamp_length_max(MAX_OBSTACLE_SPEED)
                } else {
                    glam::DVec3::ZERO
                }
            }
            None => glam::DVec3::ZERO,
        };
        let mut obstacle = Obstacle::sphere(position, sink.radius);
        obstacle.velocity = velocity;
        // A pose too close in time to its last keeps that last one's place as the velocity's
        // start.
        let keep = matches!(last, Some((_, stamp, _)) if ((o.stamp_ns - stamp) as f64) * 1e-9 < VELOCITY_MIN_GAP_S);
        if let (Some(slot), false) = (self.last.get_mut(id), keep) {
            *slot = Some((position, o.stamp_ns, velocity));
        }
        sink.sender
            .send(TaskInput::Obstacle {
                slot: id,
                obstacle: Some(obstacle),
            })
            .map_err(|e| e.to_string())
    }
}

#[cfg(not(feature = "zenoh"))]
pub struct RunCell<const J: usize>;

#[cfg(feature = "zenoh")]
impl<const J: usize> RunCell<J> {
    /// Joins the cell the flags name, for `model`'s joints at `period`; stop requests raise
    /// `stop`. `None` without `--zenoh`/`--zenoh-listen`.
    pub fn open<const B: usize>(
        args: &ZenohArgs,
        model: &rl_core::Model<B>,
        period: Duration,
        stop: &rl_rt::StopFlag,
        follows: bool,
        avoids: bool,
    ) -> Result<Option<Self>, CliError> {
        use rl::controller::plan::joint_name;
        if !args.wanted() {
            return Ok(None);
        }
        let dof = model.dof();
        let mut joints =
            rl_cell::JointLimits::unlimited((0..dof).map(|k| joint_name(model, k)).collect());
        for k in 0..dof {
            let l = model.limits(k);
            if !l.wraparound {
                joints.lower[k] = l.lower;
                joints.upper[k] = l.upper;
            }
            if l.velocity.is_finite() && l.velocity > 0.0 {
                joints.speed[k] = l.velocity;
            }
        }
        let config = rl_cell::CellConfig {
            connect: args.connect.clone(),
            listen: args.listen.clone(),
            domain: domain(args.domain)?,
            namespace: args.namespace.clone().unwrap_or_else(|| "/".into()),
            decimation: args.decimate.unwrap_or(1),
            period,
            wait_for_subscriber: args.wait,
            ..rl_cell::CellConfig::default()
        };
        // Streamed targets go to the run's input channel once it runs, with `--follow zenoh`,
        // obstacles to the task-space law's with `--obstacle zenoh`; otherwise they are
        // refused, counted, with the reason.
        let targets = std::sync::Arc::new(std::sync::OnceLock::new());
        let obstacles = std::sync::Arc::new(std::sync::OnceLock::new());
        let inbound = Box::new(ToRun {
            targets: targets.clone(),
            follows,
            obstacles: obstacles.clone(),
            avoids,
            last: [None; rl_cell::inbound::MAX_OBSTACLES],
        });
        let cell = rl_cell::Cell::open(config, joints, inbound, stop.clone())
            .map_err(|e| CliError::usage(format!("--zenoh: {e}")))?;
        if let Some(wait) = args.wait {
            match cell.subscriber_after_s() {
                Some(s) => eprintln!("rl run: the joint states have a subscriber (after {s:.2} s)"),
                None => eprintln!(
                    "rl run: warning: no subscriber of the joint states within {wait:?}; moving anyway"
                ),
            }
        }
        eprintln!(
            "rl run: joined the cell as zenoh {}; publishing {}",
            cell.zid(),
            cell.topics()
                .iter()
                .take(2)
                .map(|(t, _)| t.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
        Ok(Some(Self {
            cell: std::cell::RefCell::new(cell),
            targets,
            obstacles,
        }))
    }

    /// From now on, the cell's targets go to `sender` (the run's input channel).
    pub fn take_targets(&self, sender: rl::controller::InputSender<J, ()>) {
        let _ = self.targets.set(sender);
    }

    /// From now on, the cell's obstacles go to `sender` (the task-space law's input channel),
    /// each a sphere of `radius` m at its pose's position, moving at the velocity its last
    /// two poses' stamps give (slot: the obstacle's index among the names the cell has seen).
    pub fn take_obstacles(
        &self,
        sender: rl::controller::InputSender<J, rl::controller::task_space::TaskInput>,
        radius: f64,
    ) {
        let _ = self.obstacles.set(ObstacleSink { sender, radius });
    }

    /// Passes one cycle's record on (wait-free).
    pub fn forward(&self, r: &rl::controller::CycleRecord<J>) {
        self.cell.borrow_mut().forward(&rl_cell::Sample {
            cycle: r.cycle,
            commanded: r.commanded,
            measured: r.measured,
            effort: r.feed_forward,
        });
    }

    /// The run state from the loop's progress.
    pub fn progress(&self, p: &rl::controller::Progress) {
        self.cell
            .borrow()
            .set_state(state_json(p, None).to_string());
    }

    /// Publishes the end (state, fault, report), leaves the cell and adds what it did to the
    /// report (notes, and `zenoh` in the JSON).
    pub fn finish(self, report: &mut rl::controller::RunReport) -> serde_json::Value {
        let end = serde_json::json!({
            "state": "ended",
            "exit_code": report.exit_code(),
            "failure": report.failure,
        });
        let done = self.cell.into_inner().finish(
            end.to_string(),
            report.to_json().to_string(),
            report.failure.clone(),
        );
        report.notes.extend(done.lines());
        done.to_json()
    }
}

#[cfg(not(feature = "zenoh"))]
impl<const J: usize> RunCell<J> {
    /// Without Zenoh: never a cell (the flags were refused by [`ZenohArgs::check`]).
    pub fn open<const B: usize>(
        _: &ZenohArgs,
        _: &rl_core::Model<B>,
        _: Duration,
        _: &rl_rt::StopFlag,
        _: bool,
        _: bool,
    ) -> Result<Option<Self>, CliError> {
        Ok(None)
    }
    /// Nothing.
    pub fn take_targets(&self, _: rl::controller::InputSender<J, ()>) {}
    /// Nothing.
    pub fn take_obstacles(
        &self,
        _: rl::controller::InputSender<J, rl::controller::task_space::TaskInput>,
        _: f64,
    ) {
    }
    /// Nothing.
    pub fn forward(&self, _: &rl::controller::CycleRecord<J>) {}
    /// Nothing.
    pub fn progress(&self, _: &rl::controller::Progress) {}
    /// Nothing.
    pub fn finish(self, _: &mut rl::controller::RunReport) -> serde_json::Value {
        serde_json::Value::Null
    }
}

/// The run state published on `run_state`.
#[cfg_attr(not(feature = "zenoh"), allow(dead_code))]
fn state_json(p: &rl::controller::Progress, ended: Option<&str>) -> serde_json::Value {
    use rl_rt::StopLevel;
    let state = match (ended, p.faulted, p.stop, p.halting) {
        (Some(e), ..) => e,
        (None, true, ..) => "fault",
        (None, false, StopLevel::Now, _) => "stopping",
        (None, false, _, true) => "coming to rest",
        _ => "running",
    };
    serde_json::json!({
        "state": state,
        "cycle": p.cycle,
        "time_s": p.time_s,
        "tracking_error_max": p.error_max_rad,
        "worst_latency_us": p.worst_latency_ns as f64 / 1e3,
        "lost": p.lost,
        "stop": p.stop.to_string(),
    })
}
