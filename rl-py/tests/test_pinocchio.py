"""Kinematics and dynamics equal to Pinocchio's (PyPI `pin` 4.1) to 1e-9, on robots of
example-robot-data, through the Python API: the same URDF loaded by both, the same random
states, every frame's pose and Jacobian, RNEA, ABA, CRBA, gravity, nonlinear effects, Coriolis,
the analytical derivatives of RNEA, ABA and gravity (also against central differences); and
batched calls equal to the single ones."""

import os

import numpy as np
import pytest

import rlrs
from conftest import close

pin = pytest.importorskip("pinocchio", reason="SKIPPED: PyPI pin is not installed")

TOL = 1e-9

# name, URDF under example-robot-data, free-flyer base, mimic joints followed, joints locked at 0
ROBOTS = [
    ("ur5", "robots/ur_description/urdf/ur5_robot.urdf", False, False, []),
    ("panda_mimic", "robots/panda_description/urdf/panda.urdf", False, True, []),
    ("panda_arm", "robots/panda_description/urdf/panda.urdf", False, False,
     ["panda_finger_joint1", "panda_finger_joint2"]),
    ("kinova", "robots/kinova_description/robots/kinova.urdf", False, False, []),
    ("solo12", "robots/solo_description/robots/solo12.urdf", True, False, []),
    ("talos_reduced", "robots/talos_data/robots/talos_reduced.urdf", True, False, []),
    ("tiago_dual", "robots/tiago_description/robots/tiago_dual.urdf", False, False, []),
]
STATES = {"tiago_dual": 3}


def pinocchio_model(path, floating, mimic, lock, gravity):
    if floating:
        pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer(), mimic=mimic)
    else:
        pm = pin.buildModelFromUrdf(path, mimic=mimic)
    if lock:
        pm = pin.buildReducedModel(pm, [pm.getJointId(j) for j in lock], pin.neutral(pm))
    pm.gravity = pin.Motion(np.asarray(gravity), np.zeros(3))
    return pm


def pin_q(pm, rng):
    """A random configuration of Pinocchio's within the limits, [-1, 1] where there are none
    (Pinocchio's free-flyer translations are bounded by ±DBL_MAX)."""
    lo, hi = pm.lowerPositionLimit.copy(), pm.upperPositionLimit.copy()
    unbounded = ~(np.isfinite(lo) & np.isfinite(hi)) | (np.abs(lo) > 1e6) | (np.abs(hi) > 1e6)
    lo[unbounded], hi[unbounded] = -1.0, 1.0
    np.random.seed(int(rng.integers(1 << 31)))
    return pin.randomConfiguration(pm, lo, hi)


def forward_dynamics(pm, pd, q, v, tau, mimic):
    """Pinocchio's ABA; M⁻¹ (tau − nle) where Pinocchio 4.1's ABA refuses mimic joints."""
    if not mimic:
        return pin.aba(pm, pd, q, v, tau).copy()
    M = np.array(pin.crba(pm, pd, q))
    M = np.triu(M) + np.triu(M, 1).T
    return np.linalg.solve(M, tau - pin.nonLinearEffects(pm, pd, q, v))


@pytest.mark.parametrize("name,urdf,floating,mimic,lock", ROBOTS, ids=[r[0] for r in ROBOTS])
def test_equal_to_pinocchio(robot_data, name, urdf, floating, mimic, lock):
    path = os.path.join(robot_data, urdf)
    m = rlrs.load(path, floating_base=floating, joint_order="pinocchio",
                  mimic="follow" if mimic else "independent",
                  locked_joints={j: 0.0 for j in lock})
    pm = pinocchio_model(path, floating, mimic, lock, m.gravity_vector)
    pd = pm.createData()
    assert (m.nv, m.nq) == (pm.nv, m.nq)
    frames = [f for f in m.frames if pm.existFrame(f, pin.FrameType.BODY)]
    assert len(frames) >= len(m.frames) - 1, f"{name}: frames Pinocchio lacks: {set(m.frames) - set(frames)}"
    rng = np.random.default_rng(7)
    for k in range(STATES.get(name, 10)):
        what = f"{name} state {k}"
        qp = pin_q(pm, rng)
        q = m.q_from_pinocchio(qp)
        v = rng.uniform(-1, 1, m.nv)
        a = rng.uniform(-1, 1, m.nv)
        tau_p = pin.rnea(pm, pd, qp, v, a).copy()
        close(m.rnea(q, v, a), tau_p, TOL, f"{what}: rnea")
        M = np.array(pin.crba(pm, pd, qp))
        M = np.triu(M) + np.triu(M, 1).T
        close(m.crba(q), M, TOL, f"{what}: crba")
        g = pin.computeGeneralizedGravity(pm, pd, qp).copy()
        close(m.gravity(q), g, TOL, f"{what}: gravity")
        nle = pin.nonLinearEffects(pm, pd, qp, v).copy()
        close(m.nle(q, v), nle, TOL, f"{what}: nle")
        close(m.coriolis(q, v), nle - g, TOL, f"{what}: coriolis")
        tau_in = g + np.diag(M) * rng.uniform(-1, 1, m.nv)
        close(m.aba(q, v, tau_in), forward_dynamics(pm, pd, qp, v, tau_in, mimic), TOL,
              f"{what}: aba")
        pin.framesForwardKinematics(pm, pd, qp)
        poses = m.fk(q)
        for f in frames:
            fid = pm.getFrameId(f, pin.FrameType.BODY)
            close(poses[f], pd.oMf[fid].homogeneous, TOL, f"{what}: fk {f}")
        for f in frames[:4] + frames[-2:]:
            fid = pm.getFrameId(f, pin.FrameType.BODY)
            J = pin.computeFrameJacobian(pm, pd, qp, fid, pin.LOCAL_WORLD_ALIGNED)
            close(m.jacobian(q, f), J, TOL, f"{what}: jacobian {f}")


def test_batches_equal_single_calls(robot_data):
    """A batch runs the same code as single calls on its own workspace: the same bits."""
    m = rlrs.load(os.path.join(robot_data, "robots/solo_description/robots/solo12.urdf"),
                  floating_base=True)
    rng = np.random.default_rng(3)
    Q = m.random_configuration(50, seed=11)
    V, A = rng.uniform(-1, 1, (2, 50, m.nv))
    T = m.rnea(Q, V, A)
    assert T.shape == (50, m.nv)
    for i in range(50):
        assert np.array_equal(T[i], m.rnea(Q[i], V[i], A[i]))
    assert np.array_equal(m.aba(Q, V, T)[7], m.aba(Q[7], V[7], T[7]))
    assert np.array_equal(m.crba(Q)[3], m.crba(Q[3]))
    assert np.array_equal(m.gravity(Q)[9], m.gravity(Q[9]))
    assert np.array_equal(m.nle(Q, V)[2], m.nle(Q[2], V[2]))
    assert np.array_equal(m.jacobian(Q, "FL_FOOT")[5], m.jacobian(Q[5], "FL_FOOT"))
    batch = m.fk(Q)
    one = m.fk(Q[4])
    assert set(batch) == set(one) == set(m.frames)
    for f in m.frames:
        assert batch[f].shape == (50, 4, 4)
        assert np.array_equal(batch[f][4], one[f])
    assert np.array_equal(m.fk(Q, "HR_FOOT")[4], one["HR_FOOT"])


DERIVATIVE_ROBOTS = [r for r in ROBOTS if r[0] in ("ur5", "panda_arm", "kinova", "solo12", "talos_reduced")]


@pytest.mark.parametrize("name,urdf,floating,mimic,lock", DERIVATIVE_ROBOTS,
                         ids=[r[0] for r in DERIVATIVE_ROBOTS])
def test_derivatives_equal_to_pinocchio(robot_data, name, urdf, floating, mimic, lock):
    """∂τ/∂q, ∂τ/∂q̇, M (computeRNEADerivatives), ∂q̈/∂q, ∂q̈/∂q̇, M⁻¹ (computeABADerivatives)
    and ∂g/∂q (computeGeneralizedGravityDerivatives) to 1e-9, in Pinocchio's tangent space
    (free-flyer bases included), on the same random states; a batch equal to single calls."""
    path = os.path.join(robot_data, urdf)
    m = rlrs.load(path, floating_base=floating, joint_order="pinocchio",
                  mimic="independent", locked_joints={j: 0.0 for j in lock})
    pm = pinocchio_model(path, floating, mimic, lock, m.gravity_vector)
    pd = pm.createData()
    rng = np.random.default_rng(11)
    Q, V, A = [], [], []
    for k in range(5):
        what = f"{name} state {k}"
        qp = pin_q(pm, rng)
        q = m.q_from_pinocchio(qp)
        v = rng.uniform(-1, 1, m.nv)
        a = rng.uniform(-1, 1, m.nv)
        Q.append(q), V.append(v), A.append(a)
        theirs = [np.array(x) for x in pin.computeRNEADerivatives(pm, pd, qp, v, a)]
        theirs[2] = np.triu(theirs[2]) + np.triu(theirs[2], 1).T
        for label, ours, t in zip(("dtau_dq", "dtau_dv", "M"), m.rnea_derivatives(q, v, a), theirs):
            close(ours, t, TOL, f"{what}: rnea_derivatives {label}")
        tau = m.rnea(q, v, a)
        theirs = [np.array(x) for x in pin.computeABADerivatives(pm, pd, qp, v, tau)]
        theirs[2] = np.triu(theirs[2]) + np.triu(theirs[2], 1).T
        for label, ours, t in zip(("ddq_dq", "ddq_dv", "Minv"), m.aba_derivatives(q, v, tau), theirs):
            close(ours, t, TOL, f"{what}: aba_derivatives {label}")
        dg = np.array(pin.computeGeneralizedGravityDerivatives(pm, pd, qp))
        close(m.gravity_derivatives(q), dg, TOL, f"{what}: gravity_derivatives")
    Q, V, A = np.array(Q), np.array(V), np.array(A)
    batch = m.rnea_derivatives(Q, V, A)
    assert all(x.shape == (5, m.nv, m.nv) for x in batch)
    for i in range(5):
        one = m.rnea_derivatives(Q[i], V[i], A[i])
        assert all(np.array_equal(b[i], o) for b, o in zip(batch, one))
    T = m.rnea(Q, V, A)
    batch = m.aba_derivatives(Q, V, T)
    assert all(np.array_equal(b[2], o) for b, o in zip(batch, m.aba_derivatives(Q[2], V[2], T[2])))
    assert np.array_equal(m.gravity_derivatives(Q)[4], m.gravity_derivatives(Q[4]))


def test_derivatives_agree_with_central_differences(robot_data):
    """Independent of Pinocchio: ∂τ/∂q and ∂τ/∂q̇ against central differences of rnea, and
    ∂q̈/∂q̇ against those of aba (the UR5, 1e-6)."""
    m = rlrs.load(os.path.join(robot_data, "robots/ur_description/urdf/ur5_robot.urdf"))
    rng = np.random.default_rng(5)
    q = m.random_configuration(1, seed=3)[0]
    v, a = rng.uniform(-1, 1, (2, m.nv))
    dq, dv, _ = m.rnea_derivatives(q, v, a)
    h = 1e-6
    for j in range(m.nv):
        e = np.zeros(m.nv)
        e[j] = h
        col_q = (m.rnea(m.integrate(q, e), v, a) - m.rnea(m.integrate(q, -e), v, a)) / (2 * h)
        col_v = (m.rnea(q, v + e, a) - m.rnea(q, v - e, a)) / (2 * h)
        close(dq[:, j], col_q, 1e-6, f"dtau_dq column {j}")
        close(dv[:, j], col_v, 1e-6, f"dtau_dv column {j}")
    tau = m.rnea(q, v, a)
    _, ddv, minv = m.aba_derivatives(q, v, tau)
    for j in range(m.nv):
        e = np.zeros(m.nv)
        e[j] = h
        close(ddv[:, j], (m.aba(q, v + e, tau) - m.aba(q, v - e, tau)) / (2 * h), 1e-6,
              f"ddq_dv column {j}")
    close(minv, np.linalg.inv(m.crba(q)), 1e-9, "Minv is M⁻¹")
