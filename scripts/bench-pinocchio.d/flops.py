"""Floating-point operation counts of rl-core's algorithms, for the "physical limit" line of
scripts/bench-pinocchio: flops per call over the measured time, as a fraction of the CPU's peak.

Counted from the operations in rl-core's source (one flop per addition, subtraction,
multiplication or division; a fused multiply-add counts two; sin/cos of a revolute joint 30, the
fdlibm kernels' polynomial work), per body and per pair of coordinates where an algorithm walks
the tree, for the joint kinds of the benchmark robots. An estimate within about 20 %: it follows
the code's structure (what each sweep computes per body), not the instructions the compiler
emitted, and counts no loads, stores, shuffles or branches, so it is a lower bound on the work.

Input: the <robot>.tree.json that gen_states.py writes (joints in Pinocchio order: parent,
kind, nv).
"""

# Primitive costs (flops), as implemented in rl-core/src/spatial and rl-core/src/joint.
SINCOS = 30
MAT3_VEC3 = 15            # 9 mul + 6 add
MAT3_MAT3 = 45
CROSS = 9                 # 6 mul + 3 sub
DOT3 = 5
DOT6 = 11                 # motion · force
ADD6 = 6
SCALE6 = 6
CROSS_MOTION = 30         # ω×ω', ω×v' + v×ω'
CROSS_FORCE = 30
ACT = 2 * MAT3_VEC3 + CROSS + 3            # act_motion / act_force / inverse: 42
RBI_MUL = MAT3_VEC3 + CROSS + 3 + 3 + CROSS + 3   # rigid inertia × motion: 42
ABI_MUL = 4 * MAT3_VEC3 + 6                # articulated inertia × motion: 66
COMPOSE = MAT3_MAT3 + MAT3_VEC3 + 3        # X_parent * X: 63
WORLD_INERTIA = 120       # rotate about the centre of mass (33 mul + adds), parallel axis shift
INERTIA_TO_PARENT = 126   # transform_to_parent of a rigid inertia
RBI_ADD = 13
ABI_ADD = 27
RANK_ONE = 63             # Iᴬ −= u uᵀ/d on the three 3×3 blocks


def placed(j):
    """placement · X_J(q) of one joint."""
    k = j["kind"]
    if k == "revolute":
        return SINCOS + 18          # two columns turned
    if k == "revolute_unaligned":
        return SINCOS + 24 + MAT3_MAT3
    if k == "prismatic":
        return 3 + MAT3_VEC3 + 3
    if k == "free":
        return 30 + (COMPOSE if j["placed"] else 0)   # quaternion → matrix
    raise ValueError(k)


def subspace_world(j):
    """The joint's motion subspace columns in world coordinates (act_subspace)."""
    if j["kind"] in ("revolute", "revolute_unaligned"):
        return MAT3_VEC3 + CROSS
    if j["kind"] == "prismatic":
        return MAT3_VEC3
    return j["nv"] * ACT


def ancestors(tree, i):
    out, p = [], tree[i]["parent"]
    while p >= 0:
        out.append(p)
        p = tree[p]["parent"]
    return out


def counts(tree, tool_joint):
    """Flops per call of each algorithm of the benchmark table; `tool_joint` is the index of the
    joint that carries the Jacobian's frame."""
    for k, j in enumerate(tree):
        j["_i"] = k
    n = sum(j["nv"] for j in tree)
    anc_dofs = [sum(tree[a]["nv"] for a in ancestors(tree, i)) for i in range(len(tree))]
    pose = [placed(j) + (COMPOSE if j["parent"] >= 0 else 0) for j in tree]
    fk = sum(pose)

    branch = [tool_joint] + ancestors(tree, tool_joint)
    jac = sum(pose[i] for i in branch) + MAT3_VEC3 + 3 + sum(
        tree[i]["nv"] * (subspace_world(tree[i]) // tree[i]["nv"] + CROSS + 3) for i in branch)

    def rnea_body(j, with_qdd):
        nv = j["nv"]
        jm = 3 if nv == 1 else 12 * nv     # S q̇ (joint_motion)
        c = placed(j) + ACT + (jm + ADD6 if with_qdd else 0)
        c += jm + ACT + ADD6 + CROSS_MOTION + ADD6 + 2 * RBI_MUL + CROSS_FORCE + ADD6
        return c + (DOT3 if nv == 1 else nv * DOT6) + ACT + ADD6

    rnea = sum(rnea_body(j, True) for j in tree)
    nle = sum(rnea_body(j, False) for j in tree)
    gravity = sum(placed(j) + MAT3_VEC3 + CROSS + 3 + (DOT3 if j["nv"] == 1 else j["nv"] * DOT6)
                  + MAT3_VEC3 + 7 for j in tree)
    crba = sum(placed(j) + j["nv"] * (24 + DOT3) + INERTIA_TO_PARENT + RBI_ADD for j in tree)
    # Each DOF's force walks up its ancestors: one force transform per ancestor body, one dot
    # per ancestor DOF.
    crba += sum(j["nv"] * (len(ancestors(tree, i)) * ACT + anc_dofs[i] * DOT3)
                for i, j in enumerate(tree))

    def aba_body(j):
        nv = j["nv"]
        p1 = pose[j["_i"]] + subspace_world(j) + 12 * nv + ADD6 + CROSS_MOTION \
            + WORLD_INERTIA + RBI_MUL + CROSS_FORCE
        if nv == 1:
            p2 = ABI_MUL + DOT6 + 1 + DOT6 + 1 + RANK_ONE + ABI_MUL + 3 * ADD6 + 7 + ABI_ADD
            p3 = ADD6 + DOT6 + 2 + 12
        else:
            p2 = nv * (ABI_MUL + DOT6 + 1) + nv * nv * DOT6 + 150 + nv * (nv * 14 + 2 * 27) \
                + ABI_MUL + 2 * ADD6 + ABI_ADD
            p3 = ADD6 + nv * (DOT6 + 1) + nv * (2 * nv + 12)
        return p1 + p2 + p3

    aba = sum(aba_body(j) for j in tree)

    # RNEA derivatives (rl-core/src/algo/rnea_derivatives.rs): forward and backward per body,
    # per own coordinate, per pair (own coordinate, ancestor coordinate).
    def drnea_body(i, j, with_m):
        nv = j["nv"]
        fwd = pose[i] + subspace_world(j) + 24 * nv + ADD6 + 2 * ADD6 + CROSS_MOTION \
            + nv * (CROSS_MOTION + 2 * CROSS_MOTION + ADD6 + ADD6 + CROSS_MOTION) \
            + WORLD_INERTIA + 2 * RBI_MUL + CROSS_FORCE + ADD6 + 90
        own = nv * ((RBI_MUL if with_m else 0) + 2 * (RBI_MUL + 27 + ADD6)) \
            + nv * nv * (2 + with_m) * DOT6 + nv * (DOT6 + 30 + CROSS_FORCE + ADD6)
        pairs = nv * anc_dofs[i] * (2 * (DOT6 + DOT3 + 1) + (2 + with_m) * DOT6)
        return fwd + own + pairs + RBI_ADD + 9 + 3 + ADD6

    drnea = sum(drnea_body(i, j, 1) for i, j in enumerate(tree))
    # ABA derivatives (aba_derivatives.rs): ABA, M⁻¹ (backward walk, forward row updates), the
    # RNEA derivatives' sweeps without M, and −M⁻¹ ∂τ over the nonzeros (2 outputs × 2n flops per
    # pair of related coordinates, both orders, and the own blocks).
    daba = aba + sum(drnea_body(i, j, 0) - pose[i] - subspace_world(j) - WORLD_INERTIA
                     for i, j in enumerate(tree))
    offs, o = [], 0
    for j in tree:
        offs.append(o)
        o += j["nv"]
    for i, j in enumerate(tree):
        nv = j["nv"]
        daba += nv * anc_dofs[i] * (DOT6 + 3 + 6)                     # M⁻¹ backward
        daba += nv * anc_dofs[i] * (DOT6 + 2 + 2 * (n - offs[i]))     # M⁻¹ forward
        daba += (2 * nv * anc_dofs[i] + nv * nv) * 4 * n              # the two products
    return {"fk": fk, "jacobian": jac, "rnea": rnea, "nle": nle, "gravity": gravity,
            "crba": crba, "aba": aba, "drnea": drnea, "daba": daba}
