//! `rl run`'s safety chain flags: GPIO lines written CHIP:OFFSET, the enable, watchdog, brake
//! and stop category only with an e-stop, and a line that cannot be requested (no such chip)
//! refused with its name before anything starts. (The chain in a run is tested on fake pins in
//! tests/safety_run.rs; this machine's kernel has no gpio-sim for simulated lines.)

mod cli;
use cli::rl;

#[test]
fn safety_flags_are_checked_and_a_missing_chip_starts_nothing() {
    for (args, code, says) in [
        (&["run", "--estop", "gpiochip0"][..], 2, "CHIP:OFFSET"),
        (
            &["run", "--estop", "gpiochip0:x"][..],
            2,
            "not a line number",
        ),
        (&["run", "--watchdog", "gpiochip0:3"][..], 2, "--estop"),
        (&["run", "--brake", "gpiochip0:3"][..], 2, "--estop"),
        (
            &["run", "--estop", "gpiochip0:1", "--stop-category", "2"][..],
            2,
            "give 0",
        ),
        (
            &[
                "run",
                "--estop",
                "gpiochip97:17",
                "--watchdog",
                "gpiochip97:27",
            ][..],
            1,
            "cannot request the e-stop input gpiochip97:17 (line 17 of /dev/gpiochip97)",
        ),
    ] {
        let out = rl(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}: no report: nothing ran");
        assert!(
            !err.contains("rl run: t "),
            "{args:?}: no progress: nothing ran"
        );
    }
}
