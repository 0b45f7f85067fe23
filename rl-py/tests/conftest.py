"""Shared fixtures of the rlrs pytest suite (run by scripts/test after the wheel is built and
installed into target/py-venv; see rl-py/README.md)."""

import os
import subprocess

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "tests", "data")


def robot_data_dir():
    """example-robot-data's directory (scripts/robot-data, which may download it once), or
    None with the reason."""
    env = os.environ.get("RL_ROBOT_DATA")
    if env:
        return (env, None) if os.path.isdir(os.path.join(env, "robots")) else (None, f"RL_ROBOT_DATA={env} has no robots/")
    try:
        out = subprocess.run([os.path.join(ROOT, "scripts", "robot-data")], check=True,
                             capture_output=True, text=True, timeout=900)
    except (subprocess.SubprocessError, OSError) as e:
        return None, f"scripts/robot-data failed: {e}"
    return out.stdout.strip().splitlines()[-1], None


@pytest.fixture(scope="session")
def robot_data():
    d, why = robot_data_dir()
    if d is None:
        pytest.skip(f"SKIPPED: example-robot-data unavailable ({why})")
    return d


def close(ours, theirs, tol, what):
    """|ours - theirs| <= tol * max(1, |ours|, |theirs|) elementwise (rl-core's assert_close)."""
    ours = np.asarray(ours, dtype=float)
    theirs = np.asarray(theirs, dtype=float)
    assert ours.shape == theirs.shape, f"{what}: shape {ours.shape} vs {theirs.shape}"
    scale = np.maximum(1.0, np.maximum(np.abs(ours), np.abs(theirs)))
    err = np.abs(ours - theirs) / scale
    worst = np.unravel_index(np.argmax(err), err.shape) if err.size else ()
    assert err.size == 0 or err.max() <= tol, (
        f"{what}: relative error {err.max():.3e} > {tol:g} at {worst}: "
        f"{ours[worst]} vs {theirs[worst]}")


def failed_late(report):
    """The run failed on timing while the loop or the device's fake measured itself late: the
    report's own judgement (`likely_cause` and `lateness.culprit`, as the Rust tests' rule in
    tests/late/mod.rs). On a shared VM the host holds a real-time thread for milliseconds."""
    culprit = (report.get("lateness") or {}).get("culprit")
    return (report.get("exit_code") != 0 and report.get("likely_cause") is not None
            and culprit in ("loop", "peer", "loop_and_peer"))


def while_late(name, attempt, report_of=lambda r: r):
    """Runs `attempt` (a whole run) again while it failed late (`failed_late`), at most three
    times; returns the first other outcome to be checked in full, or skips with the reasons."""
    reasons = []
    for n in range(3):
        outcome = attempt()
        report = report_of(outcome)
        if not failed_late(report):
            return outcome
        print(f"{name}: attempt {n + 1}: the machine was late: {report['likely_cause']}")
        reasons.append(report["likely_cause"])
    pytest.skip(f"SKIPPED: {name}: the machine was late in three runs: {reasons}")
