//! The bridge: a Zenoh session and a thread of its own between a running controller and the
//! cell, never the real-time thread.
//!
//! ```text
//!  real-time loop ──CycleRecord──▶ rl-rt queue ──▶ caller's drain ──Sample──▶ rl-rt queue ─┐
//!  (unchanged)                     (the run's own telemetry)   Cell::forward (wait-free)   │
//!                                                                                          ▼
//!                        joint_states, joint_commands, run_state, fault, report ◀── bridge thread
//!  StopFlag ◀── stop ◀──┐                                                           (encodes, puts)
//!  Inbound  ◀── checks ◀┴── joint_trajectory, obstacles/<name>  (Zenoh's receive threads)
//! ```
//!
//! Out: the loop's records reach the bridge through the run's own telemetry queue (which the
//! caller drains, as it does for the CSV) and [`Cell::forward`], a wait-free push into a second
//! queue and a wake-up of the bridge thread. The bridge thread turns every `decimation`-th
//! sample into two `sensor_msgs/JointState` (measured: position and velocity; commanded:
//! position, velocity and the feed-forward effort), each with rmw_zenoh's attachment, and
//! publishes the run state (JSON) when it changes, at most ten times a second. A full queue
//! drops the newest sample and counts it; a publication Zenoh refuses is counted too.
//! Publications use congestion control `Drop`: a slow or lost peer never blocks the bridge
//! (and never the loop, which does not wait for the bridge at all).
//!
//! In: Zenoh calls back on its own threads; each sample is checked
//! ([`crate::inbound`]) and handed on, or refused and counted.
//!
//! Velocities are backward differences of consecutive samples' positions over the loop's
//! period (cycles apart × period). A sample's `header.stamp` is the cycle's time on the loop's
//! grid: `start + cycle × period`, `start` estimated from the wall clock when the samples reach
//! the bridge (the earliest of the first 1000, so the estimate errs late by the shortest
//! hand-over, typically under a millisecond). The estimate only moves earlier, and only over the
//! first 1000 samples (a stamp may then step by less than a period); from then on the stamps are
//! exactly a period apart.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use rl_rt::exchange::{QueueReceiver, QueueSender, queue};
use rl_rt::{StopFlag, StopLevel};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::sample::Sample as ZSample;

use crate::config::{CellConfig, CellError, unix_now_ns};
use crate::inbound::{
    self, Gate, Inbound, InboundCounts, JointLimits, Kind, ObstacleMsg, Refusal, TopicCounts,
};
use crate::ros2::attachment::Attachment;
use crate::ros2::msg::{
    self, JOINT_STATE, JOINT_TRAJECTORY, JointTrajectory, Message, POINT_STAMPED, POSE_STAMPED,
    PointStamped, PoseStamped, STRING, Text, Time,
};
use crate::ros2::names::{Entity, EntityKind, topic_key};
use crate::ros2::type_hash::TypeDescription;

/// What the loop did in one cycle, as the bridge publishes it: the caller copies it out of
/// the run's own per-cycle record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const J: usize> {
    /// Cycle index.
    pub cycle: u64,
    /// The position commanded for this cycle, rad or m.
    pub commanded: [f64; J],
    /// The measured position.
    pub measured: [f64; J],
    /// The commanded effort (feed-forward torque), N·m or N.
    pub effort: [f64; J],
}

/// History depth announced in the liveliness tokens (rmw_zenoh's QoS part).
const DEPTH: u32 = 10;
/// The run state is published at most this often.
const STATE_INTERVAL: Duration = Duration::from_millis(100);
/// The bridge thread looks at its queue at least this often.
const IDLE_WAKE: Duration = Duration::from_millis(2);

/// One topic this cell publishes: a Zenoh publisher, its liveliness token and GID, and its
/// sequence numbers.
struct Out {
    publisher: Publisher<'static>,
    _token: LivelinessToken,
    gid: [u8; 16],
    sequence: i64,
    published: u64,
    failed: u64,
}

impl Out {
    fn put(&mut self, payload: &[u8]) {
        self.sequence += 1;
        let attachment = Attachment {
            sequence_number: self.sequence,
            source_timestamp: unix_now_ns(),
            source_gid: self.gid,
        };
        match self
            .publisher
            .put(payload.to_vec())
            .attachment(attachment.to_bytes().to_vec())
            .wait()
        {
            Ok(()) => self.published += 1,
            Err(_) => self.failed += 1,
        }
    }
}

/// Counts of what went out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutboundCounts {
    /// Samples handed to [`Cell::forward`].
    pub forwarded: u64,
    /// Samples dropped because the bridge's queue was full.
    pub dropped: u64,
    /// Samples the bridge encoded (every one forwarded and not dropped).
    pub handled: u64,
    /// `JointState` messages published (measured and commanded).
    pub joint_states: u64,
    /// Publications Zenoh refused.
    pub failed: u64,
    /// Run states published.
    pub states: u64,
}

/// What a cell did, for the run's report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellReport {
    /// The Zenoh session id.
    pub zid: String,
    /// Outbound counts.
    pub outbound: OutboundCounts,
    /// Inbound counts.
    pub inbound: InboundCounts,
    /// The topics published and subscribed, with their data key expressions.
    pub topics: Vec<(String, String)>,
    /// With [`CellConfig::wait_for_subscriber`]: how long until the measured joint states had
    /// a subscriber, s (`None`: none came in time, or no wait was asked for).
    pub subscriber_after_s: Option<f64>,
}

impl CellReport {
    /// The report as JSON.
    pub fn to_json(&self) -> serde_json::Value {
        let topic = |t: &TopicCounts| {
            serde_json::json!({
                "received": t.received,
                "accepted": t.accepted,
                "refused": t.refused_total(),
                "refused_by_reason": t.refused.iter().map(|(k, n)| (k.to_string(), serde_json::json!(n))).collect::<serde_json::Map<_, _>>(),
                "first_refusal": t.first_refusal,
                "lost": t.lost,
                "max_age_s": t.max_age_s,
            })
        };
        serde_json::json!({
            "zid": self.zid,
            "subscriber_after_s": self.subscriber_after_s,
            "outbound": {
                "forwarded": self.outbound.forwarded,
                "dropped": self.outbound.dropped,
                "handled": self.outbound.handled,
                "joint_states": self.outbound.joint_states,
                "failed": self.outbound.failed,
                "states": self.outbound.states,
            },
            "inbound": {
                "targets": topic(&self.inbound.targets),
                "obstacles": topic(&self.inbound.obstacles),
                "stops": topic(&self.inbound.stops),
                "obstacle_names": self.inbound.obstacle_names,
            },
            "topics": self.topics.iter().map(|(t, k)| serde_json::json!({"topic": t, "key": k})).collect::<Vec<_>>(),
        })
    }

    /// One line per direction, for the text report.
    pub fn lines(&self) -> Vec<String> {
        let o = &self.outbound;
        let mut lines = vec![format!(
            "zenoh {}: {} samples forwarded, {} dropped (bridge queue full), {} joint states \
             published, {} publications refused, {} run states",
            self.zid, o.forwarded, o.dropped, o.joint_states, o.failed, o.states
        )];
        for (what, t) in [
            ("targets", &self.inbound.targets),
            ("obstacles", &self.inbound.obstacles),
            ("stop requests", &self.inbound.stops),
        ] {
            if t.received > 0 {
                lines.push(format!(
                    "zenoh {what}: {} received, {} accepted, {} refused{}, {} lost on the way, \
                     oldest accepted {:.1} ms",
                    t.received,
                    t.accepted,
                    t.refused_total(),
                    t.first_refusal
                        .as_ref()
                        .map(|r| format!(" (first: {r})"))
                        .unwrap_or_default(),
                    t.lost,
                    t.max_age_s * 1e3
                ));
            }
        }
        lines
    }
}

/// State shared by the subscribers' callbacks.
struct InState<const J: usize> {
    gate: Gate,
    counts: InboundCounts,
    joints: JointLimits,
    limits: inbound::Limits,
    sink: Box<dyn Inbound<J>>,
    stop: StopFlag,
}

impl<const J: usize> InState<J> {
    fn handle(&mut self, kind: Kind, sample: &ZSample, obstacle_prefix: &str) {
        let now = unix_now_ns();
        let attachment = sample.attachment().map(|a| a.to_bytes());
        let admitted = self
            .gate
            .admit(kind, attachment.as_deref(), now, self.limits.max_age);
        let payload = sample.payload().to_bytes();
        let result = admitted.and_then(|arrival| {
            match kind {
                Kind::Target => {
                    let msg = JointTrajectory::decode(&payload).map_err(Refusal::Malformed)?;
                    let target = inbound::target_from::<J>(&msg, &self.joints)?;
                    self.sink.target(&target, &arrival).map_err(Refusal::Sink)?;
                }
                Kind::Obstacle => {
                    let key = sample.key_expr().as_str();
                    let name = key
                        .strip_prefix(obstacle_prefix)
                        .and_then(|rest| rest.split('/').next())
                        .unwrap_or("");
                    let type_chunk = key.rsplit('/').nth(1).unwrap_or("");
                    let obstacle = if type_chunk == POINT_STAMPED.dds_name() {
                        let m = PointStamped::decode(&payload).map_err(Refusal::Malformed)?;
                        inbound::obstacle_from(
                            name,
                            ObstacleMsg::Point(&m),
                            &self.limits,
                            &mut self.counts.obstacle_names,
                        )?
                    } else {
                        let m = PoseStamped::decode(&payload).map_err(Refusal::Malformed)?;
                        inbound::obstacle_from(
                            name,
                            ObstacleMsg::Pose(&m),
                            &self.limits,
                            &mut self.counts.obstacle_names,
                        )?
                    };
                    self.sink
                        .obstacle(&obstacle, &arrival)
                        .map_err(Refusal::Sink)?;
                }
                Kind::Stop => {
                    let m = Text::decode(&payload).map_err(Refusal::Malformed)?;
                    match m.data.trim() {
                        "rest" => self.stop.request(StopLevel::Rest),
                        "now" => self.stop.request(StopLevel::Now),
                        other => {
                            return Err(Refusal::Unsupported(format!(
                                "stop request `{other}`: send `rest` or `now`"
                            )));
                        }
                    }
                }
            }
            Ok(arrival)
        });
        let counts = match kind {
            Kind::Target => &mut self.counts.targets,
            Kind::Obstacle => &mut self.counts.obstacles,
            Kind::Stop => &mut self.counts.stops,
        };
        inbound::count(counts, &result);
        counts.lost = self.gate.lost(kind);
    }
}

/// What the bridge thread owns.
struct OutState<const J: usize> {
    measured: Out,
    commanded: Out,
    state: Out,
    fault: Out,
    report: Out,
    names: Vec<String>,
    dof: usize,
    period_ns: i64,
    decimation: u64,
    previous: Option<Sample<J>>,
    start_ns: Option<i64>,
    start_samples: u32,
    buf: Vec<u8>,
    velocity: [f64; J],
    counts: OutboundCounts,
}

impl<const J: usize> OutState<J> {
    fn handle(&mut self, s: &Sample<J>, forwarded_unix_ns: i64) {
        self.counts.handled += 1;
        let dof = self.dof;
        // The start of the loop's grid, from the earliest hand-over of the first samples.
        let start = forwarded_unix_ns - (s.cycle as i64).saturating_mul(self.period_ns);
        if self.start_samples < 1000 {
            self.start_samples += 1;
            self.start_ns = Some(self.start_ns.map_or(start, |t| t.min(start)));
        }
        let stamp = Time::from_nanos(
            self.start_ns.unwrap_or(start) + (s.cycle as i64).saturating_mul(self.period_ns),
        );
        let dt = match &self.previous {
            Some(p) if s.cycle > p.cycle => {
                (s.cycle - p.cycle) as f64 * self.period_ns as f64 * 1e-9
            }
            _ => 0.0,
        };
        let publish = s.cycle % self.decimation == 0;
        for (out, q, effort) in [
            (0, &s.measured, &[][..]),
            (1, &s.commanded, &s.effort[..dof]),
        ] {
            if let (Some(p), true) = (&self.previous, dt > 0.0) {
                let before = if out == 0 { &p.measured } else { &p.commanded };
                for k in 0..dof {
                    self.velocity[k] = (q[k] - before[k]) / dt;
                }
            } else {
                self.velocity = [0.0; J];
            }
            if publish {
                msg::write_joint_state(
                    &mut self.buf,
                    stamp,
                    "",
                    &self.names,
                    &q[..dof],
                    &self.velocity[..dof],
                    effort,
                );
                let target = if out == 0 {
                    &mut self.measured
                } else {
                    &mut self.commanded
                };
                target.put(&self.buf);
            }
        }
        self.previous = Some(*s);
    }

    fn text(&mut self, which: u8, text: &str) {
        Text {
            data: text.to_owned(),
        }
        .encode(&mut self.buf);
        let out = match which {
            0 => &mut self.state,
            1 => &mut self.fault,
            _ => &mut self.report,
        };
        out.put(&self.buf);
    }

    fn finish_counts(&mut self) -> OutboundCounts {
        let mut c = self.counts.clone();
        c.joint_states = self.measured.published + self.commanded.published;
        c.failed = [
            &self.measured,
            &self.commanded,
            &self.state,
            &self.fault,
            &self.report,
        ]
        .iter()
        .map(|o| o.failed)
        .sum();
        c.states = self.state.published;
        c
    }
}

/// Shared between the caller and the bridge thread.
struct Shared {
    state: Mutex<Option<String>>,
    end: Mutex<Option<(String, Option<String>)>>,
    finished: AtomicBool,
    forwarded: AtomicU64,
}

/// A controller joined to a cell: a Zenoh session, its publishers, subscribers and liveliness
/// tokens, and the bridge thread. For up to `J` joints.
pub struct Cell<const J: usize> {
    tx: QueueSender<(Sample<J>, i64)>,
    thread: Option<JoinHandle<OutState<J>>>,
    waker: std::thread::Thread,
    shared: Arc<Shared>,
    inbound: Arc<Mutex<InState<J>>>,
    _subscribers: Vec<Subscriber<()>>,
    _tokens: Vec<LivelinessToken>,
    session: zenoh::Session,
    report: CellReport,
}

fn zerr(what: &str) -> impl Fn(zenoh::Error) -> CellError + '_ {
    move |e| CellError::Zenoh(format!("{what}: {e}"))
}

impl<const J: usize> Cell<J> {
    /// Opens the session (connect endpoints that do not answer yet are retried in the
    /// background), declares the node, its publishers and subscriptions with their liveliness
    /// tokens, and starts the bridge thread. `joints` names the model's joints (and bounds the
    /// targets); inputs go to `inbound`; stop requests raise `stop`.
    pub fn open(
        config: CellConfig,
        joints: JointLimits,
        inbound: Box<dyn Inbound<J>>,
        stop: StopFlag,
    ) -> Result<Self, CellError> {
        let config = config.checked()?;
        let dof = joints.dof();
        if dof > J || dof == 0 {
            return Err(CellError::Config(format!(
                "{dof} joints: the bridge takes 1 to {J}"
            )));
        }
        let session = zenoh::open(config.zenoh()?)
            .wait()
            .map_err(zerr("cannot open the session"))?;
        let zid = session.zid().to_string();
        let ns = config.namespace.clone();
        let node = config.node.clone();
        let mut next_id = 1u32;
        let mut tokens = Vec::new();
        let node_entity = Entity {
            domain: config.domain,
            zid: &zid,
            node_id: 0,
            id: 0,
            kind: EntityKind::Node,
            namespace: &ns,
            node: &node,
            topic: None,
        };
        tokens.push(
            session
                .liveliness()
                .declare_token(node_entity.liveliness_key())
                .wait()
                .map_err(zerr("cannot declare the node's liveliness token"))?,
        );
        let mut report = CellReport {
            zid: zid.clone(),
            ..CellReport::default()
        };
        let mut declare_out =
            |relative: &str, ty: &'static TypeDescription| -> Result<Out, CellError> {
                let topic = config.topic(relative)?;
                let key = topic_key(config.domain, &topic, ty);
                let entity = Entity {
                    id: next_id,
                    kind: EntityKind::Publisher,
                    topic: Some((&topic, ty, DEPTH)),
                    ..node_entity.clone()
                };
                next_id += 1;
                let publisher = session
                    .declare_publisher(key.clone())
                    .congestion_control(CongestionControl::Drop)
                    .express(true)
                    .wait()
                    .map_err(zerr("cannot declare a publisher"))?;
                let token = session
                    .liveliness()
                    .declare_token(entity.liveliness_key())
                    .wait()
                    .map_err(zerr("cannot declare a liveliness token"))?;
                let gid = entity.gid();
                report.topics.push((topic, key));
                Ok(Out {
                    publisher,
                    _token: token,
                    gid,
                    sequence: 0,
                    published: 0,
                    failed: 0,
                })
            };
        let measured = declare_out("joint_states", &JOINT_STATE)?;
        if let Some(wait) = config.wait_for_subscriber {
            let since = Instant::now();
            while since.elapsed() < wait {
                let matching = measured
                    .publisher
                    .matching_status()
                    .wait()
                    .is_ok_and(|m| m.matching());
                if matching {
                    report.subscriber_after_s = Some(since.elapsed().as_secs_f64());
                    break;
                }
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        let commanded = declare_out("joint_commands", &JOINT_STATE)?;
        let state = declare_out("run_state", &STRING)?;
        let fault = declare_out("fault", &STRING)?;
        let report_out = declare_out("report", &STRING)?;

        let names = joints.names.clone();
        let in_state = Arc::new(Mutex::new(InState {
            gate: Gate::default(),
            counts: InboundCounts::default(),
            joints,
            limits: config.limits.clone(),
            sink: inbound,
            stop,
        }));
        let mut subscribers = Vec::new();
        let obstacles_topic = config.topic("obstacles")?;
        let obstacle_prefix = format!(
            "{}/{}/",
            config.domain,
            obstacles_topic.trim_start_matches('/')
        );
        let ins: [(&str, Kind, &'static TypeDescription, bool); 4] = [
            ("joint_trajectory", Kind::Target, &JOINT_TRAJECTORY, true),
            ("stop", Kind::Stop, &STRING, true),
            ("obstacles/*", Kind::Obstacle, &POSE_STAMPED, false),
            ("obstacles/*", Kind::Obstacle, &POINT_STAMPED, false),
        ];
        for (relative, kind, ty, announce) in ins {
            let topic = format!("{}/{relative}", if ns == "/" { "" } else { ns.as_str() });
            let key = topic_key(config.domain, &topic, ty);
            let state = Arc::clone(&in_state);
            let prefix = obstacle_prefix.clone();
            let sub = session
                .declare_subscriber(key.clone())
                .callback(move |sample: ZSample| {
                    state
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner)
                        .handle(kind, &sample, &prefix);
                })
                .wait()
                .map_err(zerr("cannot declare a subscriber"))?;
            subscribers.push(sub);
            if announce {
                // Only concrete topics get a token (a ROS topic name has no wildcard).
                let entity = Entity {
                    id: next_id,
                    kind: EntityKind::Subscription,
                    topic: Some((&topic, ty, DEPTH)),
                    ..node_entity.clone()
                };
                next_id += 1;
                tokens.push(
                    session
                        .liveliness()
                        .declare_token(entity.liveliness_key())
                        .wait()
                        .map_err(zerr("cannot declare a liveliness token"))?,
                );
            }
            report.topics.push((topic, key));
        }

        let (tx, mut rx) = queue::<(Sample<J>, i64)>(config.capacity.max(16));
        let shared = Arc::new(Shared {
            state: Mutex::new(None),
            end: Mutex::new(None),
            finished: AtomicBool::new(false),
            forwarded: AtomicU64::new(0),
        });
        let mut out = OutState {
            measured,
            commanded,
            state,
            fault,
            report: report_out,
            names,
            dof,
            period_ns: i64::try_from(config.period.as_nanos()).unwrap_or(i64::MAX),
            decimation: u64::from(config.decimation),
            previous: None,
            start_ns: None,
            start_samples: 0,
            buf: Vec::with_capacity(1024),
            velocity: [0.0; J],
            counts: OutboundCounts::default(),
        };
        let shared_bridge = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("rl-cell".into())
            .spawn(move || {
                bridge_loop(&mut out, &mut rx, &shared_bridge);
                out
            })
            .map_err(|e| CellError::Config(format!("cannot start the bridge thread: {e}")))?;
        let waker = thread.thread().clone();
        Ok(Self {
            tx,
            thread: Some(thread),
            waker,
            shared,
            inbound: in_state,
            _subscribers: subscribers,
            _tokens: tokens,
            session,
            report,
        })
    }

    /// Hands one cycle's sample to the bridge: a wait-free push (a full queue drops it and
    /// counts it) and a wake-up of the bridge thread. Allocates nothing.
    pub fn forward(&mut self, sample: &Sample<J>) {
        self.shared.forwarded.fetch_add(1, Ordering::Relaxed);
        if self.tx.try_send((*sample, unix_now_ns())).is_ok() {
            self.waker.unpark();
        }
    }

    /// Sets the run state to publish (JSON text); the bridge sends it when it changes, at most
    /// ten times a second.
    pub fn set_state(&self, json: String) {
        *self
            .shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = Some(json);
    }

    /// The inbound counts so far.
    pub fn inbound_counts(&self) -> InboundCounts {
        self.inbound
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .counts
            .clone()
    }

    /// The Zenoh session id.
    pub fn zid(&self) -> &str {
        &self.report.zid
    }

    /// With [`CellConfig::wait_for_subscriber`]: how long until the joint states had a
    /// subscriber, s.
    pub fn subscriber_after_s(&self) -> Option<f64> {
        self.report.subscriber_after_s
    }

    /// The topics and their key expressions.
    pub fn topics(&self) -> &[(String, String)] {
        &self.report.topics
    }

    /// Publishes what is still queued, the final run state, the fault (if the run failed)
    /// and the report (JSON), then leaves the cell: the liveliness tokens go (peers see the
    /// controller leave) and the session closes. Returns what the cell did.
    pub fn finish(mut self, state: String, report: String, fault: Option<String>) -> CellReport {
        self.set_state(state);
        *self
            .shared
            .end
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = Some((report, fault));
        self.shared.finished.store(true, Ordering::Release);
        self.waker.unpark();
        let mut out = self.thread.take().and_then(|t| t.join().ok());
        let mut report = std::mem::take(&mut self.report);
        if let Some(o) = &mut out {
            report.outbound = o.finish_counts();
        }
        report.outbound.forwarded = self.shared.forwarded.load(Ordering::Relaxed);
        report.outbound.dropped = self.tx.dropped();
        report.inbound = self.inbound_counts();
        // Undeclare before closing, so peers see the tokens go at once.
        self._subscribers.clear();
        self._tokens.clear();
        drop(out);
        let _ = self.session.close().wait();
        report
    }
}

impl<const J: usize> Drop for Cell<J> {
    /// Without [`finish`](Cell::finish) (an early error): the bridge thread ends without
    /// publishing an end; the tokens go with the session.
    fn drop(&mut self) {
        if let Some(t) = self.thread.take() {
            self.shared.finished.store(true, Ordering::Release);
            self.waker.unpark();
            let _ = t.join();
        }
    }
}

fn bridge_loop<const J: usize>(
    out: &mut OutState<J>,
    rx: &mut QueueReceiver<(Sample<J>, i64)>,
    shared: &Shared,
) {
    let mut last_state: Option<String> = None;
    let mut state_sent = Instant::now() - STATE_INTERVAL;
    loop {
        let finishing = shared.finished.load(Ordering::Acquire);
        while let Some((s, t)) = rx.try_recv() {
            out.handle(&s, t);
        }
        let pending = shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        if let Some(s) = pending {
            if last_state.as_ref() != Some(&s)
                && (finishing || state_sent.elapsed() >= STATE_INTERVAL)
            {
                out.text(0, &s);
                state_sent = Instant::now();
                last_state = Some(s);
            } else if last_state.as_ref() != Some(&s) {
                // Too soon: keep it for the next turn unless a newer one comes.
                let mut slot = shared.state.lock().unwrap_or_else(PoisonError::into_inner);
                slot.get_or_insert(s);
            }
        }
        if finishing {
            let end = shared
                .end
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take();
            if let Some((report, fault)) = end {
                if let Some(f) = fault {
                    out.text(1, &f);
                }
                out.text(2, &report);
            }
            return;
        }
        std::thread::park_timeout(IDLE_WAKE);
    }
}
