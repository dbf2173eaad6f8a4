"""The protocol's scene for a settled hand: what cannot move before the object fails, made rigid.

Once the hand has closed and settled, the ramps and the weight test load the object until it moves
by the failure thresholds. Through them the palm is held (a stiff weld to a fixed mocap body), and a
finger that touches nothing and keeps clear of the object by more than the object can move before
it counts as failed stays where its servos hold it. Simulating either as a mechanism costs every
step (the Shadow hand's palm adds six degrees of freedom and six weld rows, its idle ring and little
fingers nine more) and measures nothing.

:func:`lean_scene` recompiles the settled scene with the palm and those joints welded where they
settled: their joints go, with the actuators, tendons and equalities that act on nothing else; the
sensors and keyframes go too. Every body and geom stays, so a welded finger the object does reach
still stops it, rigidly. A joint that an actuator, tendon or equality couples to a moving one keeps
moving, and so do the joints between it and the palm. The recompiled scene is checked against the
settled one (every body's pose) and must hold the unloaded object as still as the full scene does
(within the settling gate's creep). A soft
equality's force depends on the masses it joins: a loop that settled open (0.3 mm, as the Robotiq
2F-85's does under its squeeze) pushes otherwise once the palm is welded, so a lean scene that moves
the object more settles again, for :data:`RESETTLE_TIME`, and the trials start from there. Where a
check or the compiler fails, the protocol runs on the full scene, and the record says why.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.sim_eval.hand.mount import in_subtree
from ogcp.sim_eval.hand.scene import HandScene
from ogcp.sim_eval.hand.ties import UnknownTie, actuator_bodies, equality_bodies, tendon_bodies, tied_bodies
from ogcp.sim_eval.protocols.phases import CREEP_WINDOW, FULL_STATE, Settled, settle_further, unloaded_drift
from ogcp.sim_eval.scene.grasp_scene import GraspScene

#: The clearance a finger must keep from the object to be welded, in multiples of the farthest an
#: object point moves before the trial counts the object as failed.
CLEARANCE_FACTOR = 2.0
#: The largest difference [m] (or in a quaternion) between a body's settled pose and its pose in
#: the recompiled scene.
POSE_TOLERANCE = 1e-8
#: How long a lean scene that does not hold the settled object still settles again [s].
RESETTLE_TIME = 0.5
#: Per-element arrays the trial changes after compiling (servo armature and damping, contact
#: parameters); the lean scene takes them over.
_DOF_ARRAYS = ("dof_armature", "dof_damping", "dof_frictionloss")
_GEOM_ARRAYS = (
    "geom_friction",
    "geom_solref",
    "geom_solimp",
    "geom_condim",
    "geom_margin",
    "geom_gap",
    "geom_priority",
    "geom_contype",
    "geom_conaffinity",
    "geom_solmix",
)


@dataclass(frozen=True, eq=False)
class LeanScene:
    """The protocol's scene and where the trials start in it.

    Attributes:
        scene: The recompiled scene (or the full one where it could not be built).
        settled: The settled state, in that scene's layout.
        summary: What the record keeps: ``lean`` (bool), ``dofs`` and ``full_dofs`` (the number of
            degrees of freedom simulated, and of the full scene), ``welded_joints`` (names), or
            ``reason`` where the full scene is used.
    """

    scene: GraspScene
    settled: Settled
    summary: dict[str, object]


def failure_reach(move_threshold: float, rotation_threshold: float, diagonal: float) -> float:
    """How far [m] an object point can move before a trial counts the object as failed (a bound).

    Args:
        move_threshold: Displacement that counts as failure [m].
        rotation_threshold: Rotation that counts as failure [deg].
        diagonal: The object's bounding-box diagonal [m] (no point is farther from its centre of mass).
    """
    return move_threshold + math.radians(rotation_threshold) * diagonal


def lean_scene(closed: HandScene, settled: Settled, reach: float, creep: float | None = None) -> LeanScene:
    """The settled hand grasp with its palm, and the fingers that keep clear of the object, welded.

    Args:
        closed: The closed hand scene (with the spec it was compiled from).
        settled: Its settled state.
        reach: How far an object point moves before the object counts as failed [m]
            (:func:`failure_reach`); a finger is welded when it keeps :data:`CLEARANCE_FACTOR` times
            that from the object.
        creep: How much farther than in the full scene the unloaded object may move over
            :data:`~ogcp.sim_eval.protocols.phases.CREEP_WINDOW` in the lean scene [m] (the settling
            gate's tolerance); None: not checked.

    Returns:
        The lean scene, or the full one with the reason it could not be built.
    """
    full = LeanScene(closed.scene, settled, {"lean": False, "full_dofs": int(closed.scene.model.nv)})
    if closed.spec is None:
        return dataclasses.replace(full, summary={**full.summary, "reason": "no spec"})
    if not (np.all(np.isfinite(settled.state))):
        return dataclasses.replace(full, summary={**full.summary, "reason": "the settled state is not finite"})
    model = closed.scene.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    mujoco.mj_forward(model, data)
    try:
        welded = _welded_bodies(closed, data, CLEARANCE_FACTOR * reach)
        lean_model, joints, actuators = _recompile(closed, data, welded)
        lean = _lean_settled(closed, data, settled, lean_model, joints, actuators)
        resettled = False
        # As still as the full scene holds it, within the settling gate's creep; the full scene is
        # stepped only when the lean one moves the object farther than the creep alone allows.
        drift = unloaded_drift(*lean) if creep is not None else 0.0
        if creep is not None and drift > creep:
            limit = unloaded_drift(closed.scene, settled) + creep
            resettled = drift > limit
            if resettled:
                lean = (lean[0], settle_further(*lean, RESETTLE_TIME))
                moved = unloaded_drift(*lean)
                if not moved <= limit:
                    raise _NotLean(
                        f"the lean scene moves the settled object {moved * 1e6:.1f} um in {CREEP_WINDOW:g} s even "
                        f"after settling again for {RESETTLE_TIME:g} s (the full scene {limit * 1e6:.1f} um at most)"
                    )
    except (_NotLean, UnknownTie) as reason:
        return dataclasses.replace(full, summary={**full.summary, "reason": str(reason)})
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint {j}" for j in range(model.njnt)]
    kept = set(joints)
    summary = {
        "lean": True,
        "dofs": int(lean_model.nv),
        "full_dofs": int(model.nv),
        "welded_joints": [names[j] for j in range(model.njnt) if j not in kept],
    }
    if resettled:
        summary["settled_again"] = True
    return LeanScene(lean[0], lean[1], summary)


class _NotLean(Exception):
    """Why the lean scene cannot be used (the protocol then runs on the full scene)."""


def _welded_bodies(closed: HandScene, data: mujoco.MjData, clearance: float) -> set[int]:
    """Bodies with joints to weld: the mount, and the hand's bodies whose subtree stays clear of the object."""
    model, scene, hand = closed.scene.model, closed.scene, closed.hand
    objects = {int(g) for g in scene.object_geoms}
    busy = {int(hand.pads[f]) for f in closed.fingers}
    for c in range(data.ncon):
        pair = (int(data.contact[c].geom1), int(data.contact[c].geom2))
        for geom, other in (pair, pair[::-1]):
            if other in objects and geom not in objects:
                busy.add(int(model.geom_bodyid[geom]))
    for geom in hand.geoms:
        if int(model.geom_bodyid[geom]) in busy:
            continue
        for part in scene.object_geoms:
            if mujoco.mj_geomDistance(model, data, int(geom), int(part), clearance, None) < clearance:
                busy.add(int(model.geom_bodyid[geom]))
                break
    in_hand = {b for b in range(model.nbody) if in_subtree(model, b, hand.mount)}
    moving = set()
    for body in busy:  # a busy body's joints, and those of every body between it and the palm
        while body != hand.mount and body in in_hand:
            moving.add(body)
            body = int(model.body_parentid[body])
    welded = {b for b in in_hand if model.body_jntnum[b] > 0 and b not in moving}
    return _uncoupled(model, welded, hand.mount)


def _uncoupled(model: mujoco.MjModel, welded: set[int], mount: int) -> set[int]:
    """``welded`` less the bodies an actuator, tendon or equality couples to a moving body, and
    the bodies between each of those and the hand's root (a loop's driver carries its coupler:
    the Robotiq 2F-85's pads hang from its follower links, which ``connect`` pins to couplers on
    the driven links)."""
    welded = set(welded)
    changed = True
    while changed:
        changed = False
        for involved in tied_bodies(model):
            moving = {b for b in involved if b not in welded and model.body_jntnum[b] > 0}
            if moving and involved & welded:
                before = len(welded)
                for body in involved:  # the mount stays: the palm is held rigidly whatever pulls on it
                    while body not in (mount, 0):
                        welded.discard(body)
                        body = int(model.body_parentid[body])
                changed = changed or len(welded) < before
    return welded


def _recompile(closed: HandScene, data: mujoco.MjData, welded: set[int]) -> tuple[mujoco.MjModel, list[int], list[int]]:
    """Compile the scene with ``welded``'s joints gone; the kept joints' and actuators' old ids, in order."""
    model = closed.scene.model
    assert closed.spec is not None
    spec = closed.spec.copy()
    spec.compiler.fusestatic = False  # every body keeps its id
    bodies = {element.id: element for element in spec.bodies}
    dead_joints = {j for j in range(model.njnt) if int(model.jnt_bodyid[j]) in welded}
    dead_actuators = set()
    for actuator in range(model.nu):
        if actuator_bodies(model, actuator) <= welded | {0}:
            dead_actuators.add(actuator)
    dead_tendons = {t for t in range(model.ntendon) if tendon_bodies(model, t) <= welded | {0}}
    dead_tendons -= {
        int(model.actuator_trnid[a, 0])
        for a in range(model.nu)
        if a not in dead_actuators and model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_TENDON
    }
    dead_equalities = {e for e in range(model.neq) if equality_bodies(model, e) <= welded | {0} | _static(model)}
    for collection, dead in (
        (spec.actuators, dead_actuators),
        (spec.sensors, set(range(model.nsensor))),
        (spec.keys, set(range(model.nkey))),
        (spec.equalities, dead_equalities),
        (spec.tendons, dead_tendons),
    ):
        for element in [e for e in collection if e.id in dead]:
            spec.delete(element)
    for body in welded:
        element = bodies.get(body)
        if element is None:
            raise _NotLean(f"body {body} is not in the scene's spec")
        _weld_in_place(element, model, data, body)
        for joint in list(element.joints):
            spec.delete(joint)
    try:
        lean = spec.compile()
    except ValueError as error:
        raise _NotLean(f"the lean scene does not compile: {error}") from None
    joints = [j for j in range(model.njnt) if j not in dead_joints]
    actuators = [a for a in range(model.nu) if a not in dead_actuators]
    same_geoms = lean.ngeom == model.ngeom and np.array_equal(lean.geom_bodyid, model.geom_bodyid)
    if lean.njnt != len(joints) or lean.nu != len(actuators) or lean.nbody != model.nbody or not same_geoms:
        raise _NotLean("the lean scene's joints, actuators, bodies or geoms do not match the full scene's")
    return lean, joints, actuators


def _static(model: mujoco.MjModel) -> set[int]:
    """Bodies that never move: the world's and the mocap bodies' rigid groups."""
    return {0} | {b for b in range(model.nbody) if model.body_mocapid[b] >= 0}


def _weld_in_place(element: mujoco.MjsBody, model: mujoco.MjModel, data: mujoco.MjData, body: int) -> None:
    """Set a body's frame so that, without its joints, it sits where it settled relative to its parent.

    The compiled frame at the joints' reference is F · L (F: any frames around the body in the spec,
    L: its local pose); it settled at F · L · J, with J the joints' motion. So L becomes L · J.
    """
    parent = int(model.body_parentid[body])
    settled = _compose(_invert(data.xpos[parent], data.xquat[parent]), (data.xpos[body], data.xquat[body]))
    motion = _compose(_invert(model.body_pos[body], model.body_quat[body]), settled)
    quat = np.asarray(
        mujoco.MjSpec.resolve_orientation(
            degree=element.compiler.degree, sequence=element.compiler.eulerseq, orientation=element.alt
        )
        if element.alt.type != mujoco.mjtOrientation.mjORIENTATION_QUAT
        else element.quat,
        dtype=float,
    )
    quat = quat / np.linalg.norm(quat)
    position, rotation = _compose((np.asarray(element.pos, dtype=float), quat), motion)
    element.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    element.pos = position.tolist()
    element.quat = rotation.tolist()


def _invert(
    position: NDArray[np.float64], quat: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    inverse = np.array([quat[0], -quat[1], -quat[2], -quat[3]])
    moved = np.empty(3)
    mujoco.mju_rotVecQuat(moved, -np.asarray(position, dtype=float), inverse)
    return moved, inverse


def _compose(
    first: tuple[NDArray[np.float64], NDArray[np.float64]], second: tuple[NDArray[np.float64], NDArray[np.float64]]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    moved = np.empty(3)
    mujoco.mju_rotVecQuat(moved, np.asarray(second[0], dtype=float), np.asarray(first[1], dtype=float))
    quat = np.empty(4)
    mujoco.mju_mulQuat(quat, np.asarray(first[1], dtype=float), np.asarray(second[1], dtype=float))
    return np.asarray(first[0], dtype=float) + moved, quat


def _lean_settled(
    closed: HandScene,
    data: mujoco.MjData,
    settled: Settled,
    lean: mujoco.MjModel,
    joints: list[int],
    actuators: list[int],
) -> tuple[GraspScene, Settled]:
    """The settled state in the lean scene's layout, checked body by body, and the scene itself."""
    model = closed.scene.model
    target = mujoco.MjData(lean)
    target.time = data.time
    for new, old in enumerate(joints):
        size = _qpos_size(model.jnt_type[old])
        target.qpos[lean.jnt_qposadr[new] : lean.jnt_qposadr[new] + size] = data.qpos[
            model.jnt_qposadr[old] : model.jnt_qposadr[old] + size
        ]
        dofs = _dof_size(model.jnt_type[old])
        old_dofs = slice(int(model.jnt_dofadr[old]), int(model.jnt_dofadr[old]) + dofs)
        new_dofs = slice(int(lean.jnt_dofadr[new]), int(lean.jnt_dofadr[new]) + dofs)
        target.qvel[new_dofs] = data.qvel[old_dofs]
        for name in _DOF_ARRAYS:
            getattr(lean, name)[new_dofs] = getattr(model, name)[old_dofs]
    for name in _GEOM_ARRAYS:
        getattr(lean, name)[:] = getattr(model, name)
    for new, old in enumerate(actuators):
        if model.actuator_actnum[old] != lean.actuator_actnum[new]:
            raise _NotLean("an actuator's activation changed size")
        count = int(model.actuator_actnum[old])
        if count:
            start, lean_start = int(model.actuator_actadr[old]), int(lean.actuator_actadr[new])
            target.act[lean_start : lean_start + count] = data.act[start : start + count]
    mujoco.mj_kinematics(lean, target)
    drift = max(
        float(np.max(np.abs(target.xpos - data.xpos))),
        float(np.max(np.minimum(np.abs(target.xquat - data.xquat), np.abs(target.xquat + data.xquat)))),
    )
    if not drift <= POSE_TOLERANCE:
        raise _NotLean(f"a body of the lean scene sits {drift:.1e} from its settled pose")
    state = np.empty(mujoco.mj_stateSize(lean, FULL_STATE))
    mujoco.mj_getState(lean, target, state, FULL_STATE)
    scene = closed.scene
    object_joint = joints.index(int(model.body_jntadr[scene.object_body]))
    lean_scene = dataclasses.replace(
        scene,
        model=lean,
        object_qpos=int(lean.jnt_qposadr[object_joint]),
        preload_ctrl=scene.preload_ctrl[actuators].copy(),
        watched_qpos=np.arange(3, dtype=np.intp) + int(lean.jnt_qposadr[object_joint]),  # an object flung away
        start_qpos=target.qpos.copy(),
    )
    return lean_scene, dataclasses.replace(settled, state=state)


def _qpos_size(kind: int) -> int:
    return {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}.get(int(kind), 1)


def _dof_size(kind: int) -> int:
    return {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}.get(int(kind), 1)
