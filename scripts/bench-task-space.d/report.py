"""The table of scripts/bench-task-space, after the check that both sides computed the same
torques (every state: max |τ_ours − τ_pin| ≤ 1e-9 ‖τ_pin‖); without it no ratio is printed and
the exit status is 1.

Usage: report.py PROBLEM_JSON RESULTS_DIR ROUNDS INNER CPU NCPU PIN_DESC PIN_VERSION RUSTC CXX
                 ELAPSED_S
"""

import datetime
import json
import math
import statistics
import sys

TOLERANCE = 1e-9
GOAL_NS = 10_000.0  # issue 27


def main():
    (problem, res, rounds, inner, cpu, ncpu, pin_desc, pin_v, rustc, cxx,
     elapsed) = sys.argv[1:]
    P = json.load(open(problem))
    ours = [json.loads(l) for l in open(f"{res}/ours.jsonl") if l.strip()]
    pin = [json.loads(l) for l in open(f"{res}/pinocchio.jsonl") if l.strip()]
    t_ours = json.load(open(f"{res}/tau.ours.json"))["tau"]
    t_pin = json.load(open(f"{res}/tau.pinocchio.json"))["tau"]

    # The same law? Every state's torques.
    worst, worst_state, bad = 0.0, None, []
    if len(t_ours) != len(t_pin) or len(t_pin) != len(P["states"]):
        bad.append("state counts differ")
    for s, (a, b) in enumerate(zip(t_ours, t_pin)):
        norm = math.sqrt(sum(x * x for x in b))
        rel = max(abs(x - y) for x, y in zip(a, b)) / max(norm, 1e-300)
        if not math.isfinite(rel) or rel > TOLERANCE:
            bad.append(f"state {s}: {rel:.2e}")
        if not rel <= worst:
            worst, worst_state = rel, s
    same = not bad

    med = lambda rows, k: statistics.median(r[k] for r in rows)  # noqa: E731
    o_cycle, o_dist = med(ours, "ns"), med(ours, "ns_distances")
    p_all, p_sw, p_dist = med(pin, "ns_all_terms"), med(pin, "ns_sweeps"), med(pin, "ns_distances")
    p_cycle = min(p_all, p_sw)
    p_which = "computeAllTerms" if p_all <= p_sw else "fk + crba(WORLD) + nle"
    allocs = sum(r["allocations"] for r in ours)
    cycles = sum(r["timed_cycles"] for r in ours)
    within = P["capsules_within_influence"]
    k = P["gains"]["repulsion"]["max_contacts"]
    exercised = sum(1 for c in within if c >= 1)

    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    print(f"# {now}; CPU: {cpu} ({ncpu} CPUs); {pin_desc}")
    print(f"# rl-rs: {rustc}, -C target-cpu=native; Pinocchio {pin_v} (PyPI pin, C++ "
          f"header-only, -O3 -DNDEBUG -march=native, {cxx})")
    print(f"# Panda (example-robot-data panda.urdf, fingers fixed), tool {P['tool']}; "
          f"{len(P['states'])} random states; {len(P['capsules'])} capsules x "
          f"{len(P['obstacles'])} spheres; K = {k}; contacts per state: mean "
          f"{statistics.mean(min(c, k) for c in within):.2f}, repulsion acts in {exercised} "
          f"of {len(within)} states")
    print(f"# ns per cycle: median over {rounds} alternating rounds of the median of {inner} "
          f"inner rounds")
    if same:
        print(f"# same law: torques agree on all {len(t_pin)} states, max |dtau| / |tau| = "
              f"{worst:.1e} (state {worst_state}; limit {TOLERANCE:.0e})")
    else:
        print(f"# NOT THE SAME LAW: torques differ beyond {TOLERANCE:.0e} relative on "
              f"{len(bad)} states ({'; '.join(bad[:5])}); no ratio printed")
    print(f"{'part':<45} {'rl-rs':>9} {'pinocchio':>10} {'ours/pin':>9}")
    rows = [("whole cycle (FK, capsules, contacts, law)", o_cycle, p_cycle),
            ("distance part alone (FK, capsules, nearest K)", o_dist, p_dist)]
    for name, o, p in rows:
        ratio = f"{o / p:>9.2f}" if same else f"{'-':>9}"
        print(f"{name:<45} {o:>9.0f} {p:>10.0f} {ratio}")
    print(f"# Pinocchio's cycle: the faster of computeAllTerms ({p_all:.0f} ns) and "
          f"fk + crba(WORLD) + nle ({p_sw:.0f} ns): {p_which}")
    print(f"# rl-rs: {allocs} heap allocations in {cycles} timed cycles; goal <= "
          f"{GOAL_NS / 1000:.0f} us per cycle: {o_cycle / 1000:.1f} us, "
          f"{'met' if o_cycle <= GOAL_NS else 'not met'}")
    print(f"# run time {elapsed} s (with builds)")
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
