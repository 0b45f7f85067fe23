//! MoveIt motion plan requests in YAML (`moveit_msgs/MotionPlanRequest`): the start state's
//! joint positions and a joint-space goal — what MotionBenchMaker's `requestNNNN.yaml` hold.
//!
//! Read: `start_state.joint_state.name` / `.position` (lists of equal length) and
//! `goal_constraints[0].joint_constraints[*]` with `joint_name` and `position`; also
//! `group_name` and `allowed_planning_time` when present. Everything else is ignored. A
//! request with several goal constraints uses the first (the others are reported in
//! [`MotionRequest::ignored_goals`]).

use std::path::Path;

use saphyr::{LoadableYamlNode, MarkedYaml, Scalar, YamlData};

use crate::error::PlanError;
use crate::space::JointSpace;

/// A motion plan request.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MotionRequest {
    /// Start joint positions by name.
    pub start: Vec<(String, f64)>,
    /// Goal joint positions by name.
    pub goal: Vec<(String, f64)>,
    /// The planning group, if named.
    pub group: Option<String>,
    /// `allowed_planning_time`, s, if given.
    pub allowed_time: Option<f64>,
    /// Goal constraints after the first (not used).
    pub ignored_goals: usize,
}

type Node<'a> = MarkedYaml<'a>;

fn at(path: &Path, node: &Node, element: &str, message: impl Into<String>) -> PlanError {
    let m = node.span.start;
    PlanError::file(path, element, message).at_position(m.line() as u32, m.col() as u32 + 1)
}

fn get<'a, 'i>(node: &'a Node<'i>, key: &str) -> Option<&'a Node<'i>> {
    node.data.as_mapping_get(key)
}

fn seq<'a, 'i>(path: &Path, node: &'a Node<'i>, what: &str) -> Result<&'a [Node<'i>], PlanError> {
    match &node.data {
        YamlData::Sequence(v) => Ok(v),
        _ => Err(at(path, node, what, "not a list")),
    }
}

fn number(path: &Path, node: &Node, what: &str) -> Result<f64, PlanError> {
    let x = match &node.data {
        YamlData::Value(Scalar::FloatingPoint(x)) => x.into_inner(),
        YamlData::Value(Scalar::Integer(i)) => *i as f64,
        _ => return Err(at(path, node, what, "not a number")),
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(at(path, node, what, format!("{x} is not finite")))
    }
}

fn string<'a>(node: &'a Node) -> Option<&'a str> {
    match &node.data {
        YamlData::Value(Scalar::String(s)) => Some(s),
        _ => None,
    }
}

impl MotionRequest {
    /// Reads the request in `text` (from `path`, for messages).
    pub fn parse(text: &str, path: &Path) -> Result<Self, PlanError> {
        let docs = MarkedYaml::load_from_str(text).map_err(|e| {
            let m = e.marker();
            PlanError::file(path, "YAML", e.info().to_string())
                .at_position(m.line() as u32, m.col() as u32 + 1)
        })?;
        let doc = docs
            .first()
            .ok_or_else(|| PlanError::file(path, "YAML", "empty document"))?;
        let mut r = MotionRequest {
            group: get(doc, "group_name").and_then(string).map(str::to_string),
            allowed_time: get(doc, "allowed_planning_time").and_then(|n| number(path, n, "").ok()),
            ..Default::default()
        };
        let js = get(doc, "start_state")
            .and_then(|s| get(s, "joint_state"))
            .ok_or_else(|| at(path, doc, "start_state.joint_state", "missing"))?;
        let names = get(js, "name").ok_or_else(|| at(path, js, "joint_state.name", "missing"))?;
        let pos =
            get(js, "position").ok_or_else(|| at(path, js, "joint_state.position", "missing"))?;
        let (names, pos) = (
            seq(path, names, "joint_state.name")?,
            seq(path, pos, "joint_state.position")?,
        );
        if names.len() != pos.len() {
            return Err(at(
                path,
                js,
                "joint_state",
                format!("{} names but {} positions", names.len(), pos.len()),
            ));
        }
        for (n, p) in names.iter().zip(pos) {
            let name = string(n).ok_or_else(|| at(path, n, "joint_state.name", "not a string"))?;
            r.start
                .push((name.to_string(), number(path, p, "joint_state.position")?));
        }
        let goals = get(doc, "goal_constraints")
            .ok_or_else(|| at(path, doc, "goal_constraints", "missing"))?;
        let goals = seq(path, goals, "goal_constraints")?;
        let first = goals
            .first()
            .ok_or_else(|| at(path, doc, "goal_constraints", "empty"))?;
        r.ignored_goals = goals.len() - 1;
        let jc = get(first, "joint_constraints").ok_or_else(|| {
            at(
                path,
                first,
                "goal_constraints[0]",
                "no joint_constraints (only joint-space goals are supported)",
            )
        })?;
        for c in seq(path, jc, "joint_constraints")? {
            let name = get(c, "joint_name")
                .and_then(string)
                .ok_or_else(|| at(path, c, "joint_constraints[].joint_name", "missing"))?;
            let p = get(c, "position")
                .ok_or_else(|| at(path, c, "joint_constraints[].position", "missing"))?;
            r.goal.push((
                name.to_string(),
                number(path, p, "joint_constraints[].position")?,
            ));
        }
        Ok(r)
    }

    /// Reads the request file at `path`.
    pub fn load(path: &Path) -> Result<Self, PlanError> {
        let text =
            rl_core::loader::read_text(path, rl_core::loader::InputLimits::DEFAULT.max_bytes)
                .map_err(|e| PlanError::Load(e.to_string()))?;
        Self::parse(&text, path)
    }

    /// Start and goal as configurations of `space` (coordinates named by the joints; names
    /// the space does not have, such as gripper fingers, are skipped; a coordinate missing
    /// from start or goal is an error).
    pub fn configurations(&self, space: &JointSpace) -> Result<(Vec<f64>, Vec<f64>), PlanError> {
        let pick = |what: &str, values: &[(String, f64)]| -> Result<Vec<f64>, PlanError> {
            let mut q = vec![f64::NAN; space.nq()];
            for c in space.coordinates() {
                if c.topology.width() != 1 {
                    return Err(PlanError::Unsupported(format!(
                        "MoveIt requests for multi-coordinate joints ({})",
                        c.name
                    )));
                }
                let v = values.iter().find(|(n, _)| *n == c.name).ok_or_else(|| {
                    PlanError::UnknownName {
                        what: if what == "start" {
                            "joint in the start state"
                        } else {
                            "joint in the goal constraints"
                        },
                        name: c.name.clone(),
                    }
                })?;
                q[c.offset] = v.1;
            }
            Ok(q)
        };
        Ok((pick("start", &self.start)?, pick("goal", &self.goal)?))
    }
}
