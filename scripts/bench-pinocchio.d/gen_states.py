"""Prepare one robot for scripts/bench-pinocchio: the URDF every library loads and a states file.

Usage (inside the benchmark venv, which has pin and numpy):
  gen_states.py URDF OUT_URDF OUT_STATES --states N --seed S [--floating-base] [--fix J1,J2]

Also writes OUT_STATES with .tree.json (for flops.py) and .pinmodel.txt (the Pinocchio model,
Model::saveToText, for pinocchio_bench.cpp) in place of .states.

OUT_URDF is URDF with the joints of --fix turned into fixed joints (panda's fingers: the same
model as Pinocchio's buildReducedModel at q = 0, see rl-core/tests/data/pinocchio/README.md) and
every <mimic> tag removed (dynibo rejects them; after the fix none is on a moving joint). All
three programs load OUT_URDF, so they time the same model.

OUT_STATES (format "rl-bench-states 1") holds N random states in Pinocchio's joint order and
layout (free-flyer q = [x y z qx qy qz qw], v = [linear; angular] in the base frame):
  rl-bench-states 1
  nq NQ nv NV joints J states N
  joint NAME NQ_J NV_J          (J lines, Pinocchio order, root_joint first when floating)
  state q... v... a...          (N lines, nq + nv + nv numbers)
Draws: 1-DoF joints uniform within their URDF limits (or [-pi, pi] when unlimited), free-flyer
position uniform in [-1, 1]^3 and orientation uniform on SO(3), v and a uniform in [-1, 1].
Seeded numpy PCG64, so the same seed gives the same file on any machine.
"""

import argparse
import math
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

ONE_DOF = {"RX", "RY", "RZ", "RevoluteUnaligned", "PX", "PY", "PZ", "PrismaticUnaligned"}


def short_type(joint):
    return joint.shortname().replace("JointModel", "")


def write_urdf(src, dst, fix):
    tree = ET.parse(src)
    root = tree.getroot()
    found = set()
    for joint in root.iter("joint"):
        for el in joint.findall("mimic"):
            joint.remove(el)
        if joint.get("name") in fix:
            joint.set("type", "fixed")
            found.add(joint.get("name"))
    missing = set(fix) - found
    if missing:
        sys.exit(f"gen_states: {src} has no joint named {', '.join(sorted(missing))}")
    tree.write(dst, xml_declaration=True, encoding="utf-8")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("urdf")
    ap.add_argument("out_urdf")
    ap.add_argument("out_states")
    ap.add_argument("--states", type=int, default=64)
    ap.add_argument("--seed", type=int, default=20261122)
    ap.add_argument("--floating-base", action="store_true")
    ap.add_argument("--fix", default="")
    ap.add_argument("--frame", default="", help="the Jacobian's frame (recorded for flops.py)")
    a = ap.parse_args()

    fix = [j for j in a.fix.split(",") if j]
    write_urdf(a.urdf, a.out_urdf, fix)
    if a.floating_base:
        model = pin.buildModelFromUrdf(a.out_urdf, pin.JointModelFreeFlyer())
    else:
        model = pin.buildModelFromUrdf(a.out_urdf)

    rng = np.random.default_rng(a.seed)
    lines = ["rl-bench-states 1",
             f"nq {model.nq} nv {model.nv} joints {model.njoints - 1} states {a.states}"]
    for j in range(1, model.njoints):
        jm = model.joints[j]
        lines.append(f"joint {model.names[j]} {jm.nq} {jm.nv}")
    for _ in range(a.states):
        q = np.zeros(model.nq)
        for j in range(1, model.njoints):
            jm, t = model.joints[j], short_type(model.joints[j])
            iq = jm.idx_q
            if t == "FreeFlyer":
                q[iq:iq + 3] = rng.uniform(-1.0, 1.0, 3)
                quat = rng.normal(size=4)
                q[iq + 3:iq + 7] = quat / np.linalg.norm(quat)
            elif t in ONE_DOF:
                lo, hi = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
                if not (math.isfinite(lo) and math.isfinite(hi)) or hi - lo > 1e10:
                    lo, hi = -math.pi, math.pi
                q[iq] = rng.uniform(lo, hi)
            else:
                sys.exit(f"gen_states: joint {model.names[j]} has type {t}, not drawn here")
        v = rng.uniform(-1.0, 1.0, model.nv)
        acc = rng.uniform(-1.0, 1.0, model.nv)
        lines.append("state " + " ".join(repr(float(x)) for x in np.concatenate([q, v, acc])))
    with open(a.out_states, "w") as f:
        f.write("\n".join(lines) + "\n")
    # The tree for flops.py: per joint (Pinocchio order) its parent (-1: the world), kind and nv.
    import json
    tree = []
    for j in range(1, model.njoints):
        t = short_type(model.joints[j])
        kind = {"FreeFlyer": "free", "RevoluteUnaligned": "revolute_unaligned",
                "PrismaticUnaligned": "prismatic", "PX": "prismatic", "PY": "prismatic",
                "PZ": "prismatic"}.get(t, "revolute" if t in ONE_DOF else t)
        tree.append({"parent": model.parents[j] - 1, "kind": kind, "nv": model.joints[j].nv,
                     "placed": not model.jointPlacements[j].isIdentity()})
    tool_joint = None
    if a.frame:
        fid = model.getFrameId(a.frame)
        if fid >= model.nframes:
            sys.exit(f"gen_states: no frame named {a.frame}")
        tool_joint = model.frames[fid].parentJoint - 1
    with open(a.out_states[:-len(".states")] + ".tree.json", "w") as f:
        json.dump({"joints": tree, "tool_joint": tool_joint}, f)
    # The model for pinocchio_bench.cpp in Pinocchio's text serialization: the URDF is parsed
    # here, by the same Pinocchio release, so the C++ program needs no precompiled parser.
    model.saveToText(a.out_states[:-len(".states")] + ".pinmodel.txt")


if __name__ == "__main__":
    main()
