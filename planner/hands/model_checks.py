"""Hand models that compile but whose servos cannot hold every pose ogcp fits.

ogcp fits every joint of a finger (and of the loops it closes) and holds the fit with the hand's
servos. A finger whose servos span fewer directions than the finger can move in, once its joint
equalities and closed loops are respected, is *underactuated* (one tendon servo over two joints,
as Menagerie's Shadow hand drives J1 and J2): the fit poses every joint, and one servo cannot hold
that pose. It gets a one-line :class:`~ogcp.planner.hands.kinematics.HandModelWarning` rather than
results that silently mean something else.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import NDArray

#: Singular values below this fraction of the largest count as none (servo arms, equality rows).
RANK_TOLERANCE = 1e-6


def equality_jacobian(model: mujoco.MjModel, data: mujoco.MjData) -> NDArray[np.float64]:
    """The active equalities' constraint rows at a state (``mj_fwdPosition`` done), shape (n_eq, nv).

    MuJoCo's own rows: a joint equality, a tendon equality, and a ``connect`` or ``weld`` that closes a
    loop.
    """
    rows = np.flatnonzero(data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    if not len(rows):
        return np.zeros((0, model.nv))
    if mujoco.mj_isSparse(model):
        dense = np.zeros((data.nefc, model.nv))
        mujoco.mju_sparse2dense(dense, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind)
    else:
        dense = np.asarray(data.efc_J[: data.nefc * model.nv]).reshape(data.nefc, model.nv)
    return np.asarray(dense[rows], dtype=float)


def _rank(matrix: NDArray[np.float64]) -> int:
    if not matrix.size:
        return 0
    values = np.linalg.svd(matrix, compute_uv=False)
    return int(np.sum(values > RANK_TOLERANCE * values.max())) if values.max() > 0 else 0


def underactuated_fingers(
    model: mujoco.MjModel,
    qpos: NDArray[np.float64],
    fingers: Sequence[tuple[str, Sequence[int]]],
) -> list[str]:
    """The fingers with fewer independent servo directions than directions of motion, in words.

    A finger moves in the directions its joints' equalities leave free: the null space of their
    rows over its joints and the joints they tie it to (another finger's driver, as a gripper's two
    jaws share one servo); its servos must span their moment arms over those directions.

    Args:
        model: The hand's compiled model, servos added.
        qpos: A configuration to take the moment arms and equality rows at (the reference), shape (nq,).
        fingers: Each finger's name and joint ids.
    """
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_fwdPosition(model, data)
    moments = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(moments, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind)
    equalities = equality_jacobian(model, data)
    found = []
    for name, joints in fingers:
        dofs = _tied_dofs(equalities, model.jnt_dofadr[list(joints)])
        tied = equalities[:, dofs]
        tied = tied[np.abs(tied).max(axis=1) > 0] if len(tied) else tied
        _, values, basis = np.linalg.svd(tied) if len(tied) else (None, np.zeros(0), np.eye(len(dofs)))
        kept = int(np.sum(values > RANK_TOLERANCE * values.max())) if values.size and values.max() > 0 else 0
        free = basis[kept:].T  # (J, directions): the motions the equalities allow
        if not free.shape[1]:
            continue
        rank = _rank(moments[:, dofs] @ free)
        if rank < free.shape[1]:
            joint_names = ", ".join(
                mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint {j}" for j in joints
            )
            found.append(
                f"{name} ({len(joints)} joints, {joint_names}; {free.shape[1]} direction{'s' * (free.shape[1] != 1)} "
                f"of motion, {rank} servo direction{'s' * (rank != 1)})"
            )
    return found


def _tied_dofs(equalities: NDArray[np.float64], dofs: NDArray[np.intp]) -> NDArray[np.intp]:
    """``dofs`` and every dof an equality row ties to them, directly or through others, in model order."""
    found = {int(d) for d in dofs}
    active = np.abs(equalities) > 0
    grown = True
    while grown:
        grown = False
        for row in active:
            touched = set(np.flatnonzero(row).tolist())
            if touched & found and not touched <= found:
                found |= touched
                grown = True
    return np.array(sorted(found), dtype=np.intp)
