"""The Model API: loading (URDF, RL's rlmdl and rlkin), names and limits, configurations, IK,
batched calls; errors with the same what-and-where as the `rl` tool's (compared with the tool
itself when it is built, target/release/rl), and results equal to `rl model eval`'s."""

import json
import os
import subprocess

import numpy as np
import pytest

import rlrs
from conftest import DATA, ROOT, close


def rl_tool():
    """The `rl` binary of this checkout (scripts/test builds it before the Python tests)."""
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    path = os.environ.get("RL_BIN", os.path.join(target, "release", "rl"))
    if not os.access(path, os.X_OK):
        pytest.skip(f"SKIPPED: no rl tool at {path} (cargo build --release --bin rl)")
    return path


def tool(*args):
    return subprocess.run([rl_tool(), *args], capture_output=True, text=True, timeout=60)


PUMA = os.path.join(DATA, "rlmdl", "unimation-puma560.xml")
PUMA_KIN = os.path.join(DATA, "rlkin", "unimation-puma560.xml")


def test_rl_xml_models_equal_rl_model_eval():
    for path in (PUMA, os.path.join(DATA, "rlmdl", "kuka-lbr-iiwa-7-r800.xml")):
        m = rlrs.load(path)
        assert m.format == "rlmdl" and m.nq == m.nv and m.capacity == 16
        q = m.random_configuration(seed=9)
        rng = np.random.default_rng(2)
        v, a = rng.uniform(-1, 1, (2, m.nv))
        fmt = lambda x: ",".join(repr(float(y)) for y in x)
        out = tool("model", "eval", path, "--q", fmt(q), "--qd", fmt(v), "--qdd", fmt(a))
        assert out.returncode == 0, out.stderr
        ev = json.loads(out.stdout)
        close(m.rnea(q, v, a), ev["tau"], 1e-12, "tau")
        close(m.crba(q), ev["mass_matrix"], 1e-12, "mass matrix")
        close(m.gravity(q), ev["gravity"], 1e-12, "gravity")
        close(m.coriolis(q, v), ev["coriolis"], 1e-12, "coriolis")
        for t in ev["tools"]:
            close(m.fk(q, t["name"])[:3, 3], t["position"], 1e-12, "tool position")
            close(m.jacobian(q, t["name"]), t["jacobian"], 1e-12, "tool jacobian")


def test_rlkin_is_kinematics_only():
    m = rlrs.load(PUMA_KIN)
    assert m.format == "rlkin" and m.nq == 6
    assert any("kinematics only" in w for w in m.warnings)
    q = m.random_configuration(seed=1)
    # The same arm as the rlmdl file: the tool frame ends at the same place.
    full = rlrs.load(PUMA)
    close(m.fk(q, m.frames[0]), full.fk(q, full.frames[0]), 1e-9, "puma rlkin vs rlmdl")
    with pytest.raises(rlrs.ModelError, match="mass matrix cannot be factorised: joint"):
        m.aba(q, np.zeros(6), np.zeros(6))


def test_load_errors_say_what_and_where_as_the_tool(tmp_path):
    broken = tmp_path / "broken.urdf"
    broken.write_text('<robot name="b"><link name="a"/><joint name="j" type="revolute">'
                      '<parent link="a"/><child link="nope"/><axis xyz="0 0 1"/>'
                      '<limit lower="-1" upper="1" velocity="1" effort="1"/></joint></robot>')
    with pytest.raises(rlrs.LoadError) as e:
        rlrs.load(broken)
    assert str(e.value) == f'{broken}:1:33: <joint "j">: reference to "nope", which does not exist'
    out = tool("model", "info", str(broken))
    assert out.returncode == 2 and str(e.value) in out.stderr, out.stderr
    with pytest.raises(rlrs.LoadError, match="No such file"):
        rlrs.load(tmp_path / "missing.urdf")
    with pytest.raises(ValueError, match="joint_order"):
        rlrs.load(PUMA, joint_order="alphabetical")


def test_call_errors(robot_data):
    solo = rlrs.load(os.path.join(robot_data, "robots/solo_description/robots/solo12.urdf"),
                     floating_base=True)
    assert (solo.nq, solo.nv) == (19, 18) and solo.joint_names[0] == "root_joint"
    q = solo.neutral()
    z = np.zeros(solo.nv)
    q[3:7] = [0.0, 0.0, 0.0, 2.0]
    with pytest.raises(rlrs.ModelError) as e:
        solo.rnea(q, z, z)
    ours = str(e.value)
    fmt = ",".join(repr(float(x)) for x in q)
    out = tool("model", "eval", os.path.join(robot_data, "robots/solo_description/robots/solo12.urdf"),
               "--floating-base", "--q", fmt)
    # The tool names its flag (--q), the module its argument (q); the rest is the same.
    assert out.returncode == 2 and ours.split(" (Model.normalize")[0] in out.stderr.replace("--q", "q"), (ours, out.stderr)
    close(solo.normalize(q)[3:7], [0, 0, 0, 1], 0, "normalize")
    Q = np.tile(solo.neutral(), (3, 1))
    Q[2, 3:7] = 0.0
    with pytest.raises(rlrs.ModelError, match="^state 2: q: elements 3..6"):
        solo.gravity(Q)
    with pytest.raises(ValueError, match=r"q: shape \(18,\), expected \(19,\) or \(batch, 19\)"):
        solo.gravity(z)
    with pytest.raises(ValueError, match=r"v: shape \(4, 18\) does not match the other arguments \(3 states\)"):
        solo.rnea(Q, np.zeros((4, 18)), np.zeros((3, 18)))
    with pytest.raises(KeyError, match="no frame \"nope\""):
        solo.jacobian(solo.neutral(), "nope")
    # Lists and other dtypes are converted; strided views too.
    assert np.array_equal(solo.gravity(list(solo.neutral())), solo.gravity(solo.neutral()))
    wide = np.zeros((2, 38))
    wide[:, ::2] = np.tile(solo.neutral(), (2, 1))
    assert np.array_equal(solo.gravity(wide[:, ::2])[1], solo.gravity(solo.neutral()))


def test_configurations_limits_and_ik(robot_data):
    ur5 = rlrs.load(os.path.join(robot_data, "robots/ur_description/urdf/ur5_robot.urdf"))
    assert ur5.nq == ur5.nv == 6 and "tool0" in ur5.frames and ur5.name == "ur5"
    lo, hi = ur5.lower_limits, ur5.upper_limits
    Q = ur5.random_configuration(1000, seed=5)
    assert Q.shape == (1000, 6) and np.all((Q >= lo) & (Q <= hi))
    assert np.array_equal(Q, ur5.random_configuration(1000, seed=5))
    assert not np.array_equal(Q, ur5.random_configuration(1000, seed=6))
    assert np.all(ur5.velocity_limits > 0) and np.all(ur5.effort_limits > 0)
    close(ur5.integrate(Q[0], np.ones(6), 0.5), Q[0] + 0.5, 1e-15, "integrate")
    target = ur5.fk(Q[1], "tool0")
    q = ur5.ik("tool0", target, q0=Q[2], seed=1)
    close(ur5.fk(q, "tool0"), target, 1e-6, "ik pose")
    p = ur5.ik("tool0", target[:3, 3], q0=Q[2])
    close(ur5.fk(p, "tool0")[:3, 3], target[:3, 3], 1e-6, "ik position")
    far = target.copy()
    far[:3, 3] = [5.0, 0.0, 0.0]
    with pytest.raises(rlrs.IkError) as e:
        ur5.ik("tool0", far, max_iterations=300)
    assert e.value.q.shape == (6,) and e.value.residual > 3.0
    kinova = rlrs.load(os.path.join(robot_data, "robots/kinova_description/robots/kinova.urdf"),
                       joint_order="pinocchio")
    # Pinocchio stores continuous joints as (cos, sin).
    n_cont = sum(kinova.wraparound)
    qp = []
    angles = np.linspace(-1, 1, kinova.nq)
    for x, wraps in zip(angles, kinova.wraparound):
        qp += [np.cos(x), np.sin(x)] if wraps else [x]
    assert n_cont > 0 and len(qp) == kinova.nq + n_cont
    close(kinova.q_from_pinocchio(qp), angles, 1e-15, "q_from_pinocchio")


def test_threads_setting():
    n = rlrs.threads()
    assert n >= 1
    rlrs.set_threads(1)
    try:
        assert rlrs.threads() == 1
        m = rlrs.load(PUMA)
        Q = m.random_configuration(2000, seed=1)
        one = m.gravity(Q)
    finally:
        rlrs.set_threads(0)
    assert np.array_equal(one, m.gravity(Q))
