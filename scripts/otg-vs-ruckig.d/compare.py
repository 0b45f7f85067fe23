"""Our OTG (`rl otg --verify`) against Ruckig (PyPI `ruckig`) on random jobs per category.

Per category of jobs.py: N jobs in chunks (each chunk its own seed, so any chunk can be re-run
alone), Ruckig's answer per job (a fresh Ruckig per job: reused ones carry state), ours from
`rl otg --verify` on the same JSONL, and the comparison:

  failed      ours refused a job Ruckig solved
  differ      both solved, durations differ by more than 1e-9 relative and ours is not shorter
  shorter     ours is shorter than Ruckig's by more than 1e-9 relative, and valid (its end state
              and every limit checked exactly): Ruckig's answer was not time-optimal there
  violated    our trajectory exceeds a limit by more than 1e-9 (exact per-segment check)
  accepted    Ruckig calls the input invalid (target outside the limits) and ours accepted it
  worst rel   the largest relative duration difference among the agreeing jobs

Every job that fails, differs, is shorter, violates or is wrongly accepted is written to
target/otg-vs-ruckig/<category>.jsonl with Ruckig's and our answers, and the first few are
printed.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import jobs as J

TOLERANCE = 1e-9


def run_chunk(rl, category, seed, count):
    g = J.Gen(seed)
    batch = [J.make_job(category, k, g) for k in range(count)]
    theirs = [J.ruckig_solve(job) for job in batch]
    with tempfile.NamedTemporaryFile("w", suffix=".jsonl", delete=False) as f:
        for job in batch:
            f.write(json.dumps(job, separators=(",", ":")) + "\n")
        path = f.name
    try:
        out = subprocess.run([rl, "otg", "--verify", path], capture_output=True, text=True)
    finally:
        os.unlink(path)
    if out.returncode not in (0, 1):
        sys.exit(f"rl otg failed ({out.returncode}): {out.stderr}")
    ours = [json.loads(line) for line in out.stdout.splitlines()]
    if len(ours) != len(batch):
        sys.exit(f"rl otg answered {len(ours)} of {len(batch)} jobs: {out.stderr}")
    return batch, theirs, ours


def compare(category, args, rl, record):
    stats = dict(jobs=0, ruckig_ok=0, ours_ok=0, failed=0, differ=0, shorter=0, violated=0,
                 accepted=0, invalid=0)
    worst = 0.0
    shown = 0
    chunks = (args.jobs + args.chunk - 1) // args.chunk
    started = time.time()
    for c in range(chunks):
        count = min(args.chunk, args.jobs - c * args.chunk)
        seed = args.seed + 1_000_003 * (J.CATEGORIES.index(category) + 1) + c
        batch, theirs, ours = run_chunk(rl, category, seed, count)
        for job, (result, duration), mine in zip(batch, theirs, ours):
            stats["jobs"] += 1
            problem = None
            if mine["result"] == "invalid":
                stats["invalid"] += 1
                problem = "invalid"
            ok = mine["result"] == "ok"
            stats["ours_ok"] += ok
            if ok and mine.get("violation"):
                stats["violated"] += 1
                problem = "violated"
            if duration is not None:
                stats["ruckig_ok"] += 1
                if not ok:
                    stats["failed"] += 1
                    problem = "failed"
                else:
                    d = mine["duration_s"]
                    rel = abs(d - duration) / max(abs(duration), 1e-12)
                    if d < duration - TOLERANCE * abs(duration) - 1e-12 and not mine.get("violation"):
                        stats["shorter"] += 1
                        problem = problem or "shorter"
                    elif abs(d - duration) > TOLERANCE * abs(duration) + 1e-12:
                        stats["differ"] += 1
                        problem = "differ"
                    else:
                        worst = max(worst, rel)
            elif result == "ErrorInvalidInput" and ok:
                stats["accepted"] += 1
                problem = "accepted"
            if problem:
                entry = dict(job)
                entry["ruckig"] = {"result": result, "duration": duration}
                entry["ours"] = mine
                entry["problem"] = problem
                record.write(json.dumps(entry) + "\n")
                if shown < args.show and problem != "shorter":
                    print(f"  {problem}: {json.dumps(entry)}")
                    shown += 1
        done = stats["jobs"]
        if args.progress and c % 10 == 9:
            rate = done / (time.time() - started)
            print(f"  {category}: {done} jobs ({rate:.0f}/s)", file=sys.stderr)
    stats["worst_rel"] = worst
    return stats


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rl", required=True, help="the rl binary")
    parser.add_argument("--jobs", type=int, default=1_000_000, help="jobs per category")
    parser.add_argument("--chunk", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--categories", default=",".join(J.CATEGORIES))
    parser.add_argument("--out", required=True, help="directory for the jobs that disagree")
    parser.add_argument("--show", type=int, default=3, help="jobs printed per category")
    parser.add_argument("--progress", action="store_true")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    categories = [c for c in args.categories.split(",") if c]
    for c in categories:
        if c not in J.CATEGORIES:
            sys.exit(f"unknown category {c}; known: {', '.join(J.CATEGORIES)}")
    import importlib.metadata
    print(f"ruckig {importlib.metadata.version('ruckig')}, {args.jobs} jobs per category, seed {args.seed}")
    header = (f"{'category':26} {'jobs':>8} {'ruckig ok':>9} {'ours ok':>8} {'failed':>6} "
              f"{'differ':>6} {'shorter':>7} {'violated':>8} {'accepted':>8} {'worst rel':>9}")
    rows = []
    total_bad = 0
    for category in categories:
        with open(os.path.join(args.out, category + ".jsonl"), "w") as record:
            s = compare(category, args, args.rl, record)
        rows.append((category, s))
        bad = s["failed"] + s["differ"] + s["violated"] + s["accepted"] + s["invalid"]
        total_bad += bad
        print(f"{category}: {s['jobs']} jobs, Ruckig solved {s['ruckig_ok']}, ours {s['ours_ok']}; "
              f"failed {s['failed']}, differ {s['differ']}, shorter {s['shorter']}, "
              f"violated {s['violated']}, accepted invalid {s['accepted']}, "
              f"worst rel {s['worst_rel']:.1e}", flush=True)
    print()
    print(header)
    for category, s in rows:
        print(f"{category:26} {s['jobs']:8} {s['ruckig_ok']:9} {s['ours_ok']:8} {s['failed']:6} "
              f"{s['differ']:6} {s['shorter']:7} {s['violated']:8} {s['accepted']:8} "
              f"{s['worst_rel']:9.1e}")
    print(f"\njobs that disagree: {args.out}/<category>.jsonl")
    sys.exit(1 if total_bad else 0)


if __name__ == "__main__":
    main()
