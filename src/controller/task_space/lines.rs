//! The task-space law's inputs as text lines, beside the joint targets' protocol of
//! [`stream`](crate::controller::stream): what `rl run --law cartesian-impedance --obstacle
//! SOURCE` reads from a file, standard input or a UDP socket (a tracker's output, a recorded
//! scene), sent into the running law as [`TaskInput`]s.
//!
//! | line | meaning |
//! |---|---|
//! | `sphere SLOT x y z r` | a sphere of radius `r` at (x, y, z), at rest, into slot `SLOT` |
//! | `sphere SLOT x y z r velocity vx vy vz` | the same, moving at (vx, vy, vz) (`v` for short) |
//! | `capsule SLOT ax ay az bx by bz r [velocity vx vy vz]` | a capsule from a to b |
//! | `clear SLOT` | the slot emptied (the obstacle is gone) |
//! | `pose x y z qx qy qz qw` | the tool's goal, for a law built with [`TaskMotion::Streamed`](super::TaskMotion::Streamed) (the library's; `rl run` has no streamed task: it refuses poses): position and unit quaternion |
//! | `at SECONDS …` | any line, acted on that long after the stream started (a recorded file) |
//!
//! World coordinates in m, velocities in m/s (at most [`MAX_OBSTACLE_SPEED`]); `SLOT` from 0
//! to [`MAX_OBSTACLES`] − 1 (an obstacle stays in its slot, the conservative choice, until
//! replaced or cleared). Keywords are case-insensitive; commas count as spaces; `#` starts a
//! comment line. A line that does not parse is counted malformed in the stream's report with
//! its place and what is wrong (`line 3: sphere: 4 values, it takes 5 (slot x y z radius) …`);
//! what the law refuses once it has the input (a pose while braking, a pose to a law without a
//! streamed task) is counted in the run's inputs (`refused_by_law`, the first reason kept).
//!
//! ```
//! use rl::controller::stream::{Line, parse_line_for};
//! use rl::controller::task_space::TaskInput;
//!
//! let line = parse_line_for::<8, TaskInput>("sphere 2 0.5 0 0.4 0.08 v -0.1 0 0", 7)?;
//! let Some(Line::Input(TaskInput::Obstacle { slot: 2, obstacle: Some(o) })) = line else {
//!     panic!("{line:?}")
//! };
//! assert_eq!((o.shape.radius, o.velocity.x), (0.08, -0.1));
//! let e = parse_line_for::<8, TaskInput>("sphere 2 0.5 0 0.08", 7).expect_err("4 values");
//! assert!(e.to_string().starts_with("sphere: 4 values, it takes 5"), "{e}");
//! # Ok::<(), rl::controller::stream::LineError>(())
//! ```

use glam::{DMat3, DQuat, DVec3};
use rl_core::spatial::PlueckerTransform;
use rl_sg::capsule::Capsule;

use super::{MAX_OBSTACLE_SPEED, MAX_OBSTACLES, Obstacle, TaskInput};
use crate::controller::stream::{LineError, LineInput, finite_value};

/// How far from unit length a streamed quaternion may be (it is normalised).
const UNIT_TOLERANCE: f64 = 1e-3;

const SPHERE_TAKES: &str = "5 (slot x y z radius), or 9 with velocity vx vy vz";
const CAPSULE_TAKES: &str = "8 (slot ax ay az bx by bz radius), or 12 with velocity vx vy vz";
const CLEAR_TAKES: &str = "1 (slot)";
const POSE_TAKES: &str = "7 (x y z qx qy qz qw)";

impl LineInput for TaskInput {
    const KEYWORDS: &'static str = "sphere, capsule, clear or pose";

    fn parse_words(keyword: &str, words: &[&str]) -> Option<Result<Self, LineError>> {
        let is = |k: &str| keyword.eq_ignore_ascii_case(k);
        let parsed = if is("sphere") {
            obstacle("sphere", words, 3, SPHERE_TAKES)
        } else if is("capsule") {
            obstacle("capsule", words, 6, CAPSULE_TAKES)
        } else if is("clear") {
            clear(words)
        } else if is("pose") {
            pose(words)
        } else {
            return None;
        };
        Some(parsed)
    }
}

fn count(keyword: &str, got: usize, takes: &'static str) -> LineError {
    LineError::WordCount {
        keyword: keyword.to_owned(),
        got,
        takes,
    }
}

fn slot(keyword: &'static str, token: &str) -> Result<usize, LineError> {
    match token.parse::<usize>() {
        Ok(slot) if slot < MAX_OBSTACLES => Ok(slot),
        _ => Err(LineError::Invalid {
            keyword: keyword.to_owned(),
            why: format!(
                "slot '{token}' is not one of the law's (0 to {})",
                MAX_OBSTACLES - 1
            ),
        }),
    }
}

/// `values` as numbers (the first is value `first` of the line, for an error's text).
fn numbers<const N: usize>(
    keyword: &'static str,
    first: usize,
    values: &[&str],
) -> Result<[f64; N], LineError> {
    let mut out = [0.0; N];
    for (k, (slot, token)) in out.iter_mut().zip(values).enumerate() {
        *slot = finite_value(keyword, first + k, token)?;
    }
    Ok(out)
}

/// `sphere` (`points` = 3: a centre) or `capsule` (6: two ends).
fn obstacle(
    keyword: &'static str,
    words: &[&str],
    points: usize,
    takes: &'static str,
) -> Result<TaskInput, LineError> {
    // slot, the points, the radius; then `velocity` and three values, or nothing.
    let plain = 1 + points + 1;
    let (shape, velocity) = match words.len() {
        n if n == plain => (words, None),
        n if n == plain + 4 => {
            let (shape, rest) = words.split_at(plain);
            if !(rest[0].eq_ignore_ascii_case("velocity") || rest[0].eq_ignore_ascii_case("v")) {
                return Err(LineError::Invalid {
                    keyword: keyword.to_owned(),
                    why: format!("'{}' where `velocity` (or `v`) goes", rest[0]),
                });
            }
            (shape, Some(&rest[1..]))
        }
        n => return Err(count(keyword, n, takes)),
    };
    let slot = slot(keyword, shape[0])?;
    let mut ends = [DVec3::ZERO; 2];
    for (k, end) in ends.iter_mut().take(points / 3).enumerate() {
        let [x, y, z] = numbers::<3>(keyword, 2 + 3 * k, &shape[1 + 3 * k..])?;
        *end = DVec3::new(x, y, z);
    }
    let [radius] = numbers::<1>(keyword, plain, &shape[plain - 1..])?;
    if radius < 0.0 {
        return Err(LineError::Invalid {
            keyword: keyword.to_owned(),
            why: format!("radius {radius} is negative"),
        });
    }
    let b = if points == 3 { ends[0] } else { ends[1] };
    let velocity = match velocity {
        Some(v) => DVec3::from_array(numbers::<3>(keyword, plain + 2, v)?),
        None => DVec3::ZERO,
    };
    if velocity.length() > MAX_OBSTACLE_SPEED {
        return Err(LineError::Invalid {
            keyword: keyword.to_owned(),
            why: format!(
                "speed {:.3} m/s, beyond the law's {MAX_OBSTACLE_SPEED} m/s",
                velocity.length()
            ),
        });
    }
    Ok(TaskInput::Obstacle {
        slot,
        obstacle: Some(Obstacle {
            shape: Capsule::new(ends[0], b, radius),
            velocity,
        }),
    })
}

fn clear(words: &[&str]) -> Result<TaskInput, LineError> {
    match words {
        [token] => Ok(TaskInput::Obstacle {
            slot: slot("clear", token)?,
            obstacle: None,
        }),
        _ => Err(count("clear", words.len(), CLEAR_TAKES)),
    }
}

fn pose(words: &[&str]) -> Result<TaskInput, LineError> {
    if words.len() != 7 {
        return Err(count("pose", words.len(), POSE_TAKES));
    }
    let [x, y, z, qx, qy, qz, qw] = numbers::<7>("pose", 1, words)?;
    let q = DQuat::from_xyzw(qx, qy, qz, qw);
    if (q.length() - 1.0).abs() > UNIT_TOLERANCE {
        return Err(LineError::Invalid {
            keyword: "pose".to_owned(),
            why: format!(
                "the quaternion's length is {:.4}, not 1 (x y z qx qy qz qw)",
                q.length()
            ),
        });
    }
    Ok(TaskInput::Pose(PlueckerTransform {
        rotation: DMat3::from_quat(q.normalize()),
        translation: DVec3::new(x, y, z),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::stream::{Line, parse_line_for};

    fn parse(line: &str) -> Result<Option<Line<8, TaskInput>>, LineError> {
        parse_line_for::<8, TaskInput>(line, 7)
    }

    fn input(line: &str) -> TaskInput {
        match parse(line) {
            Ok(Some(Line::Input(i))) => i,
            other => panic!("{line}: {other:?}"),
        }
    }

    #[test]
    fn spheres_capsules_and_clears_fill_the_slots() {
        let TaskInput::Obstacle {
            slot: 0,
            obstacle: Some(o),
        } = input("sphere 0 0.5 0 0.4 0.1")
        else {
            panic!()
        };
        assert_eq!(o, Obstacle::sphere(DVec3::new(0.5, 0.0, 0.4), 0.1));
        let TaskInput::Obstacle {
            slot: 63,
            obstacle: Some(o),
        } = input("CAPSULE 63, 0 0 1, 1 0 1, 0.05 velocity 0 0.2 0")
        else {
            panic!()
        };
        assert_eq!(o.shape.a, DVec3::new(0.0, 0.0, 1.0));
        assert_eq!(o.shape.b, DVec3::new(1.0, 0.0, 1.0));
        assert_eq!((o.shape.radius, o.velocity.y), (0.05, 0.2));
        assert_eq!(
            input("clear 7"),
            TaskInput::Obstacle {
                slot: 7,
                obstacle: None
            }
        );
    }

    #[test]
    fn a_pose_is_a_position_and_a_unit_quaternion() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let TaskInput::Pose(p) = input(&format!("pose 0.4 0 0.5 {h} 0 0 {h}")) else {
            panic!()
        };
        assert_eq!(p.translation, DVec3::new(0.4, 0.0, 0.5));
        assert!((p.rotation * DVec3::Y - DVec3::Z).length() < 1e-12);
        let e = parse("pose 0.4 0 0.5 1 1 0 0").expect_err("not unit");
        assert!(e.to_string().contains("length is 1.4142"), "{e}");
    }

    #[test]
    fn what_is_wrong_is_said_with_the_value() {
        let text = |line: &str| parse(line).expect_err(line).to_string();
        assert_eq!(
            text("sphere 0 1 2 3"),
            "sphere: 4 values, it takes 5 (slot x y z radius), or 9 with velocity vx vy vz"
        );
        assert_eq!(
            text("sphere 64 1 2 3 0.1"),
            "sphere: slot '64' is not one of the law's (0 to 63)"
        );
        assert_eq!(
            text("sphere 0 1 abc 3 0.1"),
            "sphere: value 3 'abc' is not a number"
        );
        assert_eq!(
            text("sphere 0 1 2 3 0.1 v 0 nan 0"),
            "sphere: value 8 'nan' is not a finite number"
        );
        assert_eq!(
            text("sphere 0 1 2 3 -0.1"),
            "sphere: radius -0.1 is negative"
        );
        assert_eq!(
            text("sphere 0 1 2 3 0.1 v 0 6 0"),
            "sphere: speed 6.000 m/s, beyond the law's 5 m/s"
        );
        assert_eq!(
            text("sphere 0 1 2 3 0.1 w 0 0 0"),
            "sphere: 'w' where `velocity` (or `v`) goes"
        );
        assert_eq!(text("clear"), "clear: 0 values, it takes 1 (slot)");
        assert_eq!(
            text("cube 0 1 2"),
            "unknown keyword 'cube' (a line starts with position, p, velocity, v, stop, \
             sphere, capsule, clear or pose)"
        );
    }
}
