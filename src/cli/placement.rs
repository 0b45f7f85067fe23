//! Where robots stand, as `rl scene` and `rl view` take it: `--place x,y,z[,rx,ry,rz]` (metres,
//! and degrees about x, y, z applied as `Rz·Ry·Rx`, as RL's rlplan `<world>`), optionally for
//! robot `I` (`--place I=x,y,z…`), and RL's planning scenarios (rlplan XML), whose model is a
//! scene, a kinematic model and the `<world>` that places it.

use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use rl_core::spatial::PlueckerTransform;
pub use rl_plan::problem::rlplan::is_scenario;
use rl_plan::problem::rlplan::{Scenario, ScenarioModel};

use super::CliError;

/// Parses `x,y,z` or `x,y,z,rx,ry,rz` (m, degrees; `Rz·Ry·Rx`); `flag` names the flag in errors.
pub fn parse_place(text: &str, flag: &str) -> Result<PlueckerTransform, CliError> {
    let v: Vec<f64> = text
        .split(',')
        .enumerate()
        .map(|(i, p)| {
            p.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    CliError::usage(format!(
                        "{flag}: value {i} ({:?}) is not a finite number",
                        p.trim()
                    ))
                })
        })
        .collect::<Result<_, _>>()?;
    let (t, r) = match v.as_slice() {
        [x, y, z] => ([*x, *y, *z], [0.0; 3]),
        [x, y, z, rx, ry, rz] => ([*x, *y, *z], [*rx, *ry, *rz]),
        _ => {
            return Err(CliError::usage(format!(
                "{flag}: {} values given: x,y,z (m) or x,y,z,rx,ry,rz (m, degrees)",
                v.len()
            )));
        }
    };
    let rot = DMat3::from_rotation_z(r[2].to_radians())
        * DMat3::from_rotation_y(r[1].to_radians())
        * DMat3::from_rotation_x(r[0].to_radians());
    Ok(PlueckerTransform::new(rot, DVec3::from_array(t)))
}

/// Splits `I=VALUE` into `(Some(I), VALUE)`; a value without `I=` is `(None, VALUE)`.
pub fn split_index<'a>(text: &'a str, flag: &str) -> Result<(Option<usize>, &'a str), CliError> {
    match text.split_once('=') {
        Some((i, rest)) => {
            let i = i.trim().parse::<usize>().map_err(|_| {
                CliError::usage(format!(
                    "{flag}: \"{i}\" before '=' is not a model index (0 is the first model)"
                ))
            })?;
            Ok((Some(i), rest))
        }
        None => Ok((None, text)),
    }
}

/// Values of a repeatable `--flag [I=]VALUE`, by model index: without `I=`, the first gives
/// model 0, the next model 1, … A model given twice is an error.
pub fn per_model<T>(
    values: &[String],
    flag: &str,
    parse: impl Fn(&str) -> Result<T, CliError>,
) -> Result<Vec<(usize, T)>, CliError> {
    let mut out: Vec<(usize, T)> = Vec::with_capacity(values.len());
    for (k, v) in values.iter().enumerate() {
        let (i, rest) = split_index(v, flag)?;
        let i = i.unwrap_or(k);
        if out.iter().any(|(j, _)| *j == i) {
            return Err(CliError::usage(format!("{flag}: model {i} given twice")));
        }
        out.push((i, parse(rest)?));
    }
    Ok(out)
}

/// A robot as an RL scenario places it: the scene, the kinematics, where they stand, and the
/// problem's start and goal.
#[derive(Clone, Debug)]
pub struct ScenarioRobot {
    /// The rlsg scene (the robot is its first model).
    pub scene: PathBuf,
    /// The kinematic model (rlmdl or rlkin).
    pub kinematics: PathBuf,
    /// Where the kinematic model's world frame is in the scene (RL's `<world>`).
    pub place: PlueckerTransform,
    /// Start configuration.
    pub start: Vec<f64>,
    /// Goal configuration.
    pub goal: Vec<f64>,
}

impl ScenarioRobot {
    /// Reads the scenario at `path`: its viewer's model (the scene rlPlanDemo draws: RL's
    /// visual meshes) when `viewer` and the file has one, else the planner's model (the scene
    /// it checks: RL's convex hulls).
    pub fn load(path: &Path, viewer: bool) -> Result<Self, CliError> {
        let what = path.display();
        let sc = Scenario::load(path).map_err(|e| CliError::usage(format!("{what}: {e}")))?;
        let m: ScenarioModel = match (&sc.viewer, viewer) {
            (Some(v), true) => v.clone(),
            _ => sc.model(),
        };
        if m.model_index != 0 {
            return Err(CliError::usage(format!(
                "{what}: the robot is model {} of its scene; only a robot that is the scene's \
                 first model is supported",
                m.model_index
            )));
        }
        let loaded = rl_core::loader::load_file::<64>(&m.kinematics)
            .map_err(|e| CliError::usage(format!("{}: {e}", m.kinematics.display())))?;
        Ok(Self {
            place: m.base(&loaded),
            scene: m.scene,
            kinematics: m.kinematics,
            start: sc.start,
            goal: sc.goal,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_are_metres_and_degrees_rz_ry_rx() {
        let x = parse_place("1,2,3", "--place").unwrap();
        assert_eq!(x.translation, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(x.rotation, DMat3::IDENTITY);
        let x = parse_place("0,0,0,0,0,90", "--place").unwrap();
        assert!((x.rotation * DVec3::X - DVec3::Y).length() < 1e-12);
        // Rz·Ry·Rx: x turned first (y to z), then z turned (z stays).
        let x = parse_place("0,0,0,90,0,90", "--place").unwrap();
        assert!((x.rotation * DVec3::Y - DVec3::Z).length() < 1e-12);
        for bad in ["1,2", "1,2,3,4", "1,x,3", "1,2,inf"] {
            let e = parse_place(bad, "--place").unwrap_err().to_string();
            assert!(e.starts_with("--place: "), "{e}");
        }
    }

    #[test]
    fn per_model_values_go_in_order_or_by_index() {
        let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let p = per_model(&v(&["a", "b"]), "--x", |s| Ok(s.to_string())).unwrap();
        assert_eq!(p, vec![(0, "a".into()), (1, "b".into())]);
        let p = per_model(&v(&["1=a"]), "--x", |s| Ok(s.to_string())).unwrap();
        assert_eq!(p, vec![(1, "a".into())]);
        assert!(per_model(&v(&["a", "0=b"]), "--x", |s| Ok(s.to_string())).is_err());
        assert!(per_model(&v(&["q=a"]), "--x", |s| Ok(s.to_string())).is_err());
    }
}
