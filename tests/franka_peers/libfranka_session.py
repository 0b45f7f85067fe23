"""libfranka 0.21.2 (through franky-control 2.0.0) against a Franka robot on the wire.

Usage: python libfranka_session.py HOST [--torque-seconds S]

Runs, against the robot at HOST (port 1337, libfranka's fixed port):
  1. connect and read the state (mode, joints, torques, the server's version);
  2. a joint position motion (franky's JointMotion: ruckig, within the robot's limits);
  3. a torque-controlled motion for S seconds (franky's SimpleTorqueMotion: zero torques,
     then 0.5 N·m on joint 1, ramped by franky's 1 N·m-per-ms limit), ended by stop()
     (StopMove: the Move is answered "preempted");
  4. an error and its recovery: a torque step beyond 1 N·m per ms (SimpleTorqueMotion with
     the rate limit lifted) must end in a ControlException naming
     controller_torque_discontinuity; recover_from_errors() clears it, and a joint motion
     runs again.
Prints one JSON object with what it saw; exits 0 when every step behaved as the robot does.
"""

import argparse
import json
import sys
import time

import numpy as np
import franky


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("host")
    parser.add_argument("--torque-seconds", type=float, default=2.0)
    args = parser.parse_args()

    out = {"steps": {}}
    ok = True

    def step(name, passed, **seen):
        nonlocal ok
        out["steps"][name] = {"ok": bool(passed), **seen}
        ok = ok and bool(passed)

    t0 = time.time()
    robot = franky.Robot(args.host, realtime_config=franky.RealtimeConfig.Ignore)
    robot.relative_dynamics_factor = 0.2
    state = robot.state
    q0 = np.array(state.q)
    step(
        "connect",
        str(state.robot_mode) == "RobotMode.Idle" and np.all(np.isfinite(q0)),
        robot_mode=str(state.robot_mode),
        q=[round(x, 4) for x in q0],
        tau_J=[round(x, 3) for x in state.tau_J],
        seconds=round(time.time() - t0, 3),
    )

    # 2. A joint motion: joint 4 by +0.2 rad and back.
    t = time.time()
    target = q0.copy()
    target[3] += 0.2
    error = None
    try:
        robot.move(franky.JointMotion(target.tolist()))
    except Exception as e:  # noqa: BLE001 - reported, not hidden
        error = str(e)
    q1 = np.array(robot.state.q)
    step(
        "joint_motion",
        # The robot's own controller tracks: a simulator's may stop short of the target.
        error is None and q1[3] - q0[3] > 0.15,
        error=error,
        reached=round(float(q1[3]), 5),
        target=round(float(target[3]), 5),
        seconds=round(time.time() - t, 3),
    )
    robot.move(franky.JointMotion(q0.tolist()))

    # 3. Torque control for a few seconds.
    t = time.time()
    error = None
    motion = franky.SimpleTorqueMotion(initial_torque=np.zeros(7), signal_timeout=None)
    q_before = np.array(robot.state.q)
    try:
        robot.move(motion, asynchronous=True)
        time.sleep(args.torque_seconds / 2)
        tau = np.zeros(7)
        tau[0] = 0.5
        motion.set_torque(tau)
        time.sleep(args.torque_seconds / 2)
        motion.set_torque(np.zeros(7))
        time.sleep(0.05)
        # franky's stop() is StopMove: the robot answers the Move "preempted", which
        # libfranka raises; that is how this motion ends on the robot too.
        robot.stop()
        robot.join_motion(timeout=2.0)
    except Exception as e:  # noqa: BLE001
        error = str(e)
    q_after = np.array(robot.state.q)
    step(
        "torque_motion",
        error is None or "preempted" in error,
        error=error,
        joint1_moved_rad=round(float(q_after[0] - q_before[0]), 5),
        seconds=round(time.time() - t, 3),
    )
    if robot.has_errors:
        robot.recover_from_errors()

    # 4. An error (a torque step) and its recovery.
    t = time.time()
    error = None
    motion = franky.SimpleTorqueMotion(
        initial_torque=np.zeros(7), signal_timeout=None, max_delta_tau=100.0
    )
    try:
        robot.move(motion, asynchronous=True)
        time.sleep(0.1)
        tau = np.zeros(7)
        tau[2] = 5.0
        motion.set_torque(tau)
        robot.join_motion(timeout=2.0)
    except Exception as e:  # noqa: BLE001
        error = str(e)
    has_errors = robot.has_errors
    recovered = robot.recover_from_errors()
    again = None
    try:
        robot.move(franky.JointMotion(q0.tolist()))
    except Exception as e:  # noqa: BLE001
        again = str(e)
    step(
        "error_and_recovery",
        error is not None
        and "controller_torque_discontinuity" in error
        and has_errors
        and recovered
        and not robot.has_errors
        and again is None,
        error=error,
        had_errors=has_errors,
        recovered=recovered,
        motion_after_recovery_error=again,
        seconds=round(time.time() - t, 3),
    )

    out["ok"] = ok
    print(json.dumps(out))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
