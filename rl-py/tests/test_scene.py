"""Scene queries from Python equal `rl scene check`'s (the tool, run on the same files): RL's
Puma 560 among boxes (rlsg scene, rlmdl kinematics) and the MotionBenchMaker Panda (URDF, SRDF,
MoveIt scene); batched queries equal single ones."""

import json
import os

import numpy as np
import pytest

import rlrs
from conftest import DATA, close
from test_model import tool

PUMA_SCENE = os.path.join(DATA, "rlsg", "unimation-puma560_boxes.convex.xml")
PUMA_KIN = os.path.join(DATA, "rlmdl", "unimation-puma560.xml")
PANDA = os.path.join(DATA, "mbm", "panda")
PANDA_SCENE = os.path.join(PANDA, "problems", "box_panda", "scene0001.yaml")


def same_as_tool(ours, theirs):
    for key in ("colliding", "self_pairs_checked", "environment_bodies"):
        assert ours[key] == theirs[key], key
    for key in ("collisions", "self_collisions", "environment_collisions"):
        assert [list(p) for p in ours[key]] == theirs[key], key
    for key in ("min_distance", "self_min_distance", "environment_min_distance"):
        a, b = ours[key], theirs.get(key)
        assert (a is None) == (b is None), key
        if a is not None:
            assert (a["a"], a["b"]) == (b["a"], b["b"]), key
            close(a["distance"], b["distance"], 1e-12, key)
            close(a["point_a"], b["point_a"], 1e-12, key)


@pytest.mark.parametrize("case", ["puma", "panda"])
def test_check_equals_rl_scene_check(case):
    if case == "puma":
        scene = rlrs.Scene(PUMA_SCENE, kinematics=PUMA_KIN)
        files = [PUMA_SCENE, "--kinematics", PUMA_KIN]
        model = rlrs.load(PUMA_KIN)
    else:
        urdf = os.path.join(PANDA, "panda.urdf")
        srdf = os.path.join(PANDA, "panda.srdf")
        scene = rlrs.Scene(urdf, env=PANDA_SCENE, srdf=srdf)
        files = [urdf, "--srdf", srdf, "--env", PANDA_SCENE]
        model = rlrs.load(urdf, mimic="independent")
    assert scene.nq == model.nq and len(scene.models) >= 2
    qs = model.random_configuration(4, seed=8)
    for q in [np.zeros(model.nq), *qs]:
        out = tool("scene", "check", *files, "--q", ",".join(repr(float(x)) for x in q))
        assert out.returncode == 0, out.stderr
        theirs = json.loads(out.stdout)
        ours = scene.check(q)
        same_as_tool(ours, theirs)
        assert scene.is_colliding(q) == bool(theirs["environment_collisions"])
        if theirs.get("environment_min_distance"):
            close(scene.distance(q), theirs["environment_min_distance"]["distance"], 1e-12, "distance")
    assert np.array_equal(scene.is_colliding(qs), [scene.is_colliding(q) for q in qs])
    assert np.array_equal(scene.distance(qs, environment=False),
                          [scene.distance(q, environment=False) for q in qs])
    with pytest.raises(ValueError, match="q: shape"):
        scene.check(np.zeros(model.nq + 1))
