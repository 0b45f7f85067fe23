//! One module per `rl` subcommand. Each exposes its clap arguments and a `run` function.

pub mod capacity;
pub mod cell;
pub mod fake_robot;
pub mod jitter;
pub mod model;
pub mod otg;
pub mod output;
pub mod placement;
pub mod plan;
pub mod progress;
pub mod run;
pub mod scene;
pub mod traj;
pub mod view;

use std::fmt;
use std::sync::OnceLock;
use std::time::Duration;

/// A command's failure: a message for the user and the process exit code.
///
/// Exit code 2 means bad usage (flags, files, values); 1 means the command ran and failed.
#[derive(Debug)]
pub struct CliError {
    message: String,
    code: u8,
}

/// The exit code when standard output was closed by its reader (`rl … | head`).
const CLOSED_OUTPUT: u8 = 0;

impl CliError {
    /// Bad usage: a flag, a file or a value the user gave is wrong (exit code 2).
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: 2,
        }
    }

    /// The command ran and failed (exit code 1).
    pub fn failed(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: 1,
        }
    }

    /// Standard output was closed by its reader: the command stops, nothing more is shown
    /// and the exit status is 0 (see [`output`]).
    pub fn closed_output() -> Self {
        Self {
            message: String::new(),
            code: CLOSED_OUTPUT,
        }
    }

    /// Whether this is [`CliError::closed_output`].
    pub fn is_closed_output(&self) -> bool {
        self.message.is_empty() && self.code == CLOSED_OUTPUT
    }

    /// The same error with `what: ` before its message (the flag a file came from, say).
    pub fn prefixed(self, what: &str) -> Self {
        if self.is_closed_output() {
            return self;
        }
        Self {
            message: format!("{what}: {}", self.message),
            code: self.code,
        }
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        self.code
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// What a subcommand returns.
impl From<rl::devices::SpecError> for CliError {
    fn from(e: rl::devices::SpecError) -> Self {
        if e.is_input() {
            Self::usage(e.message())
        } else {
            Self::failed(e.message())
        }
    }
}

pub type CliResult = Result<std::process::ExitCode, CliError>;

/// The long names (without `--`) of the flags given on the command line to the subcommand that
/// runs, as [`record_given`] found them.
static GIVEN: OnceLock<Vec<String>> = OnceLock::new();

/// Records which flags of the subcommand that runs were given on the command line (not taken
/// from their defaults), for [`given`] and [`refuse_given`]. Called once, by `main`.
pub fn record_given(command: &clap::Command, matches: &clap::ArgMatches) {
    let (mut command, mut matches) = (command, matches);
    while let Some((name, sub)) = matches.subcommand() {
        match command.find_subcommand(name) {
            Some(c) => (command, matches) = (c, sub),
            None => break,
        }
    }
    let given = matches
        .ids()
        .filter(|id| {
            matches.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine)
        })
        .filter_map(|id| {
            command
                .get_arguments()
                .find(|a| a.get_id() == id)
                .and_then(|a| a.get_long())
                .map(str::to_owned)
        })
        .collect();
    let _ = GIVEN.set(given);
}

/// Whether `--long` was given on the command line (an alias counts as its flag).
pub fn given(long: &str) -> bool {
    GIVEN.get().is_some_and(|g| g.iter().any(|f| f == long))
}

/// The one rule for flags that do not apply: the first of `flags` (long names, without `--`)
/// given on the command line is refused (exit code 2) with `--FLAG does not apply WHY`, e.g.
/// `refuse_given(&["optimizer"], "to an RL scenario (rlplan XML): …")`.
pub fn refuse_given(flags: &[&str], why: &str) -> Result<(), CliError> {
    match flags.iter().find(|f| given(f)) {
        Some(flag) => Err(CliError::usage(format!("--{flag} does not apply {why}"))),
        None => Ok(()),
    }
}

/// Seconds as a number: a bare number (any: the caller checks its range, so `-0.01` reaches
/// that check) or a duration with a unit as [`parse_duration`] takes it (`10ms`), so that a
/// sampling period is written the same way in every subcommand.
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) => Ok(x),
        Err(_) => parse_duration(text).map(|d| d.as_secs_f64()),
    }
}

/// Parses `500ms`, `30s`, `2m`, `1h`, `250us`, or a bare number of seconds.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a duration: expected e.g. 500ms, 30s, 2m"))?;
    let seconds = match unit.trim() {
        "" | "s" => value,
        "us" | "µs" => value / 1e6,
        "ms" => value / 1e3,
        "m" | "min" => value * 60.0,
        "h" => value * 3600.0,
        other => {
            return Err(format!(
                "unknown unit `{other}` in `{text}`: use us, ms, s, m or h"
            ));
        }
    };
    Duration::try_from_secs_f64(seconds).map_err(|e| format!("`{text}`: {e}"))
}

/// A per-joint argument (`--armature`, `--joint-damping`, `--joint-friction`): one value for
/// every joint, or one per joint, comma-separated.
#[derive(Clone, Debug, PartialEq)]
pub struct PerJointArg(pub Vec<f64>);

impl PerJointArg {
    /// The value of each of `dof` joints; `option` names the argument in the error.
    pub fn per_dof(&self, option: &str, dof: usize) -> Result<Vec<f64>, String> {
        match self.0.len() {
            1 => Ok(vec![self.0[0]; dof]),
            n if n == dof => Ok(self.0.clone()),
            n => Err(format!(
                "{option} has {n} values: the model has {dof} joints (give one value, or one \
                 per joint)"
            )),
        }
    }
}

/// Parses `0.195,0.195,0.195,0.195,0.074,0.074,0.074` or `0.1`: finite, not negative.
pub fn parse_per_joint(text: &str) -> Result<PerJointArg, String> {
    let values = text
        .split(',')
        .enumerate()
        .map(|(k, v)| match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
            _ => Err(format!(
                "value {} (`{}`) is not a number ≥ 0",
                k + 1,
                v.trim()
            )),
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PerJointArg(values))
}

#[cfg(test)]
mod per_joint_tests {
    use super::*;

    #[test]
    fn a_per_joint_value_is_one_or_one_per_joint_and_never_negative() {
        let one = parse_per_joint("0.1").unwrap();
        assert_eq!(one.per_dof("--armature", 3).unwrap(), [0.1, 0.1, 0.1]);
        let seven = parse_per_joint("0.195,0.195,0.195,0.195,0.074,0.074, 0.074").unwrap();
        assert_eq!(seven.per_dof("--armature", 7).unwrap()[6], 0.074);
        let e = seven.per_dof("--joint-friction", 6).unwrap_err();
        assert!(e.starts_with("--joint-friction has 7 values"), "{e}");
        for bad in ["-0.1", "0.1,x", "nan", "inf", ""] {
            assert!(parse_per_joint(bad).is_err(), "{bad}");
        }
        assert!(
            parse_per_joint("0.1,-2")
                .unwrap_err()
                .contains("value 2 (`-2`)")
        );
    }
}
