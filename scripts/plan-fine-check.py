"""The independent fine check of planned paths (issue 29): Pinocchio places the URDF's collision
meshes, coal tests them against each other (the pairs the SRDF leaves checked) and against the
planning scene's obstacles, at every configuration of every edge at most 1/320 rad apart.

  plan-fine-check.py URDF PROBLEMS_DIR PATHS_DIR [--step 0.003125]

PATHS_DIR holds SCENARIO_NNNN.csv paths (rl plan bench --paths): a header of joint names, one
row per waypoint. PROBLEMS_DIR holds SCENARIO/sceneNNNN.yaml (MoveIt planning scenes). Prints
one line per path that touches, and the count. Nothing here is rl-rs code: the models come from
Pinocchio's URDF and SRDF readers, the tests from coal.
"""

import csv
import math
import sys
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import yaml


def as_pose(p):
    # MoveIt YAML poses: position {x,y,z} or [x,y,z]; orientation {x,y,z,w} or [x,y,z,w].
    t, o = p["position"], p["orientation"]
    t = [t["x"], t["y"], t["z"]] if isinstance(t, dict) else t
    o = [o["x"], o["y"], o["z"], o["w"]] if isinstance(o, dict) else o
    q = pin.Quaternion(o[3], o[0], o[1], o[2])
    q.normalize()
    return pin.SE3(q.matrix(), np.array(t, dtype=float))


def obstacles(scene):
    data = yaml.safe_load(open(scene))
    out = []
    for co in data["world"]["collision_objects"]:
        base = as_pose(co["pose"]) if "pose" in co else pin.SE3.Identity()
        for prim, pp in zip(co.get("primitives", []), co.get("primitive_poses", [])):
            d = prim["dimensions"]
            kind = prim["type"]
            if kind == "box":
                shape = coal.Box(d[0], d[1], d[2])
            elif kind == "sphere":
                shape = coal.Sphere(d[0])
            elif kind == "cylinder":
                shape = coal.Cylinder(d[1], d[0])  # MoveIt: [height, radius]
            else:
                raise SystemExit(f"{scene}: primitive {kind}")
            out.append((f"{co['id']}", shape, base * as_pose(pp)))
    return out


def main():
    args = sys.argv[1:]
    step = 1.0 / 320.0
    if "--step" in args:
        i = args.index("--step")
        step = float(args[i + 1])
        del args[i : i + 2]
    if len(args) != 3:
        raise SystemExit(__doc__)
    urdf, problems, paths = Path(args[0]), Path(args[1]), Path(args[2])
    model, geom, _ = pin.buildModelsFromUrdf(str(urdf), package_dirs=[str(urdf.parent)])
    robot_geoms = len(geom.geometryObjects)
    geom.addAllCollisionPairs()
    srdf = urdf.with_suffix(".srdf")
    if srdf.exists():
        pin.removeCollisionPairs(model, geom, str(srdf))
    self_pairs = [(p.first, p.second) for p in geom.collisionPairs]
    files = sorted(paths.glob("*.csv"))
    if not files:
        raise SystemExit(f"no paths in {paths}")
    touching, total = 0, 0
    for f in files:
        scenario, index = f.stem.rsplit("_", 1)
        scene = problems / scenario / f"scene{index}.yaml"
        g = geom.copy()
        g.collisionPairs[:] = []
        for a, b in self_pairs:
            g.addCollisionPair(pin.CollisionPair(a, b))
        for name, shape, placement in obstacles(scene):
            k = g.addGeometryObject(pin.GeometryObject(f"obstacle/{name}", 0, 0, placement, shape))
            for r in range(robot_geoms):
                g.addCollisionPair(pin.CollisionPair(r, k))
        gdata = pin.GeometryData(g)
        data = model.createData()
        rows = list(csv.reader(open(f)))
        names, points = rows[0], [np.array([float(x) for x in r]) for r in rows[1:]]
        index_of = []
        for n in names:
            if not model.existJointName(n):
                raise SystemExit(f"{f}: joint {n} not in {urdf}")
            index_of.append(model.joints[model.getJointId(n)].idx_q)
        q = pin.neutral(model)
        first = None
        for a, b in zip(points, points[1:]):
            n = max(1, math.ceil(np.linalg.norm(b - a) / step))
            for j in range(n + 1):
                x = a + (b - a) * (j / n)
                q[index_of] = x
                if pin.computeCollisions(model, data, g, gdata, q, True):
                    k = next(i for i, r in enumerate(gdata.collisionResults) if r.isCollision())
                    p = g.collisionPairs[k]
                    first = (g.geometryObjects[p.first].name, g.geometryObjects[p.second].name)
                    break
            if first:
                break
        total += 1
        if first:
            touching += 1
            print(f"{f.stem}: touches ({first[0]} / {first[1]})")
    print(f"{touching} of {total} paths touch the meshes (Pinocchio {pin.__version__}, "
          f"coal {coal.__version__ if hasattr(coal, '__version__') else '?'}, every edge at "
          f"{step:.6g} rad)")


if __name__ == "__main__":
    main()
