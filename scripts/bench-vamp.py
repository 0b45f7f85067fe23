"""The VAMP side of scripts/bench-vamp, and its table. Run with the python of scripts/vamp-build.

  bench-vamp.py run ROBOT PROBLEMS.tar.bz2 OUT.csv   plan every problem once with VAMP's RRT-Connect
                                                       (its defaults for ROBOT) and shortcut-only
                                                       simplification; one CSV row per problem
  bench-vamp.py table ROBOT DIR                        per-problem minima over the rounds in DIR
                                                       (vamp-*.csv and ours-*.csv), the table

Problems are read from VAMP's problems.tar.bz2 as its resources/problem_tar_to_pkl_json.py reads
them (MoveIt YAML scenes of boxes, cylinders and spheres; joint starts and goals), cached as a
pickle beside OUT. Times are VAMP's own (result.nanoseconds, measured in C++ around the planner
and the simplifier), as rl plan bench's are measured in Rust around ours.
"""

import csv
import math
import pickle
import re
import sys
import tarfile
from collections import defaultdict
from pathlib import Path

import numpy as np
import yaml

try:
    from yaml import CLoader as Loader
except ImportError:  # pragma: no cover
    from yaml import Loader


def transform(tf):
    from vamp.transformations import quaternion_matrix, translation_matrix

    return np.dot(translation_matrix(tf["position"]), quaternion_matrix(tf["orientation"]))


def scene_of(data):
    from vamp.transformations import (
        euler_from_matrix,
        identity_matrix,
        quaternion_from_matrix,
        translation_from_matrix,
    )

    objects = {"sphere": [], "cylinder": [], "box": []}
    for co in data["world"]["collision_objects"]:
        obj = {"name": co["id"]}
        base = identity_matrix() if "pose" not in co else transform(co["pose"])
        prim, prim_pose = co["primitives"][0], transform(co["primitive_poses"][0])
        pose = np.dot(base, prim_pose)
        kind = prim["type"]
        if kind == "sphere":
            obj["radius"] = prim["dimensions"][0]
        elif kind == "cylinder":
            obj.update({"length": prim["dimensions"][0], "radius": prim["dimensions"][1]})
        elif kind == "box":
            obj["half_extents"] = [x / 2 for x in prim["dimensions"]]
        else:
            raise RuntimeError(f"primitive {kind}")
        obj.update(
            {
                "position": translation_from_matrix(pose).tolist(),
                "orientation_euler_xyz": euler_from_matrix(pose),
                "orientation_quat_xyzw": quaternion_from_matrix(pose).tolist(),
            }
        )
        objects[kind].append(obj)
    return objects


def request_of(data, joints):
    js = data["start_state"]["joint_state"]
    start = [js["position"][js["name"].index(j)] for j in joints]
    names, values = zip(
        *[(e["joint_name"], e["position"]) for e in data["goal_constraints"][0]["joint_constraints"]]
    )
    return {"start": start, "goals": [[values[names.index(j)] for j in joints]]}


def problems(robot, tar_path, cache):
    if cache.exists():
        return pickle.loads(cache.read_bytes())
    import vamp

    module = getattr(vamp, robot)
    joints = module.joint_names()
    scenes, requests = {}, {}
    with tarfile.open(tar_path, "r:bz2") as tar:
        for m in tar.getmembers():
            if not m.isfile():
                continue
            _, scenario, filename = m.name.split("/")
            index = int(re.findall(r"\d+", filename)[0])
            data = yaml.load(tar.extractfile(m).read(), Loader=Loader)
            key = f"{scenario}/{index:04d}"
            if filename.startswith("scene"):
                scenes[key] = scene_of(data)
            else:
                requests[key] = request_of(data, joints)
    # "problem" (the scenario without the robot's suffix) as VAMP's converter sets it: its
    # problem_dict_to_vamp treats the cylinders of "box" differently (boxes, not capsules).
    out = {
        k: {**scenes[k], **requests[k], "problem": k.split("/")[0].replace(f"_{robot}", ""),
            "index": int(k.split("/")[1])}
        for k in sorted(requests)
    }
    for p in out.values():
        env = vamp.problem_dict_to_vamp(p)
        p["valid"] = bool(module.validate(p["start"], env) and module.validate(p["goals"][0], env))
    cache.write_bytes(pickle.dumps(out))
    return out


def run(robot, tar_path, out):
    import vamp

    out = Path(out)
    probs = problems(robot, tar_path, out.parent / f"problems-{robot}.pkl")
    module, planner, plan_settings, simp_settings = vamp.configure_robot_and_planner_with_kwargs(
        robot, "rrtc"
    )
    # Shortcut-only simplification, as rl plan bench --optimizer shortcut.
    simp_settings.operations = [vamp.SimplifyRoutine.SHORTCUT]
    sampler = module.halton()
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["problem", "valid", "solved", "planning_us", "simplify_us", "iterations",
                    "length_before", "length_after", "waypoints_after"])
        for name, p in probs.items():
            if not p["valid"]:
                w.writerow([name, 0, 0, "", "", "", "", "", ""])
                continue
            env = vamp.problem_dict_to_vamp(p)
            sampler.reset()
            r = planner(p["start"], p["goals"], env, plan_settings, sampler)
            if not r.path:
                w.writerow([name, 1, 0, r.nanoseconds / 1e3, "", r.iterations, "", "", ""])
                continue
            s = module.simplify(r.path, env, simp_settings, sampler)
            w.writerow([name, 1, 1, r.nanoseconds / 1e3, s.nanoseconds / 1e3, r.iterations,
                        r.path.cost(), s.path.cost(), len(s.path)])


def read(path, ours):
    rows = {}
    with open(path) as f:
        for r in csv.DictReader(f, skipinitialspace=True):
            if ours:
                # rl plan bench's RL-style CSV: scenario_robot/NNNN.
                scenario, index = r["Problem"].split("/")
                name = f"{scenario}/{index}"
                solved = r["Solved"] == "true"
                rows[name] = {
                    "solved": solved,
                    "planning_us": float(r["Duration (s)"]) * 1e6,
                    "simplify_us": float(r["Optimization Duration (s)"]) * 1e6 if solved else math.nan,
                    "length_after": float(r["Optimized Path Length"]) if solved else math.nan,
                    "iterations": int(r["Iterations"]),
                }
            else:
                solved = r["solved"] == "1"
                rows[r["problem"]] = {
                    "solved": solved,
                    "planning_us": float(r["planning_us"]) if r["planning_us"] else math.nan,
                    "simplify_us": float(r["simplify_us"]) if solved else math.nan,
                    "length_after": float(r["length_after"]) if solved else math.nan,
                    "iterations": int(r["iterations"]) if r["iterations"] else 0,
                }
    return rows


def quantile(v, p):
    v = sorted(v)
    h = (len(v) - 1) * p
    lo, hi = math.floor(h), math.ceil(h)
    return v[lo] + (h - lo) * (v[hi] - v[lo])


def table(robot, d):
    d = Path(d)
    rounds = {"vamp": sorted(d.glob("vamp-*.csv")), "ours": sorted(d.glob("ours-*.csv"))}
    if not rounds["vamp"] or not rounds["ours"]:
        sys.exit(f"bench-vamp.py: no rounds in {d}")
    runs = {k: [read(p, k == "ours") for p in v] for k, v in rounds.items()}
    names = set.intersection(*[set(r) for rs in runs.values() for r in rs])
    # The same problems solved: solved by both in every round.
    both = sorted(n for n in names if all(r[n]["solved"] for rs in runs.values() for r in rs))
    solved = {k: sum(all(r[n]["solved"] for r in rs) for n in names) for k, rs in runs.items()}
    best = defaultdict(dict)
    for k, rs in runs.items():
        for field in ("planning_us", "simplify_us"):
            best[k][field] = [min(r[n][field] for r in rs) for n in both]
        best[k]["length_after"] = [rs[0][n]["length_after"] for n in both]
    out = []
    out.append(f"{robot}: {len(both)} problems solved by both in all of {len(rounds['vamp'])} / "
               f"{len(rounds['ours'])} rounds (VAMP solved {solved['vamp']}, ours {solved['ours']}, "
               f"of {len(names)}); per-problem minimum over the rounds, µs")
    out.append("")
    out.append("| | VAMP | ours | ours / VAMP |")
    out.append("|---|---|---|---|")
    for field, label in (("planning_us", "planning"), ("simplify_us", "simplification")):
        for stat, f in (("mean", lambda v: sum(v) / len(v)), ("median", lambda v: quantile(v, 0.5)),
                        ("p95", lambda v: quantile(v, 0.95))):
            a, b = f(best["vamp"][field]), f(best["ours"][field])
            out.append(f"| {label} {stat} | {a:.1f} | {b:.1f} | {b / a:.2f} |")
    la, lb = best["vamp"]["length_after"], best["ours"]["length_after"]
    out.append(f"| simplified length mean (rad) | {sum(la) / len(la):.3f} | {sum(lb) / len(lb):.3f} "
               f"| {sum(lb) / sum(la):.2f} |")
    print("\n".join(out))


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "run":
        run(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) == 4 and sys.argv[1] == "table":
        table(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
