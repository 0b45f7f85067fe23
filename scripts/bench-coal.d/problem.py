#!/usr/bin/env python3
"""Turns `rl scene dump` JSON (stdin) into the text problem coal_bench.cpp reads (stdout).

Meshes loaded from files stay file references (coal loads them with its own assimp loader, as
Pinocchio does); other meshes and convex hulls are written out; primitives by their dimensions.
"""
import json
import sys

d = json.load(sys.stdin)
out = [f"shapes {len(d['shapes'])}"]
for s in d["shapes"]:
    k = s["kind"]
    if k == "box":
        out.append("box %r %r %r" % tuple(s["size"]))
    elif k == "sphere":
        out.append("sphere %r" % s["radius"])
    elif k in ("cylinder", "capsule", "cone"):
        out.append("%s %r %r" % (k, s["radius"], s["length"]))
    elif k == "mesh" and "source" in s:
        out.append("meshfile %s %r %r %r" % (s["source"], *s["scale"]))
    elif k in ("mesh", "convex"):
        v, t = s["vertices"], s["triangles"]
        out.append("%s %d %d %s %s" % (k, len(v), len(t), " ".join("%r %r %r" % tuple(p) for p in v),
                                       " ".join("%d %d %d" % tuple(x) for x in t)))
    else:
        sys.exit(f"problem.py: shape kind {k} has no coal equivalent here")
for name in ("self_pairs", "environment_pairs"):
    p = d[name]
    out.append("pairs %s %d %s" % (name, len(p), " ".join("%d %d" % tuple(x) for x in p)))
out.append(f"configs {len(d['configs'])}")
for c in d["configs"]:
    out.append(" ".join("%r %r %r %r %r %r %r" % tuple(p) for p in c["poses"]))
print("\n".join(out))
