"""The problem of scripts/bench-task-space: the Panda, 64 states, a target, 30 capsules on the
arm, 50 obstacle spheres and the gains, as both programs read them.

Usage (inside the benchmark venv, which has pin and numpy):
  gen_problem.py PANDA_URDF OUT_DIR [--states N] [--seed S]

Writes into OUT_DIR:
  panda.urdf       example-robot-data's panda.urdf with both finger joints fixed (at 0, as
                   Pinocchio's buildReducedModel) and <mimic> removed: the model both load;
  panda.pinmodel   that URDF as pin parsed it, in Pinocchio's text serialization
                   (Model::saveToText), for task_bench.cpp (as bench-pinocchio does);
  problem.json     everything, for rl-task-bench (Rust) and the report;
  problem.txt      the same numbers in a flat text form for task_bench.cpp (no JSON parser in
                   C++); see write_text below.

Draws (numpy PCG64, seeded: the same file on any machine): q uniform within the URDF limits,
q̇ uniform in ±1 rad/s. Target: the tool's (panda_hand) pose at the Panda's ready pose plus
5 cm; posture = the ready pose. Capsules: 3 per link on panda_link1..7, panda_hand and both
fingers (30), each in its joint's frame (the joint frame = the rl-core body frame = the child
link frame), covering the segment from the link's origin to its child's (or from its parent's
origin when that one is under 5 cm) in three consecutive pieces, radius 0.04–0.08 m. Obstacles:
50 spheres (radius 0.03–0.1 m) placed by a seeded local search so that, in as many states as
it can, 1 to 4 capsules have their nearest sphere within the influence distance.
"""

import argparse
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

FORMAT = "rl-rs task-space bench problem 1"
FIX = ["panda_finger_joint1", "panda_finger_joint2"]
TOOL = "panda_hand"
READY = [0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4]
OFFSET = [0.03, 0.0, 0.04]  # 5 cm
GRAVITY = [0.0, 0.0, -9.80665]
GAINS = {
    "stiffness": [400.0, 400.0, 400.0, 300.0, 300.0, 300.0],
    "damping_ratio": 1.0,
    "max_position_error": 0.05,
    "max_orientation_error": 0.3,
    "posture_stiffness": 10.0,
    "posture_damping_ratio": 1.0,
    "limit_band": 0.1,
    "limit_stiffness": 200.0,
    "clamp": [0.01, 0.1],  # ε_lin, ε_ang
    "priority": "orientation_first",
    "repulsion": {
        "influence": 0.2,
        "margin": 0.05,
        "gain": 1.0,  # k_b, m²/s²
        "damping": 20.0,  # D, 1/s
        "max_acceleration": 50.0,
        "max_contacts": 4,
    },
}
N_CAPSULES = 30
N_OBSTACLES = 50


def write_urdf(src, dst):
    tree = ET.parse(src)
    found = set()
    for joint in tree.getroot().iter("joint"):
        for el in joint.findall("mimic"):
            joint.remove(el)
        if joint.get("name") in FIX:
            joint.set("type", "fixed")
            found.add(joint.get("name"))
    if found != set(FIX):
        sys.exit(f"gen_problem: {src} lacks {set(FIX) - found}")
    tree.write(dst, xml_declaration=True, encoding="utf-8")


def capsules(model, rng):
    """30 capsules: (joint name, joint index, a, b, radius), a and b in the joint's frame."""
    out = []

    def split(jid, a, b, link):
        for k in range(3):
            pa = a + (b - a) * (k / 3.0)
            pb = a + (b - a) * ((k + 1) / 3.0)
            out.append({"link": link, "joint": model.names[jid], "joint_index": jid,
                        "a": pa.tolist(), "b": pb.tolist(),
                        "radius": float(rng.uniform(0.04, 0.08))})

    for i in range(1, 8):
        own = np.zeros(3)
        if i < 7:
            child = model.jointPlacements[i + 1].translation.copy()
        else:
            child = model.frames[model.getFrameId("panda_link8")].placement.translation.copy()
        if np.linalg.norm(child) < 0.05:
            m = model.jointPlacements[i]
            child = -m.rotation.T @ m.translation
        split(i, own, child, f"panda_link{i}")
    hand = model.frames[model.getFrameId("panda_hand")]
    split(hand.parentJoint, hand.placement.act(np.array([0.0, -0.08, 0.06])),
          hand.placement.act(np.array([0.0, 0.08, 0.06])), "panda_hand")
    for name in ("panda_leftfinger", "panda_rightfinger"):
        f = model.frames[model.getFrameId(name)]
        split(f.parentJoint, f.placement.act(np.zeros(3)),
              f.placement.act(np.array([0.0, 0.0, 0.054])), name)
    assert len(out) == N_CAPSULES
    return out


def world_segments(model, data, caps, qs):
    """Per state and capsule: world end a (S×C×3), axis d = b − a (S×C×3)."""
    S, C = len(qs), len(caps)
    A, D = np.zeros((S, C, 3)), np.zeros((S, C, 3))
    for s, q in enumerate(qs):
        pin.forwardKinematics(model, data, q)
        for c, cap in enumerate(caps):
            m = data.oMi[cap["joint_index"]]
            a = m.act(np.array(cap["a"]))
            A[s, c] = a
            D[s, c] = m.act(np.array(cap["b"])) - a
    return A, D


def sphere_distances(A, D, rcap, centre, radius):
    """Signed distance of every capsule in every state to one sphere (S×C)."""
    dd = np.maximum((D * D).sum(-1), 1e-24)
    t = np.clip(((centre - A) * D).sum(-1) / dd, 0.0, 1.0)
    x = A + D * t[..., None]
    return np.linalg.norm(x - centre, axis=-1) - rcap - radius


def place_obstacles(A, D, rcap, rng, influence, iters=20000):
    lo, hi = np.array([-0.9, -0.9, -0.1]), np.array([0.9, 0.9, 1.2])

    def draw():
        return rng.uniform(lo, hi), float(rng.uniform(0.03, 0.1))

    def penalty(nearest):
        cnt = (nearest < influence).sum(1)
        return np.where(cnt == 0, 1, np.maximum(cnt - 4, 0)).sum()

    spheres = [draw() for _ in range(N_OBSTACLES)]
    dist = np.stack([sphere_distances(A, D, rcap, c, r) for c, r in spheres], -1)  # S×C×O
    cur = penalty(dist.min(-1))
    for _ in range(iters):
        o = int(rng.integers(N_OBSTACLES))
        c, r = draw()
        old = dist[..., o].copy()
        dist[..., o] = sphere_distances(A, D, rcap, c, r)
        p = penalty(dist.min(-1))
        if p <= cur:
            cur, spheres[o] = p, (c, r)
        else:
            dist[..., o] = old
    cnt = (dist.min(-1) < influence).sum(1)
    return spheres, cnt


def write_text(path, P, model):
    """problem.txt: one keyword per line, then numbers (task_bench.cpp reads it)."""
    g, rep = P["gains"], P["gains"]["repulsion"]
    L = ["rl-task-bench-problem 1",
         f"nv {model.nv} states {len(P['states'])} capsules {len(P['capsules'])}"
         f" obstacles {len(P['obstacles'])}",
         f"tool {P['tool']}"]
    nums = lambda xs: " ".join(repr(float(x)) for x in xs)  # noqa: E731
    L.append("gains " + nums(g["stiffness"] + [g["damping_ratio"], g["max_position_error"],
                                               g["max_orientation_error"], g["posture_stiffness"],
                                               g["posture_damping_ratio"], g["limit_band"],
                                               g["limit_stiffness"]] + g["clamp"]
                             + [rep["influence"], rep["margin"], rep["gain"], rep["damping"],
                                rep["max_acceleration"], rep["max_contacts"]]))
    t = P["target"]
    L.append("target " + nums(t["translation"] + t["rotation"]))
    L.append("posture " + nums(P["posture"]))
    for s in P["states"]:
        L.append("state " + nums(s["q"] + s["qd"]))
    for c in P["capsules"]:
        L.append(f"capsule {c['joint']} " + nums(c["a"] + c["b"] + [c["radius"]]))
    for o in P["obstacles"]:
        L.append("obstacle " + nums(o["center"] + [o["radius"]]))
    with open(path, "w") as f:
        f.write("\n".join(L) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("urdf")
    ap.add_argument("out_dir")
    ap.add_argument("--states", type=int, default=64)
    ap.add_argument("--seed", type=int, default=20270127)
    a = ap.parse_args()
    os.makedirs(a.out_dir, exist_ok=True)
    urdf = os.path.join(a.out_dir, "panda.urdf")
    write_urdf(a.urdf, urdf)
    model = pin.buildModelFromUrdf(urdf)
    model.gravity.linear = np.array(GRAVITY)
    if model.nv != 7 or model.nq != 7:
        sys.exit(f"gen_problem: expected a 7-DoF arm, got nq {model.nq} nv {model.nv}")
    data = model.createData()
    rng = np.random.default_rng(a.seed)

    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    states = [{"q": rng.uniform(lo, hi).tolist(), "qd": rng.uniform(-1.0, 1.0, 7).tolist()}
              for _ in range(a.states)]
    fid = model.getFrameId(TOOL)
    pin.framesForwardKinematics(model, data, np.array(READY))
    x = data.oMf[fid]
    target = {"translation": (x.translation + np.array(OFFSET)).tolist(),
              "rotation": x.rotation.reshape(-1).tolist()}  # row-major

    caps = capsules(model, rng)
    A, D = world_segments(model, data, caps, [np.array(s["q"]) for s in states])
    rcap = np.array([c["radius"] for c in caps])
    spheres, cnt = place_obstacles(A, D, rcap, rng, GAINS["repulsion"]["influence"])
    obstacles = [{"center": c.tolist(), "radius": r} for c, r in spheres]

    P = {"format": FORMAT, "seed": a.seed, "source_urdf": os.path.abspath(a.urdf),
         "urdf": os.path.abspath(urdf), "tool": TOOL, "gravity": GRAVITY,
         "joints": list(model.names[1:]), "gains": GAINS, "target": target,
         "posture": READY, "states": states, "capsules": caps, "obstacles": obstacles,
         "capsules_within_influence": cnt.tolist()}
    with open(os.path.join(a.out_dir, "problem.json"), "w") as f:
        json.dump(P, f, indent=1)
    write_text(os.path.join(a.out_dir, "problem.txt"), P, model)
    model.saveToText(os.path.join(a.out_dir, "panda.pinmodel"))
    ok = int(((cnt >= 1) & (cnt <= 4)).sum())
    print(f"gen_problem: {a.states} states; capsules within influence per state: "
          f"{ok} states with 1-4, min {cnt.min()}, median {int(np.median(cnt))}, "
          f"max {cnt.max()}", file=sys.stderr)


if __name__ == "__main__":
    main()
