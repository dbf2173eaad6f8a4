"""Hand models that compile but that ogcp's hand kinematics do not describe faithfully.

ogcp samples, fits and closes a hand as an open chain of joints, each finger posed joint by joint,
each joint held by the servo that drives it or by a joint equality that ties it to a driver. Two
kinds of hands break that picture, and each gets a one-line
:class:`~ogcp.planner.hands.kinematics.HandModelWarning` rather than results that silently mean
something else:

- **closed chains**: MJCF ``connect`` or ``weld`` equalities between the hand's own bodies (a
  four-bar linkage, as in Menagerie's Robotiq 2F-85). The sampled and fitted poses ignore the loop,
  which MuJoCo enforces when the hand closes.
- **underactuated fingers**: fewer independent servo directions on a finger's joints than the
  joints an equality does not already tie (one tendon servo over two joints, as Menagerie's Shadow
  hand drives J1 and J2). The fit poses every joint; one servo cannot hold that pose.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import NDArray

#: Singular values of a finger's servo moment arms below this fraction of the largest count as none.
RANK_TOLERANCE = 1e-6


def closed_chains(model: mujoco.MjModel, hand_bodies: set[int]) -> list[str]:
    """The active ``connect`` and ``weld`` equalities between two bodies of the hand, as "a-b" names.

    Args:
        model: The hand's compiled model.
        hand_bodies: Ids of the hand's bodies (the palm's tree).
    """
    loops = []
    for e in range(model.neq):
        kind = int(model.eq_type[e])
        if kind not in (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD)) or not model.eq_active0[e]:
            continue
        first, second = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        if int(model.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE):
            first, second = int(model.site_bodyid[first]), int(model.site_bodyid[max(second, 0)])
        if first in hand_bodies and max(second, 0) in hand_bodies:
            names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body {b}" for b in (first, second)]
            loops.append("-".join(names))
    return loops


def underactuated_fingers(
    model: mujoco.MjModel,
    qpos: NDArray[np.float64],
    fingers: Sequence[tuple[str, Sequence[int]]],
    dependent: set[int],
) -> list[str]:
    """The fingers with fewer independent servo directions than free joints, described in words.

    Args:
        model: The hand's compiled model, servos added.
        qpos: A configuration to take the moment arms at (the reference), shape (nq,).
        fingers: Each finger's name and joint ids.
        dependent: Joints an active joint equality ties to a driver (they need no servo).
    """
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_fwdPosition(model, data)
    moments = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(moments, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind)
    found = []
    for name, joints in fingers:
        free = [j for j in joints if j not in dependent]
        if not free:
            continue
        arms = moments[:, model.jnt_dofadr[free]]
        values = np.linalg.svd(arms, compute_uv=False) if arms.size else np.zeros(0)
        rank = int(np.sum(values > RANK_TOLERANCE * values.max())) if values.size and values.max() > 0 else 0
        if rank < len(free):
            joint_names = ", ".join(
                mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint {j}" for j in free
            )
            found.append(f"{name} ({len(free)} joints, {joint_names}; {rank} servo direction{'s' * (rank != 1)})")
    return found
