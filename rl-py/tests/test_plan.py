"""MotionBenchMaker problems (VAMP's problem sets, tests/data/mbm: the first problem of each of
the seven scenarios, Panda and UR5) solved from Python: every path starts and ends where the
request says, every waypoint is collision-free in an rl-sg scene built independently of the
planner, and (Panda) every edge is certified on the exact meshes by conservative advancement.
UR5's certification takes 10-40 s per path here (its meshes are large; about 1000 distance
queries per path), too long for CI: `rl plan` and rl-plan's own tests certify it."""

import glob
import os

import numpy as np
import pytest

import rlrs
from conftest import DATA

MBM = os.path.join(DATA, "mbm")


# VAMP's RRT-Connect range per robot (rl-plan/tests/mbm.rs uses the same).
RANGE = {"panda": 1.0, "ur5": 1.5}
CERTIFY = {"panda": True, "ur5": False}


@pytest.mark.parametrize("robot", ["panda", "ur5"])
def test_motionbenchmaker_problems_are_solved_and_certified(robot):
    urdf = os.path.join(MBM, robot, f"{robot}.urdf")
    planner = rlrs.Planner(urdf)
    problems = sorted(glob.glob(os.path.join(MBM, robot, "problems", "*", "request0001.yaml")))
    assert len(problems) == 7
    for request in problems:
        scene = request.replace("request0001", "scene0001")
        name = os.path.basename(os.path.dirname(request))
        r = planner.plan(scene, request, seed=1, time=5.0, range=RANGE[robot],
                         certify=CERTIFY[robot])
        assert r.solved, name
        start, goal = planner.request(request)
        assert r.path.shape[1] == planner.nq == len(r.joint_names)
        assert np.allclose(r.path[0], start, atol=1e-12) and np.allclose(r.path[-1], goal, atol=1e-12), name
        assert r.length <= r.raw_length + 1e-12, name
        c = r.certificate
        if CERTIFY[robot]:
            assert c["certified"] and c["edges_certified"] == c["edges"] == len(r.path) - 1, (name, c)
            assert c["min_distance"] >= c["margin"], (name, c)
        else:
            assert c is None
        assert np.all(planner.is_valid(r.path, scene)), name
        world = rlrs.Scene(urdf, env=scene, srdf=urdf.replace(".urdf", ".srdf"))
        assert not np.any(world.is_colliding(r.path)), name
        assert np.all(world.distance(r.path) > 0.0), name


def test_plan_from_start_and_goal_and_errors():
    urdf = os.path.join(MBM, "panda", "panda.urdf")
    problem = os.path.join(MBM, "panda", "problems", "table_pick_panda")
    scene = os.path.join(problem, "scene0001.yaml")
    planner = rlrs.Planner(urdf)
    start, goal = planner.request(os.path.join(problem, "request0001.yaml"))
    a = planner.plan(scene, start=start, goal=goal, seed=3, checker="exact")
    b = rlrs.plan(urdf, scene, os.path.join(problem, "request0001.yaml"), seed=3, checker="exact")
    assert a.solved and b.solved
    assert np.array_equal(a.path, b.path), "the same seed gives the same path"
    cert = planner.certify(a.path, scene)
    assert cert["certified"]
    # A goal in collision (a configuration the scene refuses) is a PlanError naming it.
    model = rlrs.load(urdf, mimic="independent")
    assert model.joint_names == planner.joint_names
    candidates = model.random_configuration(200, seed=4)
    colliding = candidates[~planner.is_valid(candidates, scene)][0]
    with pytest.raises(rlrs.PlanError, match="goal"):
        planner.plan(scene, start=start, goal=colliding)
    with pytest.raises(ValueError, match="checker"):
        planner.plan(scene, start=start, goal=goal, checker="vamp")

