//! A network namespace made for one test (root needed) and removed when dropped, for the tests
//! that run `rl fake-robot ethercat` and `rl run --device ethercat://` on a veth pair.
#![allow(dead_code)]

use std::process::Command;

/// A network namespace, deleted (with the interfaces in it) when dropped.
pub struct Netns(pub String);

impl Drop for Netns {
    fn drop(&mut self) {
        let _ = Command::new("ip").args(["netns", "del", &self.0]).status();
    }
}

impl Netns {
    /// `<RL_NETNS_PREFIX or default_prefix>-<pid>` with the veth pair `a` <-> `b`, both up.
    pub fn with_veth(default_prefix: &str, a: &str, b: &str) -> Self {
        let prefix = std::env::var("RL_NETNS_PREFIX").unwrap_or_else(|_| default_prefix.into());
        let ns = Self(format!("{prefix}-{}", std::process::id()));
        assert!(ip(&["netns", "add", &ns.0]));
        assert!(ip(&[
            "-n", &ns.0, "link", "add", a, "type", "veth", "peer", "name", b
        ]));
        assert!(ip(&["-n", &ns.0, "link", "set", a, "up"]));
        assert!(ip(&["-n", &ns.0, "link", "set", b, "up"]));
        ns
    }

    /// `program` run inside the namespace.
    pub fn command(&self, program: &str) -> Command {
        let mut c = Command::new("ip");
        c.args(["netns", "exec", &self.0, program]);
        c
    }
}

/// `ip ARGS`, whether it succeeded.
pub fn ip(args: &[&str]) -> bool {
    Command::new("ip")
        .args(args)
        .status()
        .is_ok_and(|s| s.success())
}

/// Whether the process runs as root.
pub fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status").is_ok_and(|s| {
        s.lines()
            .find(|l| l.starts_with("Uid:"))
            .and_then(|l| l.split_whitespace().nth(2))
            == Some("0")
    })
}
