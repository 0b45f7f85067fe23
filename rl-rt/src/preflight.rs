//! What stands between this machine and hard real time, each finding with its fix.
//!
//! Reads the kernel's preemption model, RT throttling, CPU frequency governor, isolated CPUs,
//! clock source, memlock and rtprio limits, tries SCHED_FIFO on a probe thread, and lists the
//! other programs' threads at real-time priority ([`rt_threads`]: the work that can starve a
//! loop on a shared machine). Nothing is changed; the report says what to change.

use core::fmt;
use std::fs;
use std::path::Path;

pub mod rt_threads;

use crate::memory::{self, Capability};
use crate::thread::{Policy, RtThreadBuilder, ThreadError};

/// How a finding bears on real-time behaviour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Fine for hard real time.
    Ok,
    /// Nothing to judge (e.g. no cpufreq in a VM) or a matter of taste.
    Info,
    /// Works, but costs latency or risks a deadline.
    Warn,
    /// Prevents real-time operation.
    Fail,
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Ok => "ok",
            Self::Info => "info",
            Self::Warn => "warn",
            Self::Fail => "FAIL",
        })
    }
}

/// One finding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// What was checked.
    pub name: &'static str,
    /// The verdict.
    pub status: Status,
    /// What was found.
    pub found: String,
    /// How to fix it, when it needs fixing.
    pub fix: Option<String>,
}

/// All findings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Report {
    /// The findings, in a fixed order.
    pub items: Vec<Item>,
}

impl Report {
    /// The worst status of all findings.
    pub fn worst(&self) -> Status {
        self.items
            .iter()
            .map(|i| i.status)
            .max()
            .unwrap_or(Status::Ok)
    }

    /// The report as a JSON array of `{name, status, found, fix}` objects.
    pub fn to_json(&self) -> String {
        let items: Vec<String> = self
            .items
            .iter()
            .map(|i| {
                format!(
                    "{{\"name\":{},\"status\":\"{}\",\"found\":{},\"fix\":{}}}",
                    json_string(i.name),
                    i.status,
                    json_string(&i.found),
                    i.fix
                        .as_deref()
                        .map_or_else(|| "null".to_owned(), json_string)
                )
            })
            .collect();
        format!("[{}]", items.join(","))
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for item in &self.items {
            writeln!(f, "[{:>4}] {}: {}", item.status, item.name, item.found)?;
            if let Some(fix) = &item.fix {
                writeln!(f, "       fix: {fix}")?;
            }
        }
        Ok(())
    }
}

fn json_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn read_trim(path: impl AsRef<Path>) -> Option<String> {
    fs::read_to_string(path).ok().map(|s| s.trim().to_owned())
}

fn item(name: &'static str, status: Status, found: impl Into<String>, fix: Option<&str>) -> Item {
    Item {
        name,
        status,
        found: found.into(),
        fix: fix.map(str::to_owned),
    }
}

/// `Ok` when `ok`, else `Warn` with the remedy `fix`.
fn ok_or_warn(name: &'static str, ok: bool, found: String, fix: &str) -> Item {
    if ok {
        item(name, Status::Ok, found, None)
    } else {
        item(name, Status::Warn, found, Some(fix))
    }
}

/// Other programs' real-time threads listed one by one, at most; the rest are counted.
pub const MAX_RT_THREADS_LISTED: usize = 8;

/// Runs every check. Spawns one short-lived probe thread to try SCHED_FIFO.
pub fn check() -> Report {
    let mut report = Report {
        items: vec![
            kernel_preemption(),
            rt_throttling(),
            cpu_governor(),
            isolated_cpus(),
            clock_source(),
            idle_states(),
            virtualisation(),
            memlock(),
            rtprio(),
            fifo_permitted(),
        ],
    };
    report
        .items
        .extend(rt_thread_items(&rt_threads::other_rt_threads()));
    report
}

/// The findings on other real-time threads: a summary (`other real-time threads`), then a
/// warning for each other program's thread (`real-time thread`, at most
/// [`MAX_RT_THREADS_LISTED`], the rest counted in the summary). Kernel threads (interrupt
/// threads, `migration/N`, …) are the kernel's own work: counted, not warned about.
pub fn rt_thread_items(threads: &[rt_threads::RtThread]) -> Vec<Item> {
    let name = "other real-time threads";
    let (kernel, user): (Vec<_>, Vec<_>) = threads.iter().partition(|t| t.kernel);
    let kernel_note = if kernel.is_empty() {
        String::new()
    } else {
        let top = kernel[0];
        format!(
            "; {} kernel thread{} (the kernel's own, highest {} {} {})",
            kernel.len(),
            if kernel.len() == 1 { "" } else { "s" },
            top.comm,
            top.policy.name(),
            top.priority
        )
    };
    let mut items = Vec::with_capacity(user.len().min(MAX_RT_THREADS_LISTED) + 1);
    if user.is_empty() {
        items.push(item(
            name,
            Status::Ok,
            format!("none in other programs{kernel_note}"),
            None,
        ));
        return items;
    }
    let more = user.len().saturating_sub(MAX_RT_THREADS_LISTED);
    items.push(item(
        name,
        Status::Warn,
        format!(
            "{} thread{} of other programs at real-time priority{}{kernel_note}",
            user.len(),
            if user.len() == 1 { "" } else { "s" },
            if more > 0 {
                format!(" ({MAX_RT_THREADS_LISTED} listed below, {more} more not)")
            } else {
                String::new()
            }
        ),
        Some(
            "a real-time thread at or above a loop's priority (rl run: 80, its in-process fake \
             device 79) takes their CPU whenever it runs, and the run loses replies or misses \
             deadlines: give it other CPUs (taskset, isolcpus), lower its priority (chrt), or \
             stop it while the loop runs",
        ),
    ));
    for t in user.iter().take(MAX_RT_THREADS_LISTED) {
        items.push(item(
            "real-time thread",
            Status::Warn,
            format!(
                "pid {} tid {} `{}` {} priority {}",
                t.pid,
                t.tid,
                t.comm,
                t.policy.name(),
                t.priority
            ),
            Some("see `other real-time threads`"),
        ));
    }
    items
}

fn kernel_preemption() -> Item {
    let name = "kernel preemption";
    let release = read_trim("/proc/sys/kernel/osrelease").unwrap_or_default();
    let version = read_trim("/proc/sys/kernel/version").unwrap_or_default();
    let realtime = read_trim("/sys/kernel/realtime").is_some_and(|s| s == "1");
    let model = if realtime || version.contains("PREEMPT_RT") {
        "PREEMPT_RT"
    } else if version.contains("PREEMPT_DYNAMIC") {
        "PREEMPT_DYNAMIC"
    } else if version.contains("PREEMPT") {
        "PREEMPT"
    } else {
        "no forced preemption"
    };
    // With debugfs mounted, PREEMPT_DYNAMIC kernels show the active mode in parentheses.
    let mode = read_trim("/sys/kernel/debug/sched/preempt")
        .map(|m| format!(", mode: {m}"))
        .unwrap_or_default();
    let found = format!(
        "{model} ({release}{mode}); /sys/kernel/realtime = {}",
        u8::from(realtime)
    );
    ok_or_warn(
        name,
        model == "PREEMPT_RT",
        found,
        "boot a PREEMPT_RT kernel (CONFIG_PREEMPT_RT=y; Debian: linux-image-rt-amd64 / \
         -rt-arm64; Raspberry Pi: build the rpi kernel with PREEMPT_RT or use a \
         prebuilt RT image); without it worst-case latency is unbounded (milliseconds)",
    )
}

fn rt_throttling() -> Item {
    let name = "RT throttling";
    match read_trim("/proc/sys/kernel/sched_rt_runtime_us") {
        Some(v) if v == "-1" => item(name, Status::Ok, "off (sched_rt_runtime_us = -1)", None),
        Some(v) => {
            let period = read_trim("/proc/sys/kernel/sched_rt_period_us").unwrap_or("?".into());
            item(
                name,
                Status::Warn,
                format!("real-time tasks limited to {v} µs per {period} µs"),
                Some(
                    "a loop that ever needs the CPU longer is stalled until the period ends; \
                     `sysctl kernel.sched_rt_runtime_us=-1` (persist in /etc/sysctl.d/) once the \
                     loop is trusted not to spin",
                ),
            )
        }
        None => item(name, Status::Info, "sched_rt_runtime_us not readable", None),
    }
}

fn cpu_governor() -> Item {
    let name = "CPU frequency governor";
    let mut governors: Vec<String> = Vec::new();
    for cpu in 0.. {
        let dir = format!("/sys/devices/system/cpu/cpu{cpu}");
        if !Path::new(&dir).exists() {
            break;
        }
        if let Some(g) = read_trim(format!("{dir}/cpufreq/scaling_governor")) {
            governors.push(format!("cpu{cpu}={g}"));
        }
    }
    if governors.is_empty() {
        return item(
            name,
            Status::Info,
            "no cpufreq (fixed frequency or a VM)",
            None,
        );
    }
    let found = governors.join(" ");
    ok_or_warn(
        name,
        governors.iter().all(|g| g.ends_with("=performance")),
        found,
        "frequency changes add latency: `cpupower frequency-set -g performance` or write \
         `performance` to /sys/devices/system/cpu/cpu*/cpufreq/scaling_governor \
         (Raspberry Pi: also force_turbo=1 in config.txt)",
    )
}

fn cmdline_value(cmdline: &str, key: &str) -> Option<String> {
    cmdline
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key)?.strip_prefix('=').map(str::to_owned))
}

fn isolated_cpus() -> Item {
    let name = "isolated CPUs";
    let cmdline = read_trim("/proc/cmdline").unwrap_or_default();
    let isolated = read_trim("/sys/devices/system/cpu/isolated").filter(|s| !s.is_empty());
    let nohz = read_trim("/sys/devices/system/cpu/nohz_full")
        .filter(|s| !s.is_empty() && s != "(null)")
        .or_else(|| cmdline_value(&cmdline, "nohz_full"));
    let rcu = cmdline_value(&cmdline, "rcu_nocbs");
    let found = format!(
        "isolcpus: {}, nohz_full: {}, rcu_nocbs: {}",
        isolated.as_deref().unwrap_or("none"),
        nohz.as_deref().unwrap_or("none"),
        rcu.as_deref().unwrap_or("none")
    );
    ok_or_warn(
        name,
        isolated.is_some(),
        found,
        "reserve a CPU for the loop: add `isolcpus=3 nohz_full=3 rcu_nocbs=3` to the \
         kernel command line (Raspberry Pi: /boot/firmware/cmdline.txt) and pin the \
         loop there (`rl jitter --cpu 3`, RtThreadBuilder::cpus([3])); move IRQs away \
         (/proc/irq/*/smp_affinity)",
    )
}

fn clock_source() -> Item {
    let name = "clock source";
    let dir = "/sys/devices/system/clocksource/clocksource0";
    match read_trim(format!("{dir}/current_clocksource")) {
        Some(c) => {
            let available = read_trim(format!("{dir}/available_clocksource")).unwrap_or_default();
            let found = format!("{c} (available: {available})");
            // TSC (x86) and the arch timer (ARM) are read without a trap; hpet/acpi_pm are slow.
            ok_or_warn(
                name,
                matches!(c.as_str(), "tsc" | "arch_sys_counter" | "kvm-clock"),
                found,
                "a slow clock source makes every clock read costly; use tsc (x86) or \
                 arch_sys_counter (ARM) via `clocksource=` on the kernel command line",
            )
        }
        None => item(name, Status::Info, "not readable", None),
    }
}

fn idle_states() -> Item {
    let name = "CPU idle states";
    let driver = read_trim("/sys/devices/system/cpu/cpuidle/current_driver");
    let mut states = Vec::new();
    let mut deepest_us = 0u64;
    for i in 0.. {
        let dir = format!("/sys/devices/system/cpu/cpu0/cpuidle/state{i}");
        let Some(state) = read_trim(format!("{dir}/name")) else {
            break;
        };
        let latency: u64 = read_trim(format!("{dir}/latency"))
            .and_then(|l| l.parse().ok())
            .unwrap_or(0);
        let disabled = read_trim(format!("{dir}/disable")).is_some_and(|d| d == "1");
        if !disabled {
            deepest_us = deepest_us.max(latency);
        }
        states.push(format!(
            "{state} {latency} µs{}",
            if disabled { " (disabled)" } else { "" }
        ));
    }
    let Some(driver) = driver else {
        return item(name, Status::Info, "no cpuidle driver", None);
    };
    let found = format!("driver {driver}; states: {}", states.join(", "));
    ok_or_warn(
        name,
        deepest_us <= 10,
        found,
        "leaving a deep idle state adds up to its exit latency to a wake-up: hold \
         /dev/cpu_dma_latency at 0 while the loop runs (`rl jitter` does; in code \
         rl_rt::cpu_latency::CpuLatencyHint::hold(0)) or limit C-states on the kernel \
         command line (processor.max_cstate=1, intel_idle.max_cstate=0)",
    )
}

/// Share of CPU time stolen by the hypervisor since boot, in percent, from /proc/stat.
fn steal_percent() -> Option<f64> {
    let stat = fs::read_to_string("/proc/stat").ok()?;
    let line = stat.lines().find(|l| l.starts_with("cpu "))?;
    let fields: Vec<u64> = line
        .split_whitespace()
        .skip(1)
        .filter_map(|f| f.parse().ok())
        .collect();
    let total: u64 = fields.iter().take(8).sum();
    let steal = *fields.get(7)?;
    (total > 0).then(|| 100.0 * steal as f64 / total as f64)
}

fn virtualisation() -> Item {
    let name = "virtualisation";
    let cpuinfo = fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let guest = cpuinfo
        .lines()
        .filter(|l| l.starts_with("flags"))
        .any(|l| l.split_whitespace().any(|f| f == "hypervisor"));
    let steal = steal_percent().map_or("unknown".to_owned(), |p| format!("{p:.2} %"));
    if guest {
        item(
            name,
            Status::Warn,
            format!("running as a virtual machine guest; CPU time stolen since boot: {steal}"),
            Some(
                "the hypervisor can stop a virtual CPU for milliseconds (steal time), which no \
                 guest setting removes: run on bare metal, or give the VM dedicated, pinned \
                 physical cores",
            ),
        )
    } else {
        item(
            name,
            Status::Ok,
            format!("bare metal (no hypervisor flag); steal {steal}"),
            None,
        )
    }
}

fn memlock() -> Item {
    let name = "memlock limit";
    let cap = memory::has_capability(Capability::IpcLock);
    match memory::memlock_limit() {
        Ok(l) => {
            let found = format!(
                "RLIMIT_MEMLOCK soft {} hard {}, CAP_IPC_LOCK {}",
                l.soft.map_or("unlimited".into(), |b| format!("{b} bytes")),
                l.hard.map_or("unlimited".into(), |b| format!("{b} bytes")),
                if cap { "yes" } else { "no" }
            );
            ok_or_warn(
                name,
                cap || l.soft.is_none(),
                found,
                "mlockall(MCL_CURRENT|MCL_FUTURE) will fail once the process outgrows \
                 the limit: LimitMEMLOCK=infinity in a systemd unit, `ulimit -l \
                 unlimited`, or `@realtime - memlock unlimited` in \
                 /etc/security/limits.conf",
            )
        }
        Err(e) => item(name, Status::Info, format!("getrlimit failed: {e}"), None),
    }
}

fn rtprio() -> Item {
    let name = "rtprio limit";
    let cap = memory::has_capability(Capability::SysNice);
    match memory::rtprio_limit() {
        Ok(l) => {
            let found = format!(
                "RLIMIT_RTPRIO soft {} hard {}, CAP_SYS_NICE {}",
                l.soft.map_or("unlimited".into(), |p| p.to_string()),
                l.hard.map_or("unlimited".into(), |p| p.to_string()),
                if cap { "yes" } else { "no" }
            );
            ok_or_warn(
                name,
                cap || l.soft.is_none_or(|p| p >= 90),
                found,
                "real-time priorities above the limit are refused: LimitRTPRIO=99 in a \
                 systemd unit, `@realtime - rtprio 99` in /etc/security/limits.conf, or \
                 grant CAP_SYS_NICE (setcap cap_sys_nice+ep)",
            )
        }
        Err(e) => item(name, Status::Info, format!("getrlimit failed: {e}"), None),
    }
}

/// Whether this process may run a SCHED_FIFO thread, tried on a probe thread at priority 1.
/// `Err` carries the kernel's refusal with its remedy.
pub fn probe_fifo() -> Result<(), ThreadError> {
    RtThreadBuilder::new("rl-rt-probe")
        .policy(Policy::Fifo)
        .priority(1)
        .stack_size(64 << 10)
        .prefault_stack(0)
        .spawn(|| ())?
        .join()
        .map_err(|_| ThreadError::SetupLost)
}

fn fifo_permitted() -> Item {
    let name = "SCHED_FIFO permitted";
    match probe_fifo() {
        Ok(()) => item(
            name,
            Status::Ok,
            "yes (probe thread ran at SCHED_FIFO 1)",
            None,
        ),
        Err(e) => Item {
            name,
            status: Status::Fail,
            found: "no".into(),
            fix: Some(e.to_string()),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_check_reports_something() {
        let report = check();
        let names: Vec<&str> = report.items.iter().map(|i| i.name).collect();
        // Then one line for each other program's real-time thread, at most the bound.
        let (fixed, listed) = names.split_at(names.len().min(11));
        assert!(
            listed.len() <= MAX_RT_THREADS_LISTED
                && listed.iter().all(|n| *n == "real-time thread"),
            "{listed:?}"
        );
        assert_eq!(
            fixed,
            [
                "kernel preemption",
                "RT throttling",
                "CPU frequency governor",
                "isolated CPUs",
                "clock source",
                "CPU idle states",
                "virtualisation",
                "memlock limit",
                "rtprio limit",
                "SCHED_FIFO permitted",
                "other real-time threads"
            ]
        );
        for i in &report.items {
            assert!(!i.found.is_empty(), "{} found nothing", i.name);
            if i.status >= Status::Warn {
                assert!(i.fix.is_some(), "{} is {} without a fix", i.name, i.status);
            }
        }
    }

    #[test]
    fn other_real_time_threads_are_warned_about_one_by_one_up_to_the_bound() {
        use rt_threads::{RtPolicy, RtThread};
        let thread = |tid: u32, priority: u32, kernel: bool| RtThread {
            pid: 100,
            tid,
            comm: if kernel { "irq/9-acpi" } else { "spinner" }.into(),
            policy: RtPolicy::Fifo,
            priority,
            kernel,
        };
        let none = rt_thread_items(&[thread(1, 50, true)]);
        assert_eq!(none.len(), 1);
        assert_eq!(none[0].status, Status::Ok);
        assert_eq!(
            none[0].found,
            "none in other programs; 1 kernel thread (the kernel's own, highest irq/9-acpi \
             SCHED_FIFO 50)"
        );
        let mut many: Vec<RtThread> = (0..10).map(|k| thread(200 + k, 90, false)).collect();
        many.push(thread(2, 50, true));
        let items = rt_thread_items(&many);
        assert_eq!(items.len(), 1 + MAX_RT_THREADS_LISTED);
        assert_eq!(items[0].status, Status::Warn);
        assert!(
            items[0]
                .found
                .starts_with("10 threads of other programs at real-time priority (8 listed below, 2 more not); 1 kernel thread"),
            "{}",
            items[0].found
        );
        assert!(
            items[0]
                .fix
                .as_deref()
                .is_some_and(|f| f.contains("taskset"))
        );
        assert_eq!(
            items[1].found,
            "pid 100 tid 200 `spinner` SCHED_FIFO priority 90"
        );
        assert!(
            items[1..]
                .iter()
                .all(|i| i.status == Status::Warn && i.fix.is_some())
        );
    }

    #[test]
    fn cmdline_values_are_parsed() {
        let c = "BOOT_IMAGE=/vmlinuz isolcpus=2,3 nohz_full=2-3 quiet";
        assert_eq!(cmdline_value(c, "nohz_full").as_deref(), Some("2-3"));
        assert_eq!(cmdline_value(c, "rcu_nocbs"), None);
    }

    #[test]
    fn json_strings_are_escaped() {
        assert_eq!(json_string("a\"b\\c\nd\u{1}"), "\"a\\\"b\\\\c\\nd\\u0001\"");
    }
}
