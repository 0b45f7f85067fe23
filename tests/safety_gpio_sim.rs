//! The safety chain's Linux GPIO backend (`rl::controller::safety::gpio`, `gpiocdev`) on
//! simulated lines of the kernel's gpio-sim module, in runs against the fake H7: line 0 the
//! e-stop (normally closed, closed reads high: the backend's default), line 1 the watchdog, line
//! 2 the brake. Checks, in one test on one simulated chip:
//!
//! 1. e-stop pulled up: the run starts and finishes; the watchdog line is seen toggling about
//!    once per chain cycle and holds low after; the brake line is high while the arm moves and
//!    low after;
//! 2. e-stop pulled down before a run: the run is refused naming the line, nothing moves, the
//!    brake line never rises;
//! 3. e-stop pulled down during a run: the run ends with the safety fault in stop category 0,
//!    the brake line drops, and pulling the e-stop up again moves nothing.
//!
//! It runs only where the kernel has gpio-sim (root, configfs, the module): elsewhere it prints
//! one `SKIPPED:` line with the reason and passes.
#![cfg(feature = "gpio")]

mod common;
mod late;

use std::fs;
use std::os::unix::fs::MetadataExt;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use rl::controller::safety::SafetyHandle;
use rl::controller::safety::gpio::{GpioChain, GpioLine};
use rl::controller::{ControlRun, Fault, RunEnd, RunError, RunOptions, RunReport, rv6sl};
use rl::drivers::fake::h7_controller::FakeH7;
use rl::drivers::mitsubishi_h7::MitsubishiH7;
use rl::drivers::safety::{ChainState, StopCategory, StopReason};

const NAME: &str = "safety chain on gpio-sim lines";
const ESTOP: u32 = 0;
const WATCHDOG: u32 = 1;
const BRAKE: u32 = 2;
/// How often the sampler reads the output lines.
const SAMPLE: Duration = Duration::from_micros(200);

/// A gpio-sim chip of 8 lines, taken down when dropped (after the chains holding its lines).
struct SimChip {
    config: PathBuf,
    /// `/sys/devices/platform/<dev_name>/<chip_name>`, where the lines' `sim_gpioN` are.
    lines: PathBuf,
    /// `gpiochipN`, its name under `/dev`.
    chip: String,
}

/// A sysfs or configfs attribute, trimmed.
fn read(path: &Path) -> Result<String, String> {
    let text = fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()));
    text.map(|s| s.trim().to_owned())
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    fs::write(path, text).map_err(|e| format!("write {text} to {}: {e}", path.display()))
}

fn mkdir(path: &Path) -> Result<(), String> {
    fs::create_dir(path).map_err(|e| format!("mkdir {}: {e}", path.display()))
}

fn read_high(path: &Path) -> bool {
    read(path).unwrap_or_else(|e| panic!("{e}")) == "1"
}

impl SimChip {
    fn create(gpio_sim: &Path) -> Result<Self, String> {
        let config = gpio_sim.join(format!("rl-safety-{}", std::process::id()));
        mkdir(&config)?;
        // From here on, dropping `chip` takes down whatever was made.
        let mut chip = Self {
            config,
            lines: PathBuf::new(),
            chip: String::new(),
        };
        let bank = chip.config.join("bank0");
        mkdir(&bank)?;
        write(&bank.join("num_lines"), "8")?;
        write(&chip.config.join("live"), "1")?;
        chip.chip = read(&bank.join("chip_name"))?;
        let dev = read(&chip.config.join("dev_name"))?;
        chip.lines = format!("/sys/devices/platform/{dev}/{}", chip.chip).into();
        // devtmpfs (or udev) makes the device node; give it a moment.
        let (node, since) = (Path::new("/dev").join(&chip.chip), Instant::now());
        while !node.exists() {
            if since.elapsed() > Duration::from_secs(2) {
                return Err(format!("no {} (no devtmpfs or udev?)", node.display()));
            }
            thread::sleep(Duration::from_millis(10));
        }
        Ok(chip)
    }

    fn line(&self, offset: u32) -> GpioLine {
        format!("{}:{offset}", self.chip).parse().expect("line")
    }

    fn sim(&self, offset: u32, file: &str) -> PathBuf {
        self.lines.join(format!("sim_gpio{offset}")).join(file)
    }

    /// Drives the e-stop input: `true` pulls it up (high: closed), `false` down (open).
    fn estop(&self, closed: bool) {
        let pull = if closed { "pull-up" } else { "pull-down" };
        write(&self.sim(ESTOP, "pull"), pull).unwrap_or_else(|e| panic!("{e}"));
    }

    /// The level an output line was set to.
    fn is_high(&self, offset: u32) -> bool {
        read_high(&self.sim(offset, "value"))
    }

    /// A chain on the e-stop, watchdog and brake lines, stop category 0 (the CLI's
    /// `--estop C:0 --watchdog C:1 --brake C:2`).
    fn chain(&self) -> SafetyHandle {
        let chain = GpioChain {
            watchdog: Some(self.line(WATCHDOG)),
            brake: Some(self.line(BRAKE)),
            ..GpioChain::new(self.line(ESTOP))
        };
        chain.open().unwrap_or_else(|e| panic!("{e}"))
    }

    /// `f`'s result, the watchdog's changes of level seen meanwhile (read every [`SAMPLE`]),
    /// and whether the brake line was seen high.
    fn sampled<T>(&self, f: impl FnOnce() -> T) -> (T, u64, bool) {
        let (watchdog, brake) = (self.sim(WATCHDOG, "value"), self.sim(BRAKE, "value"));
        let done = AtomicBool::new(false);
        thread::scope(|s| {
            let sampler = s.spawn(|| {
                let (mut level, mut changes, mut brake_high) = (read_high(&watchdog), 0, false);
                while !done.load(Ordering::Acquire) {
                    let now = read_high(&watchdog);
                    changes += u64::from(now != level);
                    level = now;
                    brake_high |= read_high(&brake);
                    thread::sleep(SAMPLE);
                }
                (changes, brake_high)
            });
            // A panic in `f` must still stop the sampler, or the scope would wait for it.
            let out = panic::catch_unwind(AssertUnwindSafe(f));
            done.store(true, Ordering::Release);
            let (changes, brake_high) = sampler.join().expect("sampler");
            (
                out.unwrap_or_else(|p| panic::resume_unwind(p)),
                changes,
                brake_high,
            )
        })
    }
}

impl Drop for SimChip {
    fn drop(&mut self) {
        let _ = fs::write(self.config.join("live"), "0");
        let _ = fs::remove_dir(self.config.join("bank0"));
        let _ = fs::remove_dir(&self.config);
    }
}

/// Root, configfs mounted and gpio-sim loaded (mounting and loading them if need be), and a
/// chip made: the chip, or why not.
fn gpio_sim() -> Result<SimChip, String> {
    // /proc/self belongs to the process's effective user.
    let uid = fs::metadata("/proc/self").map_or(u32::MAX, |m| m.uid());
    if uid != 0 {
        return Err(format!("not root (effective uid {uid})"));
    }
    let modprobe = || match Command::new("modprobe").arg("gpio-sim").output() {
        Err(e) => format!("cannot run modprobe: {e}"),
        Ok(o) if o.status.success() => "modprobe gpio-sim succeeded".to_owned(),
        Ok(o) => String::from_utf8_lossy(&o.stderr).trim().to_owned(),
    };
    let configfs = Path::new("/sys/kernel/config");
    let gpio_sim = configfs.join("gpio-sim");
    if !configfs.is_dir() {
        let tried = modprobe(); // gpio-sim depends on configfs, which makes the directory
        if !configfs.is_dir() {
            return Err(format!("no /sys/kernel/config: no configfs ({tried})"));
        }
    }
    if fs::read_dir(configfs).is_ok_and(|mut d| d.next().is_none()) {
        let mount = Command::new("mount")
            .args(["-t", "configfs", "none", "/sys/kernel/config"])
            .status();
        if !mount.as_ref().is_ok_and(std::process::ExitStatus::success) {
            return Err(format!("configfs not mounted, mount: {mount:?}"));
        }
    }
    if !gpio_sim.is_dir() {
        let tried = modprobe();
        if !gpio_sim.is_dir() {
            return Err(format!("gpio-sim is not loadable ({tried})"));
        }
    }
    SimChip::create(&gpio_sim).map_err(|e| format!("gpio-sim is there but made no chip: {e}"))
}

/// A tour on a fresh fake H7 with `handle`'s chain.
fn start(
    handle: &SafetyHandle,
    duration: Duration,
) -> (FakeH7, Result<ControlRun<MitsubishiH7, 16, 8>, RunError>) {
    let (fake, robot) = common::realtime_fake_h7();
    let options = RunOptions {
        lock_memory: false,
        priority: 60,
        safety: Some(handle.clone()),
        ..RunOptions::default()
    };
    let run = ControlRun::start(robot, rv6sl().expect("model"), options.duration(duration));
    (fake, run)
}

/// A run's chain, report, fake, watchdog changes seen, and whether the brake was seen high.
type Outcome = (SafetyHandle, RunReport, FakeH7, u64, bool);

/// A tour on a fresh chain with the e-stop closed, for 2 s; or, with `open_after`, until the
/// e-stop opens that long after the loop started. Runs again (at most [`late::ATTEMPTS`])
/// while the machine was late.
fn run(chip: &SimChip, open_after: Option<Duration>) -> Option<Outcome> {
    let (what, duration) = match open_after {
        None => ("a closed chain", Duration::from_secs(2)),
        Some(_) => ("an e-stop while moving", Duration::from_secs(20)),
    };
    let attempt = || {
        chip.estop(true);
        let handle = chip.chain();
        let ((report, fake), changes, brake_high) = chip.sampled(|| {
            let (fake, run) = start(&handle, duration);
            let mut run = run.unwrap_or_else(|e| panic!("the run did not start: {e}"));
            let started = Instant::now();
            while run.poll(Duration::from_millis(5)).is_some() {
                if open_after.is_some_and(|t| started.elapsed() >= t) {
                    chip.estop(false);
                }
                assert!(started.elapsed().as_secs() < 30, "the run did not end");
            }
            (run.join(), fake)
        });
        (handle, report, fake, changes, brake_high)
    };
    let was_late = |o: &Outcome| late::any_shortfall(&o.1);
    late::while_late(&format!("{NAME}: {what}"), attempt, was_late)
}

/// The watchdog line holds still (for 100 ms) at its inactive level, low; the brake is low.
fn assert_outputs_dropped(chip: &SimChip) {
    for _ in 0..100 {
        assert!(!chip.is_high(WATCHDOG), "the watchdog holds low");
        assert!(!chip.is_high(BRAKE), "the brake line is low");
        thread::sleep(Duration::from_millis(1));
    }
}

fn closed_chain_runs(chip: &SimChip) {
    let Some((_handle, report, fake, changes, brake_high)) = run(chip, None) else {
        return;
    };
    assert_eq!(report.exit_code(), 0, "{report}");
    let finished = matches!(report.end, Some(RunEnd::CycleLimit | RunEnd::Completed));
    assert!(finished, "{report}");
    assert!(fake.status().moves > 0, "the arm moved: {report}");
    let safety = report.safety.expect("the chain's report");
    assert_eq!(safety.counters.stops, 0, "{report}");
    // The chain writes the watchdog's other level once per cycle: `cycles` changes over a run
    // of cycles × period. Each level lasts a period, which the sampler reads ten times or more,
    // so it sees every change unless kept off its CPU a whole period; half is the bound a busy
    // machine still meets, and far above what a stuck line (0) or one per run would give.
    let (cycles, period) = (safety.counters.cycles, report.period_s);
    assert!(period >= 10.0 * SAMPLE.as_secs_f64(), "period {period} s");
    assert!(
        changes >= cycles / 2,
        "{changes} watchdog changes seen in {cycles} cycles over {:.2} s",
        cycles as f64 * period
    );
    assert!(brake_high, "the brake line was high while the arm moved");
    assert_outputs_dropped(chip);
}

fn open_chain_refuses(chip: &SimChip) {
    chip.estop(false);
    let handle = chip.chain();
    let ((fake, run), _, brake_high) = chip.sampled(|| start(&handle, Duration::from_secs(2)));
    let e = run.err().expect("refused");
    let text = e.to_string();
    assert!(matches!(e, RunError::Safety(_)), "{text}");
    let says = |s: &str| assert!(text.contains(s), "{text}");
    says(&format!("e-stop input {} reads open", chip.line(ESTOP)));
    says("nothing was started");
    assert_eq!(fake.status().moves, 0, "nothing moved");
    assert!(!brake_high, "the brake line never rose");
    assert_outputs_dropped(chip);
    assert_ne!(handle.with(|c| c.state()), Some(ChainState::Ready));
}

fn estop_during_run_stops(chip: &SimChip) {
    let after = Some(Duration::from_millis(800));
    let Some((handle, report, fake, _, brake_high)) = run(chip, after) else {
        return;
    };
    let line = chip.line(ESTOP).to_string();
    match report.end {
        Some(RunEnd::Fault(Fault::Safety {
            category: StopCategory::Zero,
            reason: StopReason::EStopOpen { pin },
        })) => assert_eq!(pin.name.as_str(), line),
        other => panic!("the run ended by {other:?}:\n{report}"),
    }
    assert_ne!(report.exit_code(), 0);
    assert!(report.shutdown.stopped, "{report}");
    let failure = report.failure.as_deref().unwrap_or_default();
    let says = |s: &str| assert!(failure.contains(s), "{failure}");
    says(&format!("e-stop input {line} reads open"));
    says("stop category 0");
    let json = report.to_json();
    assert_eq!(json["safety"]["stops"], 1, "{json}");
    assert_eq!(json["safety"]["stop_category"], 0, "{json}");
    assert!(brake_high, "the brake line was high while the arm moved");
    assert_outputs_dropped(chip);
    // Closing the e-stop again restarts nothing: the chain stays latched.
    chip.estop(true);
    thread::sleep(Duration::from_millis(100));
    let moves = fake.status().moves;
    thread::sleep(Duration::from_millis(200));
    assert_eq!(fake.status().moves, moves, "nothing moves after closing");
    assert_outputs_dropped(chip);
    assert_ne!(handle.with(|c| c.state()), Some(ChainState::Ready));
}

#[test]
fn the_chain_on_gpio_sim_lines_allows_refuses_and_stops_runs() {
    let chip = match gpio_sim() {
        Ok(chip) => chip,
        Err(why) => {
            println!("SKIPPED: {NAME}: {why}");
            return;
        }
    };
    closed_chain_runs(&chip);
    open_chain_refuses(&chip);
    estop_during_run_stops(&chip);
}
