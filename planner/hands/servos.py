"""Position servos for a hand's finger joints where the model's own actuators hold no pose.

Closing a hand needs servos: position targets past the surface, pressing within their force
limits. A finger joint is *held* when an actuator with a stiffness on its length moves it toward
its command, directly or through a tendon (MuJoCo's affine bias with ``biasprm[1] < 0``: a
``<position>``, filtered or not, a ``<general>`` servo such as the Robotiq 2F-85's). A joint no
actuator drives gets a position servo of the descriptor's ``[actuation]``, as a user's
actuator-less model must be closed somehow. A joint driven by an actuator that holds no pose (a
``<motor>``, whose force is its command; a ``<velocity>`` servo; an ``<intvelocity>``, whose
command is a velocity its activation integrates) is closed the same way: that actuator is replaced
by a position servo of ``[actuation]``'s stiffness within the actuator's own force range (its
``forcerange``, else its command range times its gain; through its gear; asymmetric where it is),
and loading says so in one line. Actuators on tendons or sites are kept as they are. Where a joint
clamps the actuator force it takes (``actuatorfrcrange``; MuJoCo turns a URDF's ``effort`` limit
into one), its servo's force range is narrowed to that clamp, so that the range says what the
joint gets.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from ogcp.planner.hands.descriptor import Actuation
from ogcp.planner.hands.loops import Loop

#: Poses besides the reference in which a transmission's moment arms are read.
PROBE_POSES = 3
PROBE_SEED = 0
#: A moment arm below this fraction of an actuator's largest one moves no joint (round-off).
MOMENT_FLOOR = 1e-9


class HandActuatorWarning(UserWarning):
    """A hand's actuators were changed so that the hand can close (one line, naming them)."""


@dataclass(frozen=True)
class AddedServos:
    """What :func:`add_servos` changed in a hand's spec.

    Attributes:
        joints: Names of the joints that got ogcp's position servo.
        replaced: Names of the model's actuators that held no pose and were replaced.
    """

    joints: tuple[str, ...]
    replaced: tuple[str, ...]


def holds_pose(model: mujoco.MjModel, actuator: int) -> bool:
    """Whether an actuator's force falls as its length grows and its command is where it holds (a servo
    that holds a position). An ``<intvelocity>`` servo holds where its activation integrated its
    command to, a velocity: ogcp cannot set it a target, so it counts as holding none."""
    affine = int(model.actuator_biastype[actuator]) == mujoco.mjtBias.mjBIAS_AFFINE
    integrates = int(model.actuator_dyntype[actuator]) == mujoco.mjtDyn.mjDYN_INTEGRATOR
    return bool(affine and not integrates and model.actuator_biasprm[actuator, 1] < 0)


def _force_range(model: mujoco.MjModel, actuator: int, fallback: float) -> tuple[float, float]:
    """[N·m or N] The least and most an actuator pushes on its joint: its force range, else its command
    range times its gain, else ``±fallback``; through its gear. An asymmetric range (a tendon-driven
    finger that flexes harder than it extends) stays asymmetric."""
    gear = float(model.actuator_gear[actuator, 0])
    if model.actuator_forcelimited[actuator]:
        ends = gear * model.actuator_forcerange[actuator]
    elif model.actuator_ctrllimited[actuator]:
        ends = gear * float(model.actuator_gainprm[actuator, 0]) * model.actuator_ctrlrange[actuator]
    else:
        return -fallback, fallback
    low, high = sorted(float(e) for e in ends)
    return min(low, 0.0), max(high, 0.0)


def _joint_clamp(model: mujoco.MjModel, joint: int) -> tuple[float, float] | None:
    """[N·m or N] The joint's own clamp on the actuator force it takes (its ``actuatorfrcrange``; a
    URDF's ``effort`` limit becomes one), or None."""
    if not model.jnt_actfrclimited[joint]:
        return None
    low, high = model.jnt_actfrcrange[joint]
    return float(low), float(high)


def _within(ends: tuple[float, float], clamp: tuple[float, float] | None, gear: float) -> tuple[float, float]:
    """An actuator's force range ``ends`` narrowed to what its joint's ``clamp`` lets through its ``gear``."""
    if clamp is None or gear == 0:
        return ends
    low, high = sorted((clamp[0] / gear, clamp[1] / gear))
    narrowed = max(ends[0], low), min(ends[1], high)
    return narrowed if narrowed[0] <= narrowed[1] else ends  # ranges that do not meet: the actuator's own


def _clamp_kept(spec: mujoco.MjSpec, model: mujoco.MjModel, kept: Sequence[int]) -> None:
    """Narrow the force range of each kept actuator that alone drives a joint with a clamp (MuJoCo
    clamps the joint's total actuator force): the range then says what the joint gets, as the
    squeeze and the prediction read it."""
    on_joint = [
        int(model.actuator_trnid[a, 0])
        for a in range(model.nu)
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
    ]
    for a in kept:
        if model.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT:
            continue
        joint = int(model.actuator_trnid[a, 0])
        clamp = _joint_clamp(model, joint)
        if clamp is None or on_joint.count(joint) != 1:
            continue
        own = tuple(model.actuator_forcerange[a]) if model.actuator_forcelimited[a] else (-np.inf, np.inf)
        element = spec.actuators[a]
        element.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        element.forcerange = list(_within((float(own[0]), float(own[1])), clamp, float(model.actuator_gear[a, 0])))


def _driven_joints(model: mujoco.MjModel, actuators: Iterable[int]) -> set[int]:
    """The joints the actuators move: directly, or through any transmission with a moment arm on
    them (a fixed tendon; a spatial tendon routed over sites and wrapping geoms, as the Tetheria
    Aero hand's flexor tendons; a site), read from MuJoCo's moment arms in a few poses, since a
    spatial tendon's arm on a joint may vanish in one."""
    chosen = list(actuators)
    driven = {int(model.actuator_trnid[a, 0]) for a in chosen if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT}
    others = [a for a in chosen if model.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT]
    if not others:
        return driven
    data = mujoco.MjData(model)
    moments = np.zeros((model.nu, model.nv))
    for qpos in _probe_poses(model):
        data.qpos[:] = qpos
        mujoco.mj_fwdPosition(model, data)
        mujoco.mju_sparse2dense(
            moments, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind
        )
        for a in others:
            arms = np.abs(moments[a])
            dofs = np.flatnonzero(arms > MOMENT_FLOOR * max(float(arms.max(initial=0.0)), 1e-300))
            driven.update(int(model.dof_jntid[d]) for d in dofs)
    return driven


def _probe_poses(model: mujoco.MjModel) -> list[np.ndarray]:
    """The model's reference pose and :data:`PROBE_POSES` others, hinges and slides uniform within
    their ranges (unlimited hinges over a turn), seeded: where moment arms are read."""
    rng = np.random.default_rng(PROBE_SEED)
    poses = [model.qpos0.copy()]
    movable = [
        j for j in range(model.njnt) if model.jnt_type[j] in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
    ]
    for _ in range(PROBE_POSES):
        qpos = model.qpos0.copy()
        for j in movable:
            low, high = model.jnt_range[j] if model.jnt_limited[j] else (-np.pi, np.pi)
            qpos[model.jnt_qposadr[j]] = rng.uniform(low, high)
        poses.append(qpos)
    return poses


def follows(model: mujoco.MjModel, joint: int, drivers: set[int]) -> bool:
    """Whether an active joint equality ties ``joint`` to one of ``drivers``: it needs no servo of its own."""
    for e in range(model.neq):
        if model.eq_type[e] == mujoco.mjtEq.mjEQ_JOINT and model.eq_active0[e] and model.eq_obj1id[e] == joint:
            return int(model.eq_obj2id[e]) in drivers
    return False


def add_servos(
    spec: mujoco.MjSpec,
    model: mujoco.MjModel,
    joints: Sequence[int],
    loops: Sequence[Loop],
    actuation: Actuation,
    where: str,
) -> AddedServos:
    """Position servos on the finger ``joints`` that no actuator holds, in ``spec`` (compiled as ``model``).

    Args:
        spec: The hand's spec, changed in place.
        model: The spec compiled before the change.
        joints: The fingers' joint ids.
        loops: The hand's closed loops: a loop passes its driven joint's drive on to its other
            joints, and a servo there would fight it.
        actuation: The descriptor's ``[actuation]``.
        where: The descriptor's path, for the warning.
    """
    finger_joints = set(joints)
    replaced = [
        a
        for a in range(model.nu)
        if not holds_pose(model, a)
        and model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
        and int(model.actuator_trnid[a, 0]) in finger_joints
    ]
    limits = {int(model.actuator_trnid[a, 0]): _force_range(model, a, actuation.force_range) for a in replaced}
    names = tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or f"actuator {a}" for a in replaced)
    _clamp_kept(spec, model, [a for a in range(model.nu) if a not in set(replaced)])
    for element in [spec.actuators[a] for a in replaced]:
        spec.delete(element)
    driven = _driven_joints(model, (a for a in range(model.nu) if a not in set(replaced)))
    passive = {j for loop in loops if set(loop.joints) & driven for j in loop.joints} - driven
    added = []
    for j in joints:
        if j in driven or j in passive or follows(model, j, driven | finger_joints):
            continue
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        inertia = float(model.dof_M0[model.jnt_dofadr[j]])
        kv = actuation.kv if actuation.kv is not None else 2.0 * np.sqrt(actuation.kp * max(inertia, 1e-9))
        act = spec.add_actuator(name=f"ogcp_servo_{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=actuation.kp, kv=kv)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        own = limits.get(j, (-actuation.force_range, actuation.force_range))
        act.forcerange = list(_within(own, _joint_clamp(model, j), 1.0))
        added.append(name)
    if names:
        warnings.warn(
            f"{where}: actuators {', '.join(names)} hold no pose (no stiffness on their length that ogcp can read: "
            f"motors, velocity servos, plugins such as mujoco.pid); closing the hand needs one, so their joints get "
            f"position servos of [actuation] kp "
            f"{actuation.kp:g} within those actuators' force limits",
            HandActuatorWarning,
            stacklevel=4,
        )
    return AddedServos(tuple(added), names)
