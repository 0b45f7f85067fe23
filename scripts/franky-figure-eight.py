#!/usr/bin/env python3
"""franky's own Cartesian motion of rl's figure-eight on franky-sim, measured as rl measures it.

    franky-figure-eight.py run --host IP --mode tracking|waypoints [--size M --period S --duration S]
        Drive the figure-eight with franky (PyPI franky-control, libfranka 0.21) against a
        franky-sim serving on IP; print one JSON object.
    franky-figure-eight.py table NAME=FILE.json ...
        Print the comparison table of franky's runs and rl's `rl run --json` report(s).

The figure-eight is rl's (src/controller/task_space/mod.rs, fn figure_eight): Gerono's
lemniscate y = a sin φ, z = (a/2) sin 2φ (a = size/2) in the world y-z plane through the start
position, at the start orientation, φ̇ ramping from 0 to ω = 2π/T over the first period along
h(x) = x³(10 − 15x + 6x²). The error is rl's: the flange's (link8's) position by forward
kinematics of the measured joints against the figure-eight's point at the same time, max and RMS
over the run from its start, and the flange's angle to its start orientation.

franky's EE frame on franky-sim is the hand's TCP (F_T_EE: 0.1034 m along z, −45° about z). The
figure is a pure translation at constant orientation, so the TCP's figure-eight is the flange's
shifted by a constant: franky is commanded the TCP's, and the error is measured at the flange,
O_T_F = O_T_EE · F_T_EE⁻¹ (franky-sim's O_T_EE is Pinocchio's forward kinematics of the measured
q on fr3_clean.urdf plus that fixed offset, so this is FK of q at link8).

Modes (both franky's own Cartesian motions):
  tracking   CartesianImpedanceTrackingMotion: franky's client-side Cartesian impedance (torque
             control, franky's defaults 500 N/m, 50 N·m/rad, critical damping), its reference
             (pose, twist, acceleration: the same figure-eight rl tracks) set in the motion's
             per-cycle callback for the next cycle, so every 1 ms step sees the exact reference.
  waypoints  CartesianWaypointMotion: Cartesian pose commands (franky-sim's internal
             IK + joint PD stands in for the robot's controller), Ruckig through waypoints sampled
             from the figure-eight every --waypoint-dt (10 ms) with its velocity, each segment
             given that minimum time less franky's one switch cycle. franky offers no Python
             callback-driven pose generator, so the commanded path between waypoints is
             Ruckig's, not the figure-eight (its deviation is reported).
"""
import argparse
import json
import math
import sys
import threading
import time


def figure_eight(size, period, t):
    """Offset (p, v, a) of rl's figure-eight from its start at time t (s), each an [x, y, z]."""
    a = 0.5 * size
    w = 2.0 * math.pi / period
    if t < period:
        x = t / period
        h = x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)
        dh = 30.0 * x * x * (1.0 - x) ** 2 / period
        phi, dphi, ddphi = w * period * x ** 4 * (2.5 - 3.0 * x + x * x), w * h, w * dh
    else:
        phi, dphi, ddphi = w * period * 0.5 + w * (t - period), w, 0.0
    s1, c1 = math.sin(phi), math.cos(phi)
    s2, c2 = math.sin(2 * phi), math.cos(2 * phi)
    p = [0.0, a * s1, 0.5 * a * s2]
    v = [0.0, a * c1 * dphi, a * c2 * dphi]
    acc = [0.0, a * (-s1 * dphi * dphi + c1 * ddphi), a * (-2.0 * s2 * dphi * dphi + c2 * ddphi)]
    return p, v, acc


def run(args):
    import numpy as np
    import franky
    from franky import (Affine, CartesianImpedanceTrackingMotion, CartesianReference,
                        CartesianState, CartesianWaypoint, CartesianWaypointMotion, Duration,
                        RealtimeConfig, RobotPose, RobotVelocity, TorqueStopMotion, Twist,
                        TwistAcceleration)

    robot = franky.Robot(args.host, realtime_config=RealtimeConfig.Ignore)
    robot.recover_from_errors()
    s0 = robot.state
    ee0 = s0.O_T_EE.matrix
    f_t_ee = s0.F_T_EE.matrix
    ee_t_f = np.linalg.inv(f_t_ee)
    flange0 = ee0 @ ee_t_f
    p_ee0, p_f0 = ee0[:3, 3].copy(), flange0[:3, 3].copy()
    r_f0 = flange0[:3, :3].copy()
    quat0 = s0.O_T_EE.quaternion

    rec = {"n": 0, "err_max": 0.0, "err_sq": 0.0, "ori_max": 0.0, "t_last": 0.0,
           "robot_ms_first": None, "robot_ms_last": None, "gaps": 0, "skipped": 0,
           "wall_first": None, "wall_last": None, "done": False, "t_err_max": 0.0,
           "cmd_dev_max": None}
    done = threading.Event()

    def measure(state, t):
        if t > args.duration + 1e-9:
            if not rec["done"]:
                rec["done"] = True
                done.set()
            return
        now = time.perf_counter()
        ms = state.time.to_msec()
        if rec["robot_ms_first"] is None:
            rec["robot_ms_first"], rec["wall_first"] = ms, now
        elif ms - rec["robot_ms_last"] > 1:
            rec["gaps"] += 1
            rec["skipped"] += ms - rec["robot_ms_last"] - 1
        rec["robot_ms_last"], rec["wall_last"] = ms, now
        f = state.O_T_EE.matrix @ ee_t_f
        p, _, _ = figure_eight(args.size, args.period, t)
        e = float(np.linalg.norm(f[:3, 3] - (p_f0 + np.array(p))))
        dr = r_f0.T @ f[:3, :3]
        vee = np.array([dr[2, 1] - dr[1, 2], dr[0, 2] - dr[2, 0], dr[1, 0] - dr[0, 1]])
        ori = math.atan2(0.5 * float(np.linalg.norm(vee)), 0.5 * (np.trace(dr) - 1.0))
        rec["n"] += 1
        rec["err_sq"] += e * e
        if e > rec["err_max"]:
            rec["err_max"], rec["t_err_max"] = e, t
        rec["ori_max"] = max(rec["ori_max"], ori)
        rec["t_last"] = t

    if args.mode == "tracking":
        def reference(t):
            p, v, a = figure_eight(args.size, args.period, t)
            return CartesianReference(
                target=Affine(p_ee0 + np.array(p), quat0),
                target_twist=Twist(np.array(v), np.zeros(3)),
                target_acceleration=TwistAcceleration(np.array(a), np.zeros(3)))

        motion = CartesianImpedanceTrackingMotion(
            translational_stiffness=args.stiffness, rotational_stiffness=args.rot_stiffness)
        motion.set_reference(reference(0.0))

        def callback(state, dt, rel, abs_, signal):
            t = rel.to_sec()
            measure(state, t)
            # The control signal of this step is computed: the next step (1 ms on) uses this.
            motion.set_reference(reference(t + 0.001))

        motion.register_callback(callback)
        described = (f"CartesianImpedanceTrackingMotion({args.stiffness:g} N/m, "
                     f"{args.rot_stiffness:g} N·m/rad, critical damping), reference "
                     "(pose, twist, acceleration) set every cycle from the motion's callback")
    else:
        dt = args.waypoint_dt
        # On past the measured duration (then to rest), so the stop does not bend the figure.
        n = int(round((args.duration + 1.0) / dt))
        waypoints = []
        for k in range(1, n + 1):
            p, v, _ = figure_eight(args.size, args.period, k * dt)
            target = CartesianState(
                RobotPose(Affine(p_ee0 + np.array(p), quat0)),
                RobotVelocity(Twist(np.array(v) if k < n else np.zeros(3), np.zeros(3))))
            # franky spends one cycle on every switch to the next waypoint (without this, 50-ms
            # waypoints fall 1 ms behind each: 0.4 s and 38 mm off after 20 s), so each segment is
            # asked for the spacing less that cycle.
            minimum = Duration(int(round(dt * 1000)) - args.waypoint_slack_ms)
            waypoints.append(CartesianWaypoint(target, minimum_time=minimum))
        motion = CartesianWaypointMotion(waypoints)
        def callback(state, dt_, rel, abs_, signal):
            t = rel.to_sec()
            measure(state, t)
            if t <= args.duration:
                # What franky commanded (Ruckig's path) against the figure-eight, at the EE.
                c = signal.O_T_EE
                p, _, _ = figure_eight(args.size, args.period, t)
                d = math.dist((c[12], c[13], c[14]), p_ee0 + np.array(p))
                rec["cmd_dev_max"] = max(rec["cmd_dev_max"] or 0.0, d)

        motion.register_callback(callback)
        described = (f"CartesianWaypointMotion: {n} waypoints every {dt * 1000:g} ms (pose and "
                     f"velocity of the figure-eight), minimum_time {dt * 1000:g} ms less "
                     f"{args.waypoint_slack_ms} ms each")

    wall0 = time.perf_counter()
    fault = None
    try:
        robot.move(motion, asynchronous=True)
        deadline = wall0 + args.duration * 20 + 60
        while not done.is_set() and time.perf_counter() < deadline:
            if not robot.poll_motion() and not robot.is_in_control:
                break
            done.wait(0.1)
        if args.mode == "tracking" and robot.is_in_control:
            robot.move(TorqueStopMotion(), asynchronous=True)
        robot.join_motion(timeout=30)
    except franky.Exception as e:  # a reflex or a refused motion ends franky's motion
        fault = f"{type(e).__name__}: {e}"
    except Exception as e:
        fault = f"{type(e).__name__}: {e}"

    wall = (rec["wall_last"] or wall0) - (rec["wall_first"] or wall0)
    sim_ms = (rec["robot_ms_last"] or 0) - (rec["robot_ms_first"] or 0)
    out = {
        "who": f"franky {args.mode}",
        "mode": args.mode,
        "motion": described,
        "result": "ok" if fault is None and rec["t_last"] >= args.duration - 0.01 else "failed",
        "fault": fault,
        "reflexes": 1 if fault and ("reflex" in fault.lower() or "Control" in fault) else 0,
        "cycles": rec["n"],
        "covered_s": rec["t_last"],
        "task_error_max_m": rec["err_max"],
        "task_error_at_s": rec["t_err_max"],
        "task_error_rms_m": math.sqrt(rec["err_sq"] / rec["n"]) if rec["n"] else None,
        "orientation_error_max_rad": rec["ori_max"],
        "command_deviation_max_m": rec["cmd_dev_max"],
        "states_skipped": rec["skipped"],
        "gaps": rec["gaps"],
        "states_per_s": rec["n"] / wall if wall > 0 else None,
        "sim_speed": sim_ms / 1000.0 / wall if wall > 0 else None,
        "measured_at": "flange (link8): O_T_EE * inv(F_T_EE) of each cycle's state",
        "F_T_EE_translation": f_t_ee[:3, 3].tolist(),
        "start_flange": p_f0.tolist(),
        "start_q": list(map(float, s0.q)),
    }
    print(json.dumps(out))
    return 0 if out["result"] == "ok" else 1


def table(args):
    rows = []
    for item in args.files:
        name, _, path = item.partition("=")
        try:
            with open(path) as f:
                j = json.loads(f.read().strip().splitlines()[-1])
        except Exception as e:
            rows.append((name, None, f"no report ({e})"))
            continue
        rows.append((name, j, None))

    def mm(x):
        return "—" if x is None else f"{x * 1e3:8.2f}"

    print(f"{'run':<26} {'result':<7} {'max mm':>8} {'RMS mm':>8} {'ori mrad':>8} "
          f"{'reflex':>6}  link")
    for name, j, err in rows:
        if j is None:
            print(f"{name:<26} {err}")
            continue
        if "link" in j:  # rl run's report
            link = j["link"]
            wall = (j.get("cycles") or 0) / 1000.0
            extra = (f"{link['received']} states at {link['received'] / wall:.0f}/s, "
                     f"{link['sent']} commands sent, {link['lost']} lost "
                     f"({100 * link['loss_rate']:.1f} %), {link['late']} late") if wall else str(link)
            reflexes = j.get("reflexes")
        else:
            extra = (f"{j['cycles']} states at {j['states_per_s'] or 0:.0f}/s, sim "
                     f"{j['sim_speed'] or 0:.2f}× real time, {j['states_skipped']} sim steps "
                     f"unseen")
            reflexes = j.get("reflexes")
        ori = j.get("orientation_error_max_rad")
        print(f"{name:<26} {j['result']:<7} {mm(j.get('task_error_max_m'))} "
              f"{mm(j.get('task_error_rms_m'))} {mm(ori)} {reflexes!s:>6}  {extra}")
        if j.get("fault"):
            print(f"{'':<26} fault: {j['fault']}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--host", required=True)
    r.add_argument("--mode", choices=["tracking", "waypoints"], default="tracking")
    r.add_argument("--size", type=float, default=0.1)
    r.add_argument("--period", type=float, default=4.0)
    r.add_argument("--duration", type=float, default=20.0)
    r.add_argument("--stiffness", type=float, default=500.0, help="tracking: N/m (franky's default)")
    r.add_argument("--rot-stiffness", type=float, default=50.0, help="tracking: N·m/rad (franky's default)")
    r.add_argument("--waypoint-dt", type=float, default=0.01, help="waypoints: spacing, s")
    r.add_argument("--waypoint-slack-ms", type=int, default=1,
                   help="waypoints: taken off every segment's minimum_time (franky's switch cycle)")
    t = sub.add_parser("table")
    t.add_argument("files", nargs="+", help="NAME=FILE.json")
    args = ap.parse_args()
    return run(args) if args.cmd == "run" else table(args)


if __name__ == "__main__":
    sys.exit(main())
