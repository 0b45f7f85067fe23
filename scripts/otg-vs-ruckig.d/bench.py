"""Calculation time of our OTG next to Ruckig's own reported C++ calculation time, 7 axes,
moving start to a target at rest (the issue's speed category), in one run.

Jobs come in chunks of 250; for each chunk Ruckig times every job (a fresh Ruckig(7, 1 ms), then
reset + update 23 times, the best of the last 20 `calculation_duration`s: its input check,
calculation and first sample), then our bench binary times the same jobs the same way
(rl-core/benches/otg.rs with RL_OTG_JOBS: input check, calculation into a kept trajectory and the
first sample, best of 20). Alternating chunks share whatever else the machine is doing.

Prints the medians, 99th percentiles and maxima, their ratios (ours / Ruckig; the issue's goals:
median <= 0.5, worst <= 1.0), the per-job ratio distribution, and the per-cycle step (our bench's
RL_OTG_STEPS mode: best of 200 batches of 1000 cycles).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

import jobs as J
from ruckig import OutputParameter, Ruckig


def quantile(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * (len(xs) - 1) + 0.5))]


def ruckig_times(batch):
    out = []
    for job in batch:
        inp = J.ruckig_input(job)
        otg, o = Ruckig(7, 0.001), OutputParameter(7)
        best = float("inf")
        for r in range(23):
            otg.reset()
            res = otg.update(inp, o)
            if int(res) < 0:
                raise SystemExit(f"Ruckig failed on {json.dumps(job)}")
            if r >= 3:
                best = min(best, o.calculation_duration * 1000.0)
        out.append(best)
    return out


def our_times(bench, batch):
    with tempfile.NamedTemporaryFile("w", suffix=".jsonl", delete=False) as f:
        for job in batch:
            f.write(json.dumps(job) + "\n")
        path = f.name
    try:
        env = dict(os.environ, RL_OTG_JOBS=path)
        out = subprocess.run([bench], env=env, capture_output=True, text=True, check=True)
    finally:
        os.unlink(path)
    return [float(line.split()[1]) for line in out.stdout.splitlines()]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bench", required=True, help="the otg bench binary")
    parser.add_argument("--jobs", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    g = J.Gen(args.seed)
    theirs, ours = [], []
    while len(theirs) < args.jobs:
        batch = []
        while len(batch) < 250:
            job = J.make_job("moving_start", 6, g)  # job 6 of the cycle has 7 axes
            job["sync"] = "time"
            if J.ruckig_solve(job)[1] is not None:
                batch.append(job)
        theirs += ruckig_times(batch)
        ours += our_times(args.bench, batch)
    n = len(theirs)
    rows = [("median", 0.5), ("p99", 0.99), ("max", 1.0)]
    print(f"{n} moving-start jobs, 7 axes, time-synchronised; nanoseconds per calculation")
    print(f"{'':8} {'Ruckig':>10} {'rl-core':>10} {'ratio':>7}")
    ratio = {}
    for name, q in rows:
        r, o = quantile(theirs, q), quantile(ours, q)
        ratio[name] = o / r
        print(f"{name:8} {r:10.0f} {o:10.0f} {o / r:7.3f}")
    per_job = [o / r for o, r in zip(ours, theirs)]
    print(f"per-job ratio ours/Ruckig: median {quantile(per_job, 0.5):.3f}, "
          f"p99 {quantile(per_job, 0.99):.3f}, max {max(per_job):.3f}")
    steps = subprocess.run([args.bench], env=dict(os.environ, RL_OTG_STEPS="1"),
                           capture_output=True, text=True, check=True).stdout
    print("per-cycle, 7 axes: " + ", ".join(line.replace("_ns", " ns").replace(" ", " = ", 1)
                                             for line in steps.split("\n") if line))
    goal_median = "met" if ratio["median"] <= 0.5 else "NOT met"
    goal_worst = "met" if ratio["max"] <= 1.0 else "NOT met"
    print(f"goals: median <= 0.5x Ruckig: {goal_median} ({ratio['median']:.3f}); "
          f"worst <= 1.0x Ruckig: {goal_worst} ({ratio['max']:.3f})")


if __name__ == "__main__":
    main()
