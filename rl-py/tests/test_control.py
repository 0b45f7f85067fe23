"""A supervised controller run from Python against the fake Mitsubishi H7 (in-process, on
loopback, pacing its replies at the H7's 7.11 ms): the report is the tool's, the telemetry
arrays hold one row per cycle, a stop request brings the arm to rest, and a run that cannot
start raises without moving anything."""

import threading
import time

import numpy as np
import pytest

import rlrs
from conftest import while_late


def test_fake_h7_run_reports_and_records_every_cycle():
    def attempt():
        run = rlrs.ControlRun("fake-h7", duration=1.0)
        assert run.joints == [f"joint{i}" for i in range(6)]
        assert run.plan_duration > 1.0
        while (p := run.poll(0.2)) is not None:
            assert set(p) >= {"cycle", "time", "error_max", "faulted"}
        return run, run.join()

    run, report = while_late("a fake H7 run", attempt, lambda o: o[1])
    assert report["exit_code"] == 0, report["text"]
    assert "result: ok" in report["text"] and "fake H7 saw 1 end packet, servo off" in report["text"]
    assert report["fake_servo_on"] is False and report["fake_end_packets"] == 1
    tel = run.telemetry()
    n = len(tel["cycle"])
    # One record per cycle, none dropped; 1 s at 7.11 ms plus coming to rest.
    assert n == report["cycles"] > 100, (n, report["cycles"])
    assert report["telemetry_dropped"] == 0
    assert tel["commanded"].shape == tel["measured"].shape == tel["feed_forward"].shape == (n, 6)
    assert np.all(np.diff(tel["cycle"]) == 1) and np.all(np.diff(tel["t"]) >= 0)
    # The report's tracking error is the telemetry's largest |commanded - measured|.
    err = np.abs(tel["commanded"] - tel["measured"]).max(axis=0)
    tracking = report["tracking_error_rad"]
    assert np.allclose(err, tracking["max_per_joint"], rtol=1e-9, atol=1e-12), (err, tracking)
    assert np.all(err <= np.array(tracking["bound_per_joint"]))
    assert run.join() == report


def test_stop_brings_the_arm_to_rest():
    def attempt():
        run = rlrs.ControlRun("fake-h7")
        # A run that already ended (a timing fault) is judged by while_late, then checked.
        if run.poll(0.3) is not None:
            run.stop()
        return run, run.wait()

    run, report = while_late("a stopped run", attempt, lambda o: o[1])
    # `rl run`'s status for a run stopped on request: 130, the device stopped safely.
    assert report["exit_code"] == 130 and report["interrupted"], report["text"]
    assert "end: stopped on request, brought to rest" in report["text"]
    assert report["device_stopped"] and not report["fake_servo_on"]
    assert report["trajectory_time_s"] < run.plan_duration


def test_another_thread_may_stop_and_join_while_one_polls():
    """Waiting (poll) holds the run with the GIL released; stop and join from another thread
    neither deadlock nor lose the report."""
    run = rlrs.ControlRun("fake-h7")
    seen = []

    def watch():
        while (p := run.poll(1.0)) is not None:
            seen.append(p)

    watcher = threading.Thread(target=watch)
    watcher.start()
    time.sleep(0.5)
    run.stop()
    report = run.join()
    watcher.join(timeout=30)
    assert not watcher.is_alive()
    assert seen and report["exit_code"] == 130, report["text"]
    assert len(run.telemetry()["cycle"]) == report["cycles"]


def test_runs_that_cannot_start_raise():
    with pytest.raises(ValueError, match="unknown device"):
        rlrs.ControlRun("tcp://1.2.3.4")
    with pytest.raises(ValueError, match="rate"):
        rlrs.ControlRun("fake-h7", rate=500.0)
    # A waypoint beyond joint 0's limit: the plan is refused before anything moves.
    with pytest.raises(rlrs.RunError, match="refusing to move"):
        rlrs.ControlRun("fake-h7", waypoints=[[10.0, 0, 0, 0, 0, 0]], duration=0.5)


def test_a_run_follows_targets_sent_from_python():
    """follow=True: the arm holds where it stands, goes to each target sent with send_position
    (the controller's TargetFollower, rl-core's online trajectory generator in the loop) and
    ends at rest at the last; the joints' limits refuse a target naming the joint; the report
    counts the targets."""
    def attempt():
        run = rlrs.ControlRun("fake-h7", follow=True, duration=4.0, input_timeout=10.0)
        assert run.follows
        assert run.poll(0.3) is not None
        start = run.telemetry()["commanded"][-1].copy()
        with pytest.raises(ValueError, match="joint0"):
            run.send_position(start + np.array([100.0, 0, 0, 0, 0, 0]))
        with pytest.raises(ValueError, match="shape"):
            run.send_position(start[:3])
        first = start + np.array([0.1, -0.05, 0.05, 0.0, 0.1, -0.1])
        run.send_position(first)
        time.sleep(1.0)
        last = start + np.array([-0.05, 0.05, 0.0, 0.1, 0.0, 0.05])
        try:
            run.send_position(last)
        except ValueError as e:
            # The run ended before it (a timing failure, judged below).
            assert "over" in str(e), e
        return run, run.wait(), start, first, last

    run, report, start, first, last = while_late("a followed run", attempt, lambda o: o[1])
    assert report["exit_code"] == 0, report["text"]
    assert report["trajectory_source"] == "follow", report["text"]
    law = report["law"]
    assert law["targets"] == 2 and law["unreachable"] == 0, law
    tel = run.telemetry()
    commanded = tel["commanded"]
    # It reached the first target (at rest there before the second came) and ended at the last.
    assert np.min(np.abs(commanded - first).max(axis=1)) < 1e-7
    assert np.abs(commanded[-1] - last).max() < 1e-7, (commanded[-1], last)
    # Nothing moved before the first target: the arm held where it stood.
    assert np.abs(commanded[0] - start).max() < 1e-12
    with pytest.raises(rlrs.RunError, match="ended"):
        run.send_position(last)


def test_targets_need_a_following_run():
    run = rlrs.ControlRun("fake-h7", duration=0.5)
    with pytest.raises(ValueError, match="follow=True"):
        run.send_velocity(np.zeros(6))
    run.wait()
    with pytest.raises(ValueError, match="input_timeout"):
        rlrs.ControlRun("fake-h7", input_timeout=1.0)
