//! A network namespace with a veth pair inside it, made for one test and removed when dropped:
//! the fake segment listens on one end, the master opens the other. Needs root (CI runs as root);
//! [`Veth::create`] says why it cannot, and the test prints `SKIPPED` with that reason.

use std::fs::File;
use std::os::fd::AsFd;
use std::process::Command;
use std::sync::atomic::{AtomicU32, Ordering};

use nix::sched::{CloneFlags, setns};

/// A namespace `ns` holding the veth pair `a` <-> `b`, both up.
#[derive(Debug)]
pub struct Veth {
    /// The namespace's name (for `ip netns exec`).
    pub ns: String,
    /// The master's end.
    pub a: String,
    /// The fake segment's end.
    pub b: String,
}

fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("cannot run `ip`: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "`ip {}` failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

impl Veth {
    /// Creates `rlecat-<pid>-<n>` (the prefix from `RL_NETNS_PREFIX` when set, so that runs
    /// beside each other on one machine can tell theirs apart) with the pair `ecm<n>` (master)
    /// and `ecs<n>` (segment).
    pub fn create() -> Result<Self, String> {
        static NEXT: AtomicU32 = AtomicU32::new(0);
        if !super::is_root() {
            return Err(
                "needs root for a network namespace and raw sockets (CI runs as root)".into(),
            );
        }
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let prefix = std::env::var("RL_NETNS_PREFIX").unwrap_or_else(|_| "rlecat".into());
        let ns = format!("{prefix}-{}-{n}", std::process::id());
        let (a, b) = (format!("ecm{n}"), format!("ecs{n}"));
        ip(&["netns", "add", &ns])?;
        let v = Self { ns, a, b };
        ip(&[
            "-n", &v.ns, "link", "add", &v.a, "type", "veth", "peer", "name", &v.b,
        ])?;
        // No IPv6 chatter (router solicitations) on the pair: only EtherCAT frames.
        let _ = Command::new("ip")
            .args([
                "netns",
                "exec",
                &v.ns,
                "sysctl",
                "-qw",
                "net.ipv6.conf.all.disable_ipv6=1",
            ])
            .status();
        for dev in [&v.a, &v.b] {
            ip(&["-n", &v.ns, "link", "set", dev, "up"])?;
        }
        Ok(v)
    }

    /// Runs `f` on this thread inside the namespace (sockets opened there stay there), then
    /// returns to the namespace the thread was in.
    pub fn enter<T>(&self, f: impl FnOnce() -> T) -> T {
        let home = File::open("/proc/thread-self/ns/net").expect("own network namespace");
        let target = File::open(format!("/var/run/netns/{}", self.ns)).expect("test namespace");
        setns(target.as_fd(), CloneFlags::CLONE_NEWNET).expect("setns into the test namespace");
        let r = f();
        setns(home.as_fd(), CloneFlags::CLONE_NEWNET).expect("setns back");
        r
    }

    /// Sets interface `dev` of the namespace up or down (a cable plugged or pulled).
    pub fn set_link(&self, dev: &str, up: bool) -> Result<(), String> {
        ip(&[
            "-n",
            &self.ns,
            "link",
            "set",
            dev,
            if up { "up" } else { "down" },
        ])
    }

    /// A command run inside the namespace (`ip netns exec NS program`).
    pub fn command(&self, program: &str) -> Command {
        let mut c = Command::new("ip");
        c.args(["netns", "exec", &self.ns, program]);
        c
    }
}

impl Drop for Veth {
    fn drop(&mut self) {
        // Deleting the namespace deletes the veth pair inside it.
        if let Err(e) = ip(&["netns", "del", &self.ns]) {
            eprintln!("cleanup: {e}");
        }
    }
}

/// The test's namespace, or `None` after printing `SKIPPED: <why>`.
pub fn veth_or_skip(test: &str) -> Option<Veth> {
    match Veth::create() {
        Ok(v) => Some(v),
        Err(why) => {
            println!("SKIPPED: {test}: {why}");
            None
        }
    }
}
