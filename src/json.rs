//! The version key of the `rl` tool's JSON outputs (issue 25).
//!
//! Every top-level JSON object a command prints carries one key, [`SCHEMA_KEY`] (`"schema"`),
//! whose value names the command and the version of its layout: `"rl.<command>/<version>"`,
//! e.g. `"rl.model.eval/1"` (subcommands joined by dots). A reader checks the whole string; the
//! version goes up when a key is removed, renamed or changes its meaning or unit (adding a key
//! keeps it). `docs/json.md` documents every output's keys with their types and units, and
//! `tests/json_schema.rs` checks that each command's output carries the key and that the
//! document names every top-level key it prints.

use serde_json::Value;

/// The name of the version key, the same in every output.
pub const SCHEMA_KEY: &str = "schema";

/// The version key's value for `command` (e.g. `"model.eval"`) at `version`:
/// `"rl.model.eval/1"`.
pub fn schema_id(command: &str, version: u32) -> String {
    format!("rl.{command}/{version}")
}

/// Adds the version key of `command` at `version` to `value` if it is an object (other values,
/// which have no keys, are returned as they are), and returns it.
pub fn versioned(command: &str, version: u32, mut value: Value) -> Value {
    tag(command, version, &mut value);
    value
}

/// Adds the version key of `command` at `version` to `value` in place, if it is an object.
pub fn tag(command: &str, version: u32, value: &mut Value) {
    if let Value::Object(map) = value {
        map.insert(
            SCHEMA_KEY.into(),
            Value::String(schema_id(command, version)),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn objects_get_the_key_other_values_stay() {
        let v = versioned("model.eval", 1, json!({"dof": 6}));
        assert_eq!(v, json!({"dof": 6, "schema": "rl.model.eval/1"}));
        assert_eq!(versioned("x", 1, json!([1, 2])), json!([1, 2]));
        assert_eq!(schema_id("plan.bench", 2), "rl.plan.bench/2");
    }
}
