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
