"""Jerk-limited profiles against Ruckig (PyPI `ruckig`, the C++ library's binding): on random
rest-to-rest jobs the durations agree to 1e-9 relative, and the slowest axis — whose
time-optimal profile is unique — follows Ruckig's positions; array evaluation equals scalar
evaluation; the limits hold."""

import numpy as np
import pytest

import rlrs
from conftest import close

ruckig = pytest.importorskip("ruckig", reason="SKIPPED: PyPI ruckig is not installed")


def ruckig_trajectory(start, goal, v, a, j):
    n = len(start)
    otg = ruckig.Ruckig(n)
    inp = ruckig.InputParameter(n)
    inp.current_position = list(start)
    inp.current_velocity = [0.0] * n
    inp.current_acceleration = [0.0] * n
    inp.target_position = list(goal)
    inp.target_velocity = [0.0] * n
    inp.target_acceleration = [0.0] * n
    inp.max_velocity = list(v)
    inp.max_acceleration = list(a)
    inp.max_jerk = list(j)
    traj = ruckig.Trajectory(n)
    result = otg.calculate(inp, traj)
    assert result == ruckig.Result.Working, result
    return traj


def test_durations_and_slowest_axis_equal_ruckig():
    rng = np.random.default_rng(32)
    for job in range(200):
        n = int(rng.integers(1, 8))
        start = rng.uniform(-3, 3, n)
        goal = rng.uniform(-3, 3, n)
        v = rng.uniform(0.2, 3.0, n)
        a = rng.uniform(0.5, 10.0, n)
        j = rng.uniform(1.0, 100.0, n)
        ours = rlrs.JerkLimited(start, goal, v, a, j)
        theirs = ruckig_trajectory(start, goal, v, a, j)
        close(ours.duration, theirs.duration, 1e-9, f"job {job}: duration")
        slowest = int(np.argmax(ours.axis_durations))
        times = np.linspace(0.0, ours.duration, 23)
        p = ours(times)
        for t, row in zip(times, p):
            pos, _, _ = theirs.at_time(t)
            close(row[slowest], pos[slowest], 1e-9, f"job {job}: position of axis {slowest} at {t}")


def test_arrays_of_times_equal_single_times_and_keep_the_limits():
    start, goal = np.array([0.0, 0.5, -1.0]), np.array([1.0, -0.5, 2.0])
    v, a, j = np.array([1.0, 2.0, 0.5]), 2.0, 10.0
    p = rlrs.JerkLimited(start, goal, v, a, j)
    assert p.axes == 3
    t = np.linspace(-0.5, p.duration + 0.5, 1001)
    pos, vel, acc, jerk = p.sample(t)
    assert pos.shape == vel.shape == acc.shape == jerk.shape == (1001, 3)
    for k in (0, 1, 500, 999, 1000):
        one = p.sample(float(t[k]))
        for x, y in zip(one, (pos[k], vel[k], acc[k], jerk[k])):
            assert np.array_equal(x, y)
    assert np.array_equal(pos[0], start) and np.allclose(pos[-1], goal, atol=1e-12)
    assert np.all(np.abs(vel) <= v * (1 + 1e-9))
    assert np.all(np.abs(acc) <= 2.0 * (1 + 1e-9))
    assert np.all(np.abs(jerk) <= 10.0 * (1 + 1e-9))
    ends = p.phase_ends(0)
    assert ends.shape == (7,) and np.all(np.diff(ends) >= 0) and ends[-1] == p.duration
    # 64 axes is the largest build; 65 is refused with a message saying where to change it.
    assert rlrs.JerkLimited(np.zeros(64), np.ones(64), 1.0, 1.0, 1.0).axes == 64
    with pytest.raises(ValueError, match="up to 64 axes"):
        rlrs.JerkLimited(np.zeros(65), np.ones(65), 1.0, 1.0, 1.0)


def test_bad_limits_are_refused():
    with pytest.raises(rlrs.TrajectoryError):
        rlrs.JerkLimited([0.0], [1.0], -1.0, 1.0, 1.0)
    with pytest.raises(rlrs.TrajectoryError):
        rlrs.JerkLimited([0.0], [np.nan], 1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="max_jerk"):
        rlrs.JerkLimited([0.0, 1.0], [1.0, 2.0], 1.0, 1.0, [1.0, 2.0, 3.0])
