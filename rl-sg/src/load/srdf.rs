//! SRDF: the allowed-collision pairs that ship with most robot descriptions (MoveIt's semantic
//! robot description).
//!
//! `<disable_collisions link1 link2 reason/>` allows a pair; `<disable_default_collisions
//! link/>` allows every pair with that link; `<enable_collisions link1 link2/>` checks a pair
//! again (applied last, as MoveIt does). An SRDF replaces the model's default allowed set
//! (adjacent links): its authors list the adjacent pairs themselves. Links rigidly joined (by
//! fixed joints, one rl-core body) stay allowed whatever the SRDF says: they cannot move
//! against each other, so their contact is no collision (ur5's SRDF, for one, forgets its
//! 1 cm `ee_link` box inside `wrist_3_link`). Links the SRDF names but
//! the model lacks are reported as warnings (MoveIt ignores them too), not errors: SRDFs are
//! often shared between variants of a robot.
//!
//! Which SRDF a robot uses is one rule, [`for_robot`]: the one given, else the SRDF beside its
//! URDF (`NAME.srdf` for `NAME.urdf`, in the same directory), else none. Every command of the
//! `rl` tool that uses collision pairs (`plan`, `run --plan`, `run --view`, `scene`, `view`)
//! and rl-plan's robot loader take it from there.

use std::path::{Path, PathBuf};

use super::read_text;
use super::xml::{at, attr, children, number, parse, robot_root};
use crate::error::SgError;
use crate::scene::Model;

/// What an SRDF did to a model.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SrdfReport {
    /// Pairs allowed.
    pub disabled: usize,
    /// Pairs checked again by `<enable_collisions>`.
    pub enabled: usize,
    /// Elements naming links the model does not have.
    pub unknown_links: Vec<String>,
}

/// Applies the SRDF in `text` to `model` (see the module docs).
pub fn apply_str(text: &str, model: &mut Model) -> Result<SrdfReport, SgError> {
    let doc = parse(text)?;
    let robot = robot_root(&doc, "an SRDF")?;
    let mut report = SrdfReport::default();
    let mut allowed = crate::AllowedCollisions::new();
    let unknown = |name: &str, report: &mut SrdfReport| {
        if !report.unknown_links.iter().any(|n| n == name) {
            report.unknown_links.push(name.to_string());
        }
    };
    for d in children(robot, "disable_collisions") {
        let (l1, l2) = (attr(d, "link1")?, attr(d, "link2")?);
        match (model.body_index(l1), model.body_index(l2)) {
            (Some(a), Some(b)) => {
                allowed.allow(a, b);
                report.disabled += 1;
            }
            (a, b) => {
                if a.is_none() {
                    unknown(l1, &mut report);
                }
                if b.is_none() {
                    unknown(l2, &mut report);
                }
            }
        }
    }
    let n = model.bodies().len();
    for d in children(robot, "disable_default_collisions") {
        let l = attr(d, "link")?;
        match model.body_index(l) {
            Some(a) => {
                for b in (0..n).filter(|&b| b != a) {
                    allowed.allow(a, b);
                    report.disabled += 1;
                }
            }
            None => unknown(l, &mut report),
        }
    }
    for d in children(robot, "enable_collisions") {
        let (l1, l2) = (attr(d, "link1")?, attr(d, "link2")?);
        if let (Some(a), Some(b)) = (model.body_index(l1), model.body_index(l2)) {
            allowed.disallow(a, b);
            report.enabled += 1;
        }
    }
    *model.allowed_collisions_mut() = allowed;
    // Links rigidly joined (one kinematic body) can never move against each other: their
    // contact is permanent and meaningless, whatever the SRDF lists.
    model.allow_rigidly_joined();
    if !report.unknown_links.is_empty() {
        model.warn(format!(
            "the SRDF names links this model does not have: {}",
            report.unknown_links.join(", ")
        ));
    }
    Ok(report)
}

/// `NAME.srdf` beside `NAME.urdf` (same directory, same stem), if that file exists.
pub fn beside(urdf: &Path) -> Option<PathBuf> {
    let p = urdf.with_extension("srdf");
    p.is_file().then_some(p)
}

/// The SRDF the robot in `model` uses: `given` if any, else, when `model` is a URDF, the SRDF
/// [`beside`] it if there is one, else none (adjacent links and links rigidly joined are then
/// not checked against each other).
pub fn for_robot(model: &Path, given: Option<&Path>) -> Option<PathBuf> {
    match given {
        Some(path) => Some(path.to_path_buf()),
        None if super::is_urdf(model) => beside(model),
        None => None,
    }
}

/// Applies the SRDF file at `path` to `model`.
pub fn apply_file(path: &Path, model: &mut Model) -> Result<SrdfReport, SgError> {
    let text = read_text(path)?;
    apply_str(&text, model).map_err(|e| e.in_file(path))
}

/// A named configuration of an SRDF (`<group_state name group>` with its `<joint name value>`
/// elements): MoveIt's "home", "ready", … poses.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedState {
    /// Its name.
    pub name: String,
    /// The planning group it is for.
    pub group: String,
    /// Joint values by joint name (rad or m; several values for a multi-coordinate joint).
    pub joints: Vec<(String, Vec<f64>)>,
}

/// The named states (`<group_state>`) of the SRDF in `text`, in file order.
pub fn named_states_str(text: &str) -> Result<Vec<NamedState>, SgError> {
    let doc = parse(text)?;
    let robot = robot_root(&doc, "an SRDF")?;
    let mut out = Vec::new();
    for g in children(robot, "group_state") {
        let mut joints = Vec::new();
        for j in children(g, "joint") {
            let name = attr(j, "name")?;
            let text = attr(j, "value")?;
            let values = text
                .split_whitespace()
                .map(|v| number(j, "value", v))
                .collect::<Result<Vec<_>, _>>()?;
            if values.is_empty() {
                return Err(at(j, SgError::invalid("value", text, "no number")));
            }
            joints.push((name.to_string(), values));
        }
        out.push(NamedState {
            name: attr(g, "name")?.to_string(),
            group: attr(g, "group")?.to_string(),
            joints,
        });
    }
    Ok(out)
}

/// The named states of the SRDF file at `path`.
pub fn named_states_file(path: &Path) -> Result<Vec<NamedState>, SgError> {
    let text = read_text(path)?;
    named_states_str(&text).map_err(|e| e.in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_urdf_takes_the_srdf_given_else_the_one_beside_it() {
        let dir = std::env::temp_dir().join(format!("rl-sg-srdf-rule-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (urdf, lone, rlmdl) = (
            dir.join("arm.urdf"),
            dir.join("lone.urdf"),
            dir.join("arm.xml"),
        );
        for f in [&urdf, &lone] {
            std::fs::write(f, r#"<robot name="arm"><link name="a"/></robot>"#).unwrap();
        }
        std::fs::write(&rlmdl, "<rl><model/></rl>").unwrap();
        std::fs::write(dir.join("arm.srdf"), r#"<robot name="arm"/>"#).unwrap();
        let given = dir.join("other.srdf");
        assert_eq!(for_robot(&urdf, None), Some(dir.join("arm.srdf")));
        assert_eq!(for_robot(&urdf, Some(&given)), Some(given.clone()));
        assert_eq!(for_robot(&lone, None), None);
        // Not a URDF: no SRDF unless given, whatever lies beside it.
        assert_eq!(for_robot(&rlmdl, None), None);
        assert_eq!(for_robot(&rlmdl, Some(&given)), Some(given));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn named_states_are_read_in_file_order_with_bad_values_refused() {
        let s = named_states_str(
            r#"<robot name="r">
                 <group_state name="home" group="arm">
                   <joint name="a" value="0.5"/><joint name="b" value="-1.57"/>
                 </group_state>
                 <group_state name="open" group="hand"><joint name="f" value="0.04"/></group_state>
               </robot>"#,
        )
        .unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].name, "home");
        assert_eq!(s[0].group, "arm");
        assert_eq!(
            s[0].joints,
            vec![("a".into(), vec![0.5]), ("b".into(), vec![-1.57])]
        );
        assert_eq!(s[1].joints, vec![("f".into(), vec![0.04])]);
        let e = named_states_str(
            r#"<robot name="r"><group_state name="x" group="g"><joint name="a" value="NaN?"/></group_state></robot>"#,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("value"), "{e}");
    }
}
