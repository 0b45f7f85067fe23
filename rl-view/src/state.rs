//! The viewer's state: every robot's joint positions and where they came from, body poses
//! (rl-core forward kinematics placed into the rl-sg scene), Coach body-pose overrides,
//! collisions and the robot–environment distance (rl-sg), the last inverse-kinematics result
//! (rl-core's IK), and the Coach counters. [`Engine::state_json`] gives the protocol's `state`
//! message; geometry is recomputed there, once per broadcast, not per input.

use std::collections::BTreeMap;
use std::time::Instant;

use glam::{DQuat, DVec3};
use rl_core::Data;
use rl_core::algo::ik::{IkError, IkGoal, IkSolver};
use rl_core::algo::{forward_position, tool_pose};
use rl_core::rotation::euler::from_zyx;
use rl_core::spatial::PlueckerTransform;
use rl_sg::{BodyId, CollisionFilter, ModelId};
use serde_json::{Value, json};

use crate::load::{CAPACITY, World};
use crate::scene_json::{pose7, scene_json};

/// Who set a model's joint positions last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// The configuration loaded with the model.
    Init,
    /// A Coach client (`2 <i> q…`).
    Coach,
    /// The page's sliders.
    Ui,
    /// Inverse kinematics.
    Ik,
    /// Path playback.
    Path,
    /// A real-time loop through [`crate::Publisher`].
    Live,
}

impl Source {
    /// The protocol's name.
    pub fn as_str(self) -> &'static str {
        match self {
            Source::Init => "init",
            Source::Coach => "coach",
            Source::Ui => "ui",
            Source::Ik => "ik",
            Source::Path => "path",
            Source::Live => "live",
        }
    }
}

/// The result of an inverse-kinematics request.
#[derive(Clone, Debug, PartialEq)]
pub struct IkReport {
    /// The model.
    pub model: usize,
    /// Whether the tool reached the target (the model moved there).
    pub ok: bool,
    /// Why not (empty on success).
    pub reason: String,
    /// Distance from the tool to the target position at the configuration found, m.
    pub position_error: f64,
    /// Iterations spent.
    pub iterations: usize,
}

/// A controller's run as the page shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct RunStatus {
    /// Whether the run has ended.
    pub ended: bool,
    /// Whether it went well (or goes well so far).
    pub ok: bool,
    /// One line: what happened (`"ended: passed after 4.00 s"`, the fault and when, …).
    pub summary: String,
}

/// Coach counters.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CoachStats {
    /// Clients connected now.
    pub clients: u64,
    /// Lines received.
    pub lines: u64,
    /// Lines rejected (unknown command, wrong count, NaN, unknown model, too long).
    pub rejected: u64,
    /// The last rejection, with its reason.
    pub last_error: Option<String>,
}

#[derive(Clone, Debug)]
struct ModelState {
    q: Vec<f64>,
    /// The commanded positions that came with `q` (from a controller), if any.
    q_cmd: Option<Vec<f64>>,
    qd: Option<Vec<f64>>,
    source: Source,
    /// Coach `0` overrides by body index, until the next joint update.
    body_overrides: BTreeMap<usize, PlueckerTransform>,
    /// Coach `1` shape transforms by (body, shape).
    shape_overrides: BTreeMap<(usize, usize), PlueckerTransform>,
}

/// The viewer's state (behind the server's lock).
pub struct Engine {
    world: World,
    scene_json: Value,
    data: Box<Data<CAPACITY>>,
    ik_solver: Box<IkSolver<CAPACITY>>,
    models: Vec<ModelState>,
    geometry_dirty: bool,
    colliding: Vec<(usize, String)>,
    distance: Value,
    ik: Option<IkReport>,
    coach: CoachStats,
    run: Option<RunStatus>,
    page_errors: u64,
    seq: u64,
    changed: bool,
    start: Instant,
}

/// `x y z a b c` (RL's Coach pose) as a transform, if finite.
pub fn coach_pose(p: &[f64; 6]) -> Option<PlueckerTransform> {
    p.iter()
        .all(|v| v.is_finite())
        .then(|| PlueckerTransform::new(from_zyx([p[3], p[4], p[5]]), DVec3::new(p[0], p[1], p[2])))
}

/// `[x, y, z, qx, qy, qz, qw]` as a transform, if finite with a non-zero quaternion.
pub fn pose_from7(p: &[f64; 7]) -> Option<PlueckerTransform> {
    if !p.iter().all(|v| v.is_finite()) {
        return None;
    }
    let q = DQuat::from_xyzw(p[3], p[4], p[5], p[6]);
    let n = q.length();
    (n > 1e-9)
        .then(|| PlueckerTransform::from_quat_translation(q / n, DVec3::new(p[0], p[1], p[2])))
}

impl Engine {
    /// The state of a freshly loaded world: every robot at its initial configuration.
    pub fn new(world: World) -> Engine {
        let models = world
            .robots
            .iter()
            .map(|r| ModelState {
                q: r.initial_q.clone(),
                q_cmd: None,
                qd: None,
                source: Source::Init,
                body_overrides: BTreeMap::new(),
                shape_overrides: BTreeMap::new(),
            })
            .collect();
        let scene_json = scene_json(&world);
        let mut ik_solver = Box::<IkSolver<CAPACITY>>::default();
        // Answer the page within a frame or so: a bounded budget, no endless restarts.
        ik_solver.options.max_iterations = 3000;
        Engine {
            world,
            scene_json,
            data: Box::new(Data::new()),
            ik_solver,
            models,
            geometry_dirty: true,
            colliding: Vec::new(),
            distance: Value::Null,
            ik: None,
            coach: CoachStats::default(),
            run: None,
            page_errors: 0,
            seq: 0,
            changed: true,
            start: Instant::now(),
        }
    }

    /// The loaded world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The Scene JSON (made once at load).
    pub fn scene(&self) -> &Value {
        &self.scene_json
    }

    /// Number of robots.
    pub fn model_count(&self) -> usize {
        self.models.len()
    }

    /// Model `model`'s joint positions.
    pub fn q(&self, model: usize) -> Option<&[f64]> {
        self.models.get(model).map(|m| m.q.as_slice())
    }

    /// Whether anything changed since the last [`Engine::state_json`].
    pub fn changed(&self) -> bool {
        self.changed
    }

    fn touch(&mut self) {
        self.changed = true;
    }

    /// Sets model `model`'s joint positions (every value finite, `nq` of them); clears its
    /// Coach body overrides and the commanded positions (`q_cmd` is null until a controller
    /// sends them again).
    pub fn set_q(&mut self, model: usize, q: &[f64], source: Source) -> Result<(), String> {
        self.set_q_commanded(model, q, None, source)
    }

    /// Model `model`'s commanded joint positions, when the last update carried them.
    pub fn q_cmd(&self, model: usize) -> Option<&[f64]> {
        self.models.get(model).and_then(|m| m.q_cmd.as_deref())
    }

    /// [`Engine::set_q`] with the commanded positions that go with the measured `q` (from a
    /// controller): the state shows both, and the page the tracking error `q_cmd − q`.
    pub fn set_q_commanded(
        &mut self,
        model: usize,
        q: &[f64],
        q_cmd: Option<&[f64]>,
        source: Source,
    ) -> Result<(), String> {
        let m = self
            .models
            .get_mut(model)
            .ok_or_else(|| format!("unknown model {model}"))?;
        if q.len() != m.q.len() {
            return Err(format!(
                "model {model} has {} joints, {} values given",
                m.q.len(),
                q.len()
            ));
        }
        if let Some(k) = q.iter().position(|v| !v.is_finite()) {
            return Err(format!("value {k} is not a finite number"));
        }
        if let Some(c) = q_cmd {
            if c.len() != q.len() {
                return Err(format!(
                    "model {model} has {} joints, {} commanded values given",
                    q.len(),
                    c.len()
                ));
            }
            if let Some(k) = c.iter().position(|v| !v.is_finite()) {
                return Err(format!("commanded value {k} is not a finite number"));
            }
        }
        m.q.copy_from_slice(q);
        match (q_cmd, &mut m.q_cmd) {
            (Some(c), Some(old)) => old.copy_from_slice(c),
            (Some(c), slot) => *slot = Some(c.to_vec()),
            (None, slot) => *slot = None,
        }
        m.source = source;
        m.body_overrides.clear();
        self.geometry_dirty = true;
        self.touch();
        Ok(())
    }

    /// Sets model `model`'s joint velocities (shown, not integrated).
    pub fn set_qd(&mut self, model: usize, qd: &[f64]) -> Result<(), String> {
        let m = self
            .models
            .get_mut(model)
            .ok_or_else(|| format!("unknown model {model}"))?;
        if qd.len() != m.q.len() {
            return Err(format!(
                "model {model} has {} joints, {} velocities given",
                m.q.len(),
                qd.len()
            ));
        }
        if let Some(k) = qd.iter().position(|v| !v.is_finite()) {
            return Err(format!("velocity {k} is not a finite number"));
        }
        m.qd = Some(qd.to_vec());
        self.touch();
        Ok(())
    }

    /// A Coach `0`: body `body` of model `model` drawn at `pose` until the next joint update.
    pub fn set_body_pose(
        &mut self,
        model: usize,
        body: usize,
        pose: &[f64; 6],
    ) -> Result<(), String> {
        let bodies = self
            .world
            .scene
            .models()
            .get(model)
            .filter(|_| model < self.models.len())
            .ok_or_else(|| format!("unknown model {model}"))?
            .bodies()
            .len();
        if body >= bodies {
            return Err(format!(
                "model {model} has {bodies} bodies, not {}",
                body + 1
            ));
        }
        let x = coach_pose(pose).ok_or("pose is not finite")?;
        self.models[model].body_overrides.insert(body, x);
        self.touch();
        Ok(())
    }

    /// A Coach `1`: shape `shape` of body `body` at `pose` in its body's frame.
    pub fn set_shape_pose(
        &mut self,
        model: usize,
        body: usize,
        shape: usize,
        pose: &[f64; 6],
    ) -> Result<(), String> {
        let b = self
            .world
            .scene
            .models()
            .get(model)
            .filter(|_| model < self.models.len())
            .ok_or_else(|| format!("unknown model {model}"))?
            .bodies()
            .get(body)
            .ok_or_else(|| format!("model {model} has no body {body}"))?;
        if shape >= b.shapes().len() {
            return Err(format!("body {body} of model {model} has no shape {shape}"));
        }
        let x = coach_pose(pose).ok_or("pose is not finite")?;
        self.models[model].shape_overrides.insert((body, shape), x);
        self.touch();
        Ok(())
    }

    /// Moves model `model`'s tool to `target` by inverse kinematics from the current `q`. On
    /// success the model moves there (source `ik`); on failure it stays. The report is also
    /// in the next state.
    pub fn ik(&mut self, model: usize, target: &[f64; 7]) -> IkReport {
        let report = self.solve_ik(model, target);
        if report.ok {
            self.geometry_dirty = true;
        }
        self.ik = Some(report.clone());
        self.touch();
        report
    }

    fn solve_ik(&mut self, model: usize, target: &[f64; 7]) -> IkReport {
        let fail = |reason: String| IkReport {
            model,
            ok: false,
            reason,
            position_error: f64::NAN,
            iterations: 0,
        };
        let (Some(robot), Some(state)) = (self.world.robots.get(model), self.models.get(model))
        else {
            return fail(format!("unknown model {model}"));
        };
        let Some(x) = pose_from7(target) else {
            return fail("target is not a finite pose with a non-zero quaternion".into());
        };
        // The target is in the scene's frame; the kinematics in the robot's placed world frame.
        let x = robot.base.inverse() * x;
        let kin = &robot.kinematics.model;
        if kin.tools().is_empty() {
            return fail("the model has no tool".into());
        }
        let goal = IkGoal::pose(robot.tool, x);
        let mut q = state.q.clone();
        let start = Instant::now();
        let mut clock = || start.elapsed().as_secs_f64();
        let r = self.ik_solver.solve_within(
            kin,
            &mut self.data,
            &[goal],
            &state.q,
            &mut q,
            &mut clock,
            0.25,
        );
        let position_error = match forward_position(kin, &mut self.data, &q)
            .ok()
            .and_then(|()| tool_pose(kin, &self.data, robot.tool).ok())
        {
            Some(t) => (t.translation - x.translation).length(),
            None => f64::NAN,
        };
        match r {
            Ok(sol) => {
                let m = &mut self.models[model];
                m.q.copy_from_slice(&q);
                m.source = Source::Ik;
                m.q_cmd = None;
                m.body_overrides.clear();
                IkReport {
                    model,
                    ok: true,
                    reason: String::new(),
                    position_error,
                    iterations: sol.iterations,
                }
            }
            Err(e) => {
                let iterations = match e {
                    IkError::NotConverged { iterations, .. } => iterations,
                    IkError::TimeBudget { iterations, .. } => iterations,
                    _ => 0,
                };
                let reason = match e {
                    IkError::NotConverged { residual, .. }
                    | IkError::TimeBudget { residual, .. } => {
                        format!(
                            "target not reached (unreachable or beyond the joint limits): \
                             best residual {residual:.3e}, position error {position_error:.3e} m; {e}"
                        )
                    }
                    other => other.to_string(),
                };
                IkReport {
                    model,
                    ok: false,
                    reason,
                    position_error,
                    iterations,
                }
            }
        }
    }

    /// Counts a Coach line, and a rejection with its reason. A line taken clears the last
    /// rejection (the count stays): the page shows an error only while it is the latest word.
    pub fn coach_line(&mut self, rejected: Option<String>) {
        self.coach.lines += 1;
        match rejected {
            Some(e) => {
                self.coach.rejected += 1;
                self.coach.last_error = Some(e);
            }
            None => self.coach.last_error = None,
        }
        self.touch();
    }

    /// Sets what the page says about a controller's run (`rl run --view`): running, or ended
    /// and how.
    pub fn set_run(&mut self, run: RunStatus) {
        self.run = Some(run);
        self.touch();
    }

    /// What the page says about a run, if anything.
    pub fn run(&self) -> Option<&RunStatus> {
        self.run.as_ref()
    }

    /// A Coach client came or went.
    pub fn coach_clients(&mut self, delta: i64) {
        self.coach.clients = self.coach.clients.saturating_add_signed(delta);
        self.touch();
    }

    /// The Coach counters.
    pub fn coach_stats(&self) -> &CoachStats {
        &self.coach
    }

    /// Counts a malformed page message.
    pub fn page_error(&mut self) {
        self.page_errors += 1;
        self.touch();
    }

    /// Malformed page messages so far.
    pub fn page_errors(&self) -> u64 {
        self.page_errors
    }

    /// Places every robot in the scene and recomputes collisions and the distance.
    fn update_geometry(&mut self) {
        if !self.geometry_dirty {
            return;
        }
        self.geometry_dirty = false;
        let robots = self.world.robots.len();
        for i in 0..robots {
            let kin = &self.world.robots[i].kinematics.model;
            // q is checked finite on the way in: an error here is a model problem, reported
            // as no update (the bodies stay where they were).
            let _ = self.world.scene.set_configuration(
                ModelId(i),
                kin,
                &mut self.data,
                &self.models[i].q,
            );
        }
        let scene = &self.world.scene;
        let mut colliding = Vec::new();
        let mut push = |b: BodyId| {
            if b.model < robots {
                colliding.push((
                    b.model,
                    scene.models()[b.model].bodies()[b.body].name().to_string(),
                ));
            }
        };
        for i in 0..robots {
            // Models without self-collision (RL skeletons) are only checked against others.
            let own = scene.models()[i]
                .self_collision()
                .then_some(CollisionFilter::SelfCollision(ModelId(i)));
            for f in own
                .into_iter()
                .chain([CollisionFilter::Against(ModelId(i))])
            {
                for (a, b) in scene.colliding_bodies(&f) {
                    push(a);
                    push(b);
                }
            }
        }
        colliding.sort();
        colliding.dedup();
        self.colliding = colliding;
        let mut best: Option<rl_sg::Distance> = None;
        for i in 0..robots {
            for e in robots..scene.models().len() {
                if let Some(d) =
                    scene.min_distance(&CollisionFilter::Between(ModelId(i), ModelId(e)))
                {
                    if best.is_none_or(|b| d.distance < b.distance) {
                        best = Some(d);
                    }
                }
            }
        }
        self.distance = match best {
            Some(d) => json!({
                "value": d.distance,
                "a": d.point_a.to_array(),
                "b": d.point_b.to_array(),
                "model": d.a.model,
                "body": scene.models()[d.a.model].bodies()[d.a.body].name(),
                "obstacle": rl_sg::report::body_label(scene, d.b.body_id()),
            }),
            None => Value::Null,
        };
    }

    /// The bodies in contact now: `(model, body name)`.
    pub fn colliding(&mut self) -> &[(usize, String)] {
        self.update_geometry();
        &self.colliding
    }

    /// The world poses of model `model`'s bodies (scene order), Coach overrides applied.
    pub fn body_poses(&mut self, model: usize) -> Vec<[f64; 7]> {
        self.update_geometry();
        let Some(m) = self.world.scene.models().get(model) else {
            return Vec::new();
        };
        let st = &self.models[model];
        m.bodies()
            .iter()
            .enumerate()
            .map(|(b, body)| pose7(st.body_overrides.get(&b).unwrap_or(body.pose())))
            .collect()
    }

    /// The protocol's `state` message for a broadcast: bumps `seq`, clears
    /// [`Engine::changed`].
    pub fn state_json(&mut self) -> Value {
        self.seq += 1;
        self.changed = false;
        self.snapshot_json()
    }

    /// The current `state` message without counting it as broadcast (for `hello`).
    pub fn snapshot_json(&mut self) -> Value {
        self.update_geometry();
        let models: Vec<Value> = (0..self.models.len())
            .map(|i| {
                let bodies = self.body_poses(i);
                let st = &self.models[i];
                let shapes: Vec<Value> = st
                    .shape_overrides
                    .iter()
                    .map(|((b, s), x)| json!([b, s, pose7(x)]))
                    .collect();
                json!({"index": i, "q": st.q, "q_cmd": st.q_cmd, "qd": st.qd,
                       "source": st.source.as_str(),
                       "bodies": bodies, "shapes": shapes})
            })
            .collect();
        let ik = self.ik.as_ref().map(|r| {
            json!({"model": r.model, "ok": r.ok, "reason": r.reason,
                   "position_error": if r.position_error.is_finite() { json!(r.position_error) } else { Value::Null },
                   "iterations": r.iterations})
        });
        json!({
            "type": "state",
            "seq": self.seq,
            "models": models,
            "colliding": self.colliding.iter().map(|(m, b)| json!([m, b])).collect::<Vec<_>>(),
            "distance": self.distance,
            "ik": ik,
            "coach": {"clients": self.coach.clients, "lines": self.coach.lines,
                      "rejected": self.coach.rejected, "last_error": self.coach.last_error},
            "run": self.run.as_ref().map(|r| json!({"ended": r.ended, "ok": r.ok, "summary": r.summary})),
            "page_errors": self.page_errors,
            "t": self.start.elapsed().as_secs_f64(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coach_poses_are_rz_ry_rx() {
        let h = std::f64::consts::FRAC_PI_2;
        // c = 90°: a turn about z.
        let x = coach_pose(&[1.0, 2.0, 3.0, 0.0, 0.0, h]).unwrap();
        let q = x.quaternion();
        let s = std::f64::consts::FRAC_1_SQRT_2;
        assert!(
            (q.z.abs() - s).abs() < 1e-12 && (q.w.abs() - s).abs() < 1e-12,
            "{q:?}"
        );
        assert_eq!(x.translation, DVec3::new(1.0, 2.0, 3.0));
        // a = 90° and c = 90°: R = Rz·Rx takes y to z (Rx turns it there, Rz keeps it).
        let x = coach_pose(&[0.0, 0.0, 0.0, h, 0.0, h]).unwrap();
        let y = x.rotation * DVec3::Y;
        assert!((y - DVec3::Z).length() < 1e-12, "{y:?}");
        assert!(coach_pose(&[f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]).is_none());
        assert!(pose_from7(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).is_none());
        assert!(pose_from7(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0]).is_some());
    }
}
