"""rl-rs from Python: robot kinematics and dynamics, jerk-limited trajectories, collision
queries and motion planning, and a supervised real-time controller, in Rust, on numpy arrays.

    import numpy as np, rlrs
    ur5 = rlrs.load("ur5_robot.urdf")
    q = ur5.random_configuration()
    tau = ur5.rnea(q, np.zeros(ur5.nv), np.zeros(ur5.nv))
    poses = ur5.fk(q)                      # {frame: 4x4}
    J = ur5.jacobian(q, "tool0")           # (6, nv), [linear; angular], world frame
    taus = ur5.rnea(Q, V, A)               # batches: one state per row, the loop in Rust

See the README's Python section and the type stubs (rlrs/__init__.pyi).
"""

from ._rlrs import *  # noqa: F401,F403
from ._rlrs import __version__  # noqa: F401
