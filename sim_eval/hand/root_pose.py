"""Hand configurations written as a root pose and joint angles (DexGraspBench, BODex) as ogcp stages.

DexGraspBench-style records give each stage (``pregrasp_qpos``, ``grasp_qpos``, ``squeeze_qpos``)
as one vector: the position [m] and (w, x, y, z) quaternion of the hand's root body (the body
below the model's world that carries the palm), then joint angles. ogcp holds the palm instead and
moves only the fingers, so :func:`stage_from_root_qpos` runs the hand's own forward kinematics
(MuJoCo) with every given joint, wrist ones included, and returns the palm's pose in the object
frame with the finger joints' angles: the same hand configuration, seen from the palm.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.hand_poses import HandStage
from ogcp.sim_eval.hand.given import quaternion_of, rotation_of

_MOVABLE = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


def model_joints(kinematics: HandKinematics) -> tuple[str, ...]:
    """Every hinge and slide joint of the hand's model below its root, in model order (wrist included)."""
    model = kinematics.model
    names = []
    for j in range(model.njnt):
        body = int(model.jnt_bodyid[j])
        while body > 0 and body != kinematics.root:
            body = int(model.body_parentid[body])
        if body == kinematics.root and int(model.jnt_type[j]) in _MOVABLE:
            names.append(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j))
    return tuple(names)


def joint_order(kinematics: HandKinematics, count: int, given: Sequence[str] | None, where: str) -> tuple[str, ...]:
    """The joints a qpos vector's angles belong to, in its order.

    Args:
        kinematics: The hand.
        count: How many angles follow the root pose.
        given: Joint names in the vector's order; None: the model's joints (wrist included) if
            there are that many, else the hand's finger joints.
        where: The record's name, for messages.

    Raises:
        OgcpError: When no order fits the count, or a given name is not a joint of the hand.
    """
    if given is not None:
        order = tuple(given)
        unknown = [name for name in order if name not in model_joints(kinematics)]
        if unknown:
            raise OgcpError(
                f"{where}: joint {unknown[0]!r} is not a joint of the {kinematics.descriptor.name} hand; "
                f"its joints are {', '.join(model_joints(kinematics))}"
            )
    else:
        every = model_joints(kinematics)
        order = every if count == len(every) else kinematics.joint_names
    if len(order) != count:
        raise OgcpError(
            f"{where}: {count} joint angles after the root pose; the {kinematics.descriptor.name} hand has "
            f"{len(model_joints(kinematics))} joints ({len(kinematics.joint_names)} on its fingers): give "
            f"the order of the angles (joints)"
        )
    return order


def stage_from_root_qpos(kinematics: HandKinematics, qpos: ArrayLike, order: Sequence[str], where: str) -> HandStage:
    """A stage from a root pose and joint angles: the palm's pose and the finger joints' angles.

    Args:
        kinematics: The hand.
        qpos: Root position (3) [m], root quaternion (w, x, y, z) (4), then one angle per
            name of ``order`` [rad or m].
        order: The joints the angles belong to (:func:`joint_order`).
        where: The record's name and stage, for messages.

    Raises:
        OgcpError: For a vector of the wrong length, values that are not finite, or a zero quaternion.
    """
    vector = np.asarray(qpos, dtype=float).ravel()
    if len(vector) != 7 + len(order) or not np.isfinite(vector).all():
        raise OgcpError(
            f"{where}: expected 7 + {len(order)} finite numbers (root pose, joint angles), got {len(vector)}"
        )
    quaternion = vector[3:7]
    if np.linalg.norm(quaternion) < 1e-9:
        raise OgcpError(f"{where}: the root quaternion (values 4 to 7) is zero")
    angles = dict(zip(order, (float(v) for v in vector[7:]), strict=True))
    palm_rotation, palm_position, _ = _palm_in_root(kinematics, angles)
    root = rotation_of(quaternion)
    rotation = root @ palm_rotation
    finger = {name: angle for name, angle in angles.items() if name in kinematics.joint_names}
    return HandStage(finger, root @ palm_position + vector[:3], quaternion_of(rotation))


def root_qpos(kinematics: HandKinematics, stage: HandStage, order: Sequence[str]) -> NDArray[np.float64]:
    """The inverse of :func:`stage_from_root_qpos` for a hand whose non-finger joints stay at their reference.

    Returns:
        Root position (3) [m], root quaternion (w, x, y, z) (4), then the angles of ``order``.
    """
    assert stage.palm_position is not None and stage.palm_quaternion is not None
    palm_rotation, palm_position, qpos = _palm_in_root(kinematics, stage.joint_angles)
    rotation = rotation_of(stage.palm_quaternion) @ palm_rotation.T
    position = stage.palm_position - rotation @ palm_position
    angles = [qpos[_qpos_address(kinematics, name)] for name in order]
    return np.concatenate([position, quaternion_of(rotation), angles])


def _qpos_address(kinematics: HandKinematics, joint: str) -> int:
    model = kinematics.model
    return int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint)])


def _palm_in_root(
    kinematics: HandKinematics, angles: Mapping[str, float]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The palm's rotation (3, 3) and position (3,) [m] in the root body's frame with the named
    joints at ``angles`` (the others at their reference), and the qpos used, shape (nq,)."""
    model = kinematics.model
    data = mujoco.MjData(model)
    data.qpos[:] = kinematics.reference_qpos
    for name, angle in angles.items():
        data.qpos[_qpos_address(kinematics, name)] = angle
    mujoco.mj_kinematics(model, data)
    root_rotation = data.xmat[kinematics.root].reshape(3, 3)
    rotation = root_rotation.T @ data.xmat[kinematics.palm].reshape(3, 3)
    position = root_rotation.T @ (data.xpos[kinematics.palm] - data.xpos[kinematics.root])
    return rotation, position, data.qpos.copy()
