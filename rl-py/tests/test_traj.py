"""Jerk-limited profiles against Ruckig (PyPI `ruckig`, the C++ library's binding): on random
rest-to-rest jobs the durations agree to 1e-9 relative, and the slowest axis — whose
time-optimal profile is unique — follows Ruckig's positions; array evaluation equals scalar
evaluation; the limits hold. The online trajectory generator (rlrs.otg, rlrs.Otg) against
Ruckig from moving starts, to moving targets, with asymmetric limits and the velocity
interface; its refusals, position limits, waypoints, and the per-cycle generator."""

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


def ruckig_job(cur, tgt, vmax, amax, jmax, vmin=None, amin=None, sync="time"):
    """Ruckig's trajectory for a job: cur and tgt are (p, v, a) per axis."""
    n = len(cur[0])
    otg = ruckig.Ruckig(n)
    inp = ruckig.InputParameter(n)
    inp.current_position, inp.current_velocity, inp.current_acceleration = (list(x) for x in cur)
    inp.target_position, inp.target_velocity, inp.target_acceleration = (list(x) for x in tgt)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(vmax), list(amax), list(jmax)
    if vmin is not None:
        inp.min_velocity = list(vmin)
    if amin is not None:
        inp.min_acceleration = list(amin)
    inp.synchronization = {"time": ruckig.Synchronization.Time,
                           "phase": ruckig.Synchronization.Phase,
                           "none": ruckig.Synchronization.No}[sync]
    traj = ruckig.Trajectory(n)
    result = otg.calculate(inp, traj)
    return traj if result == ruckig.Result.Working else None


def random_job(rng, n, moving_target):
    vmax = rng.uniform(0.5, 3.0, n)
    amax = rng.uniform(1.0, 10.0, n)
    jmax = rng.uniform(5.0, 100.0, n)
    cur = (rng.uniform(-3, 3, n), rng.uniform(-1, 1, n) * vmax * 0.9, rng.uniform(-1, 1, n) * amax * 0.5)
    if moving_target:
        tgt = (rng.uniform(-3, 3, n), rng.uniform(-1, 1, n) * vmax * 0.3, np.zeros(n))
    else:
        tgt = (rng.uniform(-3, 3, n), np.zeros(n), np.zeros(n))
    return cur, tgt, vmax, amax, jmax


@pytest.mark.parametrize("moving_target", [False, True], ids=["target_at_rest", "moving_target"])
def test_otg_durations_equal_ruckig_from_moving_starts(moving_target):
    """rlrs.otg from a moving start (and to a moving target) on 300 random jobs of 1 to 12
    axes: the same duration as Ruckig's to 1e-9 relative wherever Ruckig finds one, the samples
    within every limit, and the trajectory ending at the target."""
    rng = np.random.default_rng(26 + moving_target)
    compared = 0
    for job in range(300):
        n = int(rng.integers(1, 13))
        cur, tgt, vmax, amax, jmax = random_job(rng, n, moving_target)
        theirs = ruckig_job(cur, tgt, vmax, amax, jmax)
        if theirs is None:
            continue
        compared += 1
        ours = rlrs.otg(cur[0], tgt[0], vmax, amax, jmax, current_velocity=cur[1],
                        current_acceleration=cur[2], target_velocity=tgt[1],
                        target_acceleration=tgt[2])
        assert ours.axes == n
        close(ours.duration, theirs.duration, 1e-9, f"job {job}: duration")
        t = np.linspace(0.0, ours.duration, 400)
        p, v, a, j = ours.sample(t)
        assert p.shape == (400, n)
        # A start beyond a limit, or one whose acceleration carries the velocity past it while
        # the jerk takes that acceleration away (v0 + a0|a0|/2j), brakes back within it.
        v_reach = np.abs(cur[1] + cur[2] * np.abs(cur[2]) / (2 * jmax))
        v_bound = np.maximum(vmax, np.maximum(np.abs(cur[1]), v_reach))
        assert np.all(np.abs(v) <= v_bound * (1 + 1e-9) + 1e-12), f"job {job}"
        assert np.all(np.abs(a) <= np.maximum(amax, np.abs(cur[2])) * (1 + 1e-9) + 1e-12), f"job {job}"
        assert np.all(np.abs(j) <= jmax * (1 + 1e-9)), f"job {job}"
        end = ours.sample(ours.duration)
        for k, (x, want) in enumerate(zip(end[:3], tgt)):
            close(x, want, 1e-8, f"job {job}: end state, derivative {k}")
    assert compared == 300, f"Ruckig solved only {compared} of 300 jobs"


def test_otg_asymmetric_limits_and_velocity_interface_equal_ruckig():
    rng = np.random.default_rng(9)
    for job in range(100):
        n = int(rng.integers(1, 8))
        cur, tgt, vmax, amax, jmax = random_job(rng, n, False)
        vmin, amin = -rng.uniform(0.5, 3.0, n), -rng.uniform(1.0, 10.0, n)
        cur = (cur[0], np.clip(cur[1], vmin * 0.9, vmax * 0.9), np.clip(cur[2], amin * 0.5, amax * 0.5))
        theirs = ruckig_job(cur, tgt, vmax, amax, jmax, vmin, amin)
        assert theirs is not None, f"job {job}: Ruckig found no trajectory"
        ours = rlrs.otg(cur[0], tgt[0], vmax, amax, jmax, current_velocity=cur[1],
                        current_acceleration=cur[2], min_velocity=vmin, min_acceleration=amin)
        close(ours.duration, theirs.duration, 1e-9, f"job {job}: asymmetric duration")
    # The velocity interface: reach a velocity, the position free.
    ours = rlrs.otg([0.0, 1.0], [0.0, 0.0], 2.0, 4.0, 20.0, target_velocity=[1.0, -0.5],
                    interface="velocity")
    n = 2
    otg = ruckig.Ruckig(n)
    inp = ruckig.InputParameter(n)
    inp.control_interface = ruckig.ControlInterface.Velocity
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0, 1.0], [0.0] * 2, [0.0] * 2
    inp.target_velocity, inp.target_acceleration = [1.0, -0.5], [0.0] * 2
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [2.0] * 2, [4.0] * 2, [20.0] * 2
    traj = ruckig.Trajectory(n)
    assert otg.calculate(inp, traj) == ruckig.Result.Working
    close(ours.duration, traj.duration, 1e-9, "velocity interface duration")
    close(ours.sample(ours.duration)[1], [1.0, -0.5], 1e-9, "velocity reached")


def test_otg_refuses_what_cannot_be_reached_and_keeps_position_limits():
    # A target beyond the position limits: a TrajectoryError naming the axis.
    with pytest.raises(rlrs.TrajectoryError, match="axis 1"):
        rlrs.otg([0.0, 0.0], [0.5, 2.0], 1.0, 2.0, 10.0, min_position=-1.0, max_position=1.0)
    # Moving fast toward a limit: the trajectory stays inside it.
    ours = rlrs.otg([0.0], [0.8], 2.0, 2.0, 10.0, current_velocity=[1.5], max_position=1.0,
                    min_position=-1.0)
    p = ours(np.linspace(0.0, ours.duration, 2001))
    assert p.max() <= 1.0 + 1e-12 and p.min() >= -1.0 - 1e-12
    with pytest.raises(ValueError, match="axes"):
        rlrs.otg(np.zeros(17), np.zeros(17), 1.0, 1.0, 1.0)
    # Waypoints: passes them, sections add up.
    w = rlrs.otg([0.0, 0.0], [1.0, 0.0], 1.0, 2.0, 10.0, waypoints=[[0.5, 0.5]])
    assert len(w.sections) == 2 and w.min_durations is None
    close(w.sections.sum(), w.duration, 1e-12, "sections")
    close(w(w.sections[0]), [0.5, 0.5], 1e-8, "the waypoint")


def test_the_online_generator_follows_the_offline_trajectory_and_brakes():
    """rlrs.Otg: one cycle per call along what rlrs.otg calculates for the same job, bit for bit
    at each cycle's time; a new goal mid-way continues from the state commanded last
    (continuous); brake comes to rest; an unreachable goal leaves the motion under way."""
    cycle = 0.001
    limits = dict(max_velocity=[1.0, 2.0, 0.5], max_acceleration=3.0, max_jerk=30.0)
    gen = rlrs.Otg(cycle, [0.0, 0.0, 0.0])
    offline = rlrs.otg([0.0, 0.0, 0.0], [0.4, -0.3, 0.2], **limits)
    t = 0.0
    for k in range(1, 201):
        p, v, a, finished = gen.update([0.4, -0.3, 0.2], **limits)
        t += cycle  # the generator's clock: one cycle added per call
        pw, vw, aw, _ = offline.sample(t)
        assert np.array_equal(p, pw) and np.array_equal(v, vw) and np.array_equal(a, aw), k
        assert not finished
    close(gen.duration, offline.duration, 0.0, "the same trajectory")
    before = gen.state
    p, v, a, _ = gen.update([-0.2, 0.1, 0.0], **limits)
    assert np.all(np.abs(p - before[0]) <= np.abs(before[1]) * cycle + 3.0 * cycle**2 + 1e-12)
    with pytest.raises(rlrs.TrajectoryError):
        gen.update([5.0, 0.0, 0.0], **limits, max_position=1.0)
    p2, v2, _, _ = gen.step()
    assert np.all(np.abs(p2 - p) <= 2.0 * cycle + 1e-12)
    gen.brake(**limits)
    for _ in range(5000):
        p, v, a, finished = gen.step()
        if finished:
            break
    assert finished
    close(v, np.zeros(3), 1e-9, "at rest")
    close(a, np.zeros(3), 1e-9, "at rest")
