//! Other threads at real-time priority: the work that can starve a real-time loop, or the
//! in-process fake device beside it, on a shared machine. Read from `/proc/*/task/*/stat`
//! (policy and priority of every thread; no privileges needed); this process's own threads
//! are left out.

use std::fs;

/// A real-time scheduling policy found on a thread.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum RtPolicy {
    /// `SCHED_FIFO`.
    Fifo,
    /// `SCHED_RR`.
    RoundRobin,
    /// `SCHED_DEADLINE` (runs before every FIFO and RR thread).
    Deadline,
}

impl RtPolicy {
    /// The kernel's policy number (`/proc/…/stat` field 41), if it is a real-time one.
    pub fn from_number(policy: u32) -> Option<Self> {
        match policy {
            1 => Some(Self::Fifo),
            2 => Some(Self::RoundRobin),
            6 => Some(Self::Deadline),
            _ => None,
        }
    }

    /// The policy's name, as `chrt` prints it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fifo => "SCHED_FIFO",
            Self::RoundRobin => "SCHED_RR",
            Self::Deadline => "SCHED_DEADLINE",
        }
    }
}

/// One thread at a real-time policy.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RtThread {
    /// Its process.
    pub pid: u32,
    /// The thread.
    pub tid: u32,
    /// Its name (`comm`, at most 15 bytes).
    pub comm: String,
    /// Its policy.
    pub policy: RtPolicy,
    /// Its real-time priority (1 to 99; 0 for `SCHED_DEADLINE`).
    pub priority: u32,
    /// A kernel thread (`PF_KTHREAD`): interrupt threads, `migration/N`, `watchdog/N`, … —
    /// part of the kernel's own work, not another program's.
    pub kernel: bool,
}

/// `PF_KTHREAD` in the `flags` field of `/proc/…/stat`.
const PF_KTHREAD: u64 = 0x0020_0000;

/// A thread's scheduling from the text of its `/proc/<pid>/task/<tid>/stat`; `None` when it
/// does not parse or the policy is not a real-time one. The name may hold spaces and
/// parentheses: the fields after it start at the last `)`.
pub fn parse_stat(pid: u32, stat: &str) -> Option<RtThread> {
    let open = stat.find('(')?;
    let close = stat.rfind(')')?;
    let tid = stat.get(..open)?.trim().parse().ok()?;
    let comm = stat.get(open + 1..close)?.to_owned();
    // Fields from 3 (`state`) on: flags is field 9, rt_priority 40, policy 41.
    let fields: Vec<&str> = stat.get(close + 1..)?.split_whitespace().collect();
    let field = |n: usize| fields.get(n - 3).copied();
    let flags: u64 = field(9)?.parse().ok()?;
    let priority = field(40)?.parse().ok()?;
    let policy = RtPolicy::from_number(field(41)?.parse().ok()?)?;
    Some(RtThread {
        pid,
        tid,
        comm,
        policy,
        priority,
        kernel: flags & PF_KTHREAD != 0,
    })
}

/// Every thread of other processes at a real-time policy, highest priority first (deadline
/// threads before all). Threads that end while being read are skipped.
pub fn other_rt_threads() -> Vec<RtThread> {
    let me = std::process::id();
    let mut found = Vec::new();
    let Ok(procs) = fs::read_dir("/proc") else {
        return found;
    };
    for entry in procs.flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|n| n.parse::<u32>().ok())
        else {
            continue;
        };
        if pid == me {
            continue;
        }
        let Ok(tasks) = fs::read_dir(entry.path().join("task")) else {
            continue;
        };
        for task in tasks.flatten() {
            if let Some(t) = fs::read_to_string(task.path().join("stat"))
                .ok()
                .and_then(|s| parse_stat(pid, &s))
            {
                found.push(t);
            }
        }
    }
    found.sort_by(|a, b| {
        (b.policy == RtPolicy::Deadline, b.priority, a.pid, a.tid).cmp(&(
            a.policy == RtPolicy::Deadline,
            a.priority,
            b.pid,
            b.tid,
        ))
    });
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stat_line_with_a_strange_name_parses() {
        // A FIFO 95 user thread named "a) (b c" (fields 3 to 52; flags 4194560, no PF_KTHREAD).
        let stat = "4242 (a) (b c) S 1 4242 4242 0 -1 4194560 120 0 0 0 1 2 0 0 -96 0 3 0 \
                    123456 10000000 300 18446744073709551615 1 1 0 0 0 0 0 0 0 0 0 0 17 1 95 1 \
                    0 0 0 0 0 0 0 0 0 0 0";
        let t = parse_stat(4240, stat).expect("parses");
        assert_eq!(
            t,
            RtThread {
                pid: 4240,
                tid: 4242,
                comm: "a) (b c".into(),
                policy: RtPolicy::Fifo,
                priority: 95,
                kernel: false,
            }
        );
        // The same thread at SCHED_OTHER is not listed; a kernel thread is marked.
        let other = stat.replace(" 95 1 ", " 0 0 ");
        assert_eq!(parse_stat(4240, &other), None);
        let kthread = stat.replace(" 4194560 ", " 2129984 ");
        assert!(parse_stat(4240, &kthread).expect("parses").kernel);
        assert_eq!(parse_stat(1, "garbage"), None);
    }
}
