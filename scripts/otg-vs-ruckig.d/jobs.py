"""Random OTG jobs by category, and Ruckig's answer to each (PyPI `ruckig`, the C++ library's
binding). Used by scripts/otg-vs-ruckig (the full comparison) and scripts/gen-otg-fixtures (the
committed subset that rl-core's test reads).

A job is a dict in the JSONL format of `rl otg` (infinite numbers as the strings "inf"/"-inf").
The distributions follow Ruckig's own randomised tests (test/test_target.cpp: positions N(0, 4),
velocities and accelerations N(0, 0.8), limits U(0.08, 16) plus the target's magnitude), one
category per question the issue asks.
"""
import math
import random

from ruckig import (ControlInterface, InputParameter, Result, Ruckig, Synchronization,
                    Trajectory)

CATEGORIES = [
    "rest_to_rest",
    "moving_start",
    "moving_target",
    "velocity_interface",
    "asymmetric_limits",
    "near_zero_and_zero_limits",
    "infinite_limits",
    "outside_reachable_set",
    "phase_collinear",
    "discrete_edges",
    "high_limits",
]

SYNC = {"time": Synchronization.Time, "time_if_necessary": Synchronization.TimeIfNecessary,
        "phase": Synchronization.Phase, "none": Synchronization.No}


def enc(x):
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


def dec(x):
    if isinstance(x, str):
        return float(x)
    return x


class Gen:
    def __init__(self, seed):
        self.r = random.Random(seed)

    def pos(self, n):
        return [self.r.gauss(0.0, 4.0) for _ in range(n)]

    def dyn(self, n, p=1.0):
        return [self.r.gauss(0.0, 0.8) if self.r.random() < p else 0.0 for _ in range(n)]

    def lim(self, n, offset=None, lo=0.08, hi=16.0):
        return [self.r.uniform(lo, hi) + (abs(offset[i]) if offset else 0.0) for i in range(n)]


def make_job(cat, k, g):
    """Job number k of a category (deterministic for a generator state)."""
    r = g.r
    n = 1 + k % 7
    job = {"sync": "phase" if k % 4 == 0 else "time"}
    zeros = [0.0] * n
    if cat == "rest_to_rest":
        cur = {"p": g.pos(n), "v": zeros, "a": zeros}
        tgt = {"p": g.pos(n), "v": zeros, "a": zeros}
        vmax, amax, jmax = g.lim(n), g.lim(n), g.lim(n)
    elif cat == "moving_start":
        cur = {"p": g.pos(n), "v": g.dyn(n, 0.9), "a": g.dyn(n, 0.8)}
        tgt = {"p": g.pos(n), "v": zeros, "a": zeros}
        vmax, amax, jmax = g.lim(n), g.lim(n), g.lim(n)
    elif cat in ("moving_target", "asymmetric_limits", "phase_collinear", "high_limits"):
        cur = {"p": g.pos(n), "v": g.dyn(n, 0.9), "a": g.dyn(n, 0.8)}
        tgt = {"p": g.pos(n), "v": g.dyn(n, 0.7), "a": g.dyn(n, 0.6)}
        if cat == "high_limits":
            cur["v"], cur["a"] = g.dyn(n, 0.1), g.dyn(n, 0.1)
            tgt["v"], tgt["a"] = g.dyn(n, 0.1), g.dyn(n, 0.1)
            vmax = g.lim(n, tgt["v"], 10.0, 1e6)
            amax = g.lim(n, tgt["a"], 10.0, 1e6)
            jmax = g.lim(n, None, 10.0, 1e6)
        else:
            vmax, amax, jmax = g.lim(n, tgt["v"]), g.lim(n, tgt["a"]), g.lim(n)
        if cat == "asymmetric_limits":
            job["vmin"] = [-x for x in g.lim(n, tgt["v"])]
            job["amin"] = [-x for x in g.lim(n, tgt["a"])]
        if cat == "phase_collinear":
            # One direction for everything, scaled per axis: straight lines in joint space.
            job["sync"] = "phase"
            scale = [r.uniform(-1.0, 1.0) for _ in range(n)]
            base = [r.gauss(0, 4), r.gauss(0, 0.8) * (r.random() < 0.7), r.gauss(0, 0.8) * (r.random() < 0.5),
                    r.gauss(0, 0.8) * (r.random() < 0.5), r.gauss(0, 0.8) * (r.random() < 0.4)]
            p0 = g.pos(n)
            cur = {"p": p0, "v": [base[1] * s for s in scale], "a": [base[2] * s for s in scale]}
            tgt = {"p": [p0[i] + base[0] * scale[i] for i in range(n)],
                   "v": [base[3] * s for s in scale], "a": [base[4] * s for s in scale]}
            vmax, amax, jmax = g.lim(n, tgt["v"]), g.lim(n, tgt["a"]), g.lim(n)
    elif cat == "velocity_interface":
        job["interface"] = "velocity"
        cur = {"p": zeros, "v": g.dyn(n, 0.9), "a": g.dyn(n, 0.8)}
        tgt = {"p": zeros, "v": g.dyn(n, 0.7), "a": g.dyn(n, 0.6)}
        vmax, amax, jmax = g.lim(n, tgt["v"]), g.lim(n, tgt["a"]), g.lim(n)
    elif cat == "near_zero_and_zero_limits":
        cur = {"p": g.pos(n), "v": g.dyn(n, 0.5), "a": g.dyn(n, 0.3)}
        tgt = {"p": g.pos(n), "v": g.dyn(n, 0.3), "a": g.dyn(n, 0.2)}
        if r.random() < 0.3:
            tgt["p"] = list(cur["p"])
        vmax, amax, jmax = g.lim(n, tgt["v"]), g.lim(n, tgt["a"]), g.lim(n)
        for lim, target in ((vmax, tgt["v"]), (amax, tgt["a"]), (jmax, None)):
            for i in range(n):
                u = r.random()
                if u < 0.15:
                    lim[i] = 0.0 if target is None or target[i] == 0.0 else abs(target[i])
                elif u < 0.35:
                    lim[i] = 10 ** r.uniform(-9, -2) + (abs(target[i]) if target else 0.0)
    elif cat == "infinite_limits":
        cur = {"p": g.pos(n), "v": g.dyn(n, 0.8), "a": g.dyn(n, 0.5)}
        tgt = {"p": g.pos(n), "v": g.dyn(n, 0.5), "a": g.dyn(n, 0.3)}
        vmax, amax, jmax = g.lim(n, tgt["v"]), g.lim(n, tgt["a"]), g.lim(n)
        mode = r.random()
        for i in range(n):
            if mode < 0.5 or r.random() < 0.5:
                jmax[i] = math.inf
        if mode > 0.8:
            amax = [math.inf] * n
            jmax = [math.inf] * n
    elif cat == "outside_reachable_set":
        cur = {"p": g.pos(n), "v": g.dyn(n, 0.8), "a": g.dyn(n, 0.6)}
        tgt = {"p": g.pos(n), "v": g.dyn(n, 0.9), "a": g.dyn(n, 0.9)}
        vmax, amax, jmax = g.lim(n, None, 0.08, 2.0), g.lim(n, None, 0.08, 2.0), g.lim(n)
        # Push one axis' target beyond its limits (or right at the edge of what is approachable).
        i = r.randrange(n)
        how = r.random()
        if how < 0.3:
            tgt["v"][i] = (vmax[i] * r.uniform(1.0, 2.0)) * (1 if r.random() < 0.5 else -1)
        elif how < 0.6:
            tgt["a"][i] = (amax[i] * r.uniform(1.0, 2.0)) * (1 if r.random() < 0.5 else -1)
        else:
            af = amax[i] * r.uniform(0.5, 1.0) * (1 if r.random() < 0.5 else -1)
            swing = af * af / (2 * jmax[i])
            tgt["a"][i] = af
            tgt["v"][i] = (vmax[i] - swing * r.uniform(0.0, 2.0)) if af < 0 else -(vmax[i] - swing * r.uniform(0.0, 2.0))
    elif cat == "discrete_edges":
        d = lambda: float(r.randint(-1, 1))
        cur = {"p": [d() for _ in range(n)], "v": [d() for _ in range(n)], "a": [d() for _ in range(n)]}
        tgt = {"p": [d() for _ in range(n)], "v": [d() for _ in range(n)], "a": [d() for _ in range(n)]}
        vmax = [float(r.randint(1, 2)) + abs(tgt["v"][i]) for i in range(n)]
        amax = [float(r.randint(1, 2)) + abs(tgt["a"][i]) for i in range(n)]
        jmax = [float(r.randint(1, 2)) for _ in range(n)]
    else:
        raise ValueError(cat)
    job.update({"current": cur, "target": tgt, "vmax": vmax, "amax": amax, "jmax": jmax})
    return encode(job)


def encode(job):
    out = {}
    for key, value in job.items():
        if isinstance(value, dict):
            out[key] = {k: [enc(x) for x in v] for k, v in value.items()}
        elif isinstance(value, list):
            out[key] = [enc(x) for x in value]
        else:
            out[key] = value
    return out


def ruckig_input(job):
    n = len(job["vmax"])
    inp = InputParameter(n)
    inp.current_position = [dec(x) for x in job["current"]["p"]]
    inp.current_velocity = [dec(x) for x in job["current"]["v"]]
    inp.current_acceleration = [dec(x) for x in job["current"]["a"]]
    inp.target_position = [dec(x) for x in job["target"]["p"]]
    inp.target_velocity = [dec(x) for x in job["target"]["v"]]
    inp.target_acceleration = [dec(x) for x in job["target"]["a"]]
    inp.max_velocity = [dec(x) for x in job["vmax"]]
    inp.max_acceleration = [dec(x) for x in job["amax"]]
    inp.max_jerk = [dec(x) for x in job["jmax"]]
    if "vmin" in job:
        inp.min_velocity = [dec(x) for x in job["vmin"]]
    if "amin" in job:
        inp.min_acceleration = [dec(x) for x in job["amin"]]
    if job.get("interface") == "velocity":
        inp.control_interface = ControlInterface.Velocity
    inp.synchronization = SYNC[job.get("sync", "time")]
    if "min_duration" in job:
        inp.minimum_duration = job["min_duration"]
    return inp


def ruckig_solve(job):
    """Ruckig's result name and duration (None unless it succeeded).

    A fresh Ruckig and Trajectory per job: reusing them carries state from one calculation to
    the next (with infinite jerk and acceleration limits the previous job's braking time stays
    in the profile and is added to the next duration; seen with 0.19.4).
    """
    n = len(job["vmax"])
    otg = (Ruckig(n), Trajectory(n))
    inp = ruckig_input(job)
    try:
        res = otg[0].calculate(inp, otg[1])
    except Exception as e:  # the binding raises RuckigError instead of returning most errors
        text = str(e)
        if "-101" in text:  # ErrorTrajectoryDuration, missing from the binding's Result enum
            return "ErrorTrajectoryDuration", None
        if "step 1" in text:
            return "ErrorExecutionTimeCalculation", None
        if "zero limits" in text:
            return "ErrorZeroLimits", None
        if "step 2" in text or "synchronization" in text:
            return "ErrorSynchronizationCalculation", None
        return "ErrorInvalidInput", None
    name = str(res).split(".")[-1]
    if res == Result.Working:
        return name, otg[1].duration
    return name, None
