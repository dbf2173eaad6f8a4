"""A hand grasp in MuJoCo: the object free, the hand's palm held by a stiff mocap weld, closed by its servos.

:func:`build_hand_scene` compiles the object (convex parts, mass properties of the watertight mesh,
as for fingertips) and the hand (:func:`ogcp.sim_eval.hand.mount.attach_hand`) with ogcp's solver
options, whatever the hand's own file sets (a model tuned for MJX has one CG iteration). The
mount is welded to a mocap body at the fitted palm pose. Every colliding hand geom collides with
the object, with the grasp's friction and contact parameters, and never with the hand itself.

:func:`close_hand` runs the closing sequence from the pregrasp (pads backed off along their
normals, the palm where the fit put it): the servo targets move to the grasp configuration, then
to the squeeze (:mod:`ogcp.sim_eval.hand.squeeze`: targets under which the servos press balanced
contact forces, a share of the largest the actuators allow; where no balanced squeeze exists, the
pads' targets :data:`SQUEEZE_RADII` pad radii past the surface), each over :data:`STAGE_TIME`. The
state it ends in becomes the scene's start, so the protocol's settling, gates and ramps
(:mod:`ogcp.sim_eval.protocols.phases`) run on it as on fingertips, the squeeze targets held as preload.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.sim_eval.hand.fit import HandFit, fit_hand
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.mount import MOUNT, PREFIX, MountedHand, attach_hand
from ogcp.sim_eval.hand.servo_step import steady_servos
from ogcp.sim_eval.hand.squeeze import Grip, balanced_grip, servo_ctrl
from ogcp.sim_eval.scene.collision import Part
from ogcp.sim_eval.scene.grasp_scene import GraspScene, add_object, contact_friction, set_options
from ogcp.sim_eval.settings import SimSettings

WRIST = "ogcp_wrist"
#: The weld holding the palm: a stiff constraint (time constant [s], damping ratio).
WELD_SOLREF = (0.002, 1.0)
#: How far the pregrasp backs each pad off its contact, in pad radii (BODex: 1 cm).
PREGRASP_RADII = 2.0
#: The shares of the largest balanced grip a trial squeezes with, strongest first: the first whose
#: settled grasp passes the gates is tested (a full grip can squeeze an object out of rolling pads).
SQUEEZE_LADDER = (1.0, 0.5, 0.25)
#: Where no balanced squeeze exists: how far past its contact, along the normal, each pad's
#: target lies, in pad radii.
SQUEEZE_RADII = 0.5
#: The approach's waypoints, as fractions of the pregrasp's distance from the contacts.
APPROACH = (1.0, 0.75, 0.5, 0.25, 0.0)
#: Duration of each closing stage, pregrasp to grasp and grasp to squeeze [s] (DexGraspBench: 0.4 s).
STAGE_TIME = 0.4
#: While the hand closes, the object's motion is damped with this time constant [s]: where no
#: approach waypoint is clear of the object, the hand starts with a link a fraction of a millimetre
#: inside it (within the fit's tolerance), and with the palm held rigidly that overlap would kick the
#: object away instead of pushing it out. Settling and the protocol run on the free object.
CLOSING_DRAG_TIME = 0.01


@dataclass(frozen=True, eq=False)
class HandScene:
    """A compiled hand grasp: the protocol's scene, and where the hand is in it.

    Attributes:
        scene: The model as the protocol takes it (pads as the fingers, squeeze targets as preload).
        hand: The hand's parts in the model.
        fingers: The chosen fingers' indices (finger ``fingers[k]`` takes contact k).
        pregrasp: Pregrasp configuration, shape (J,).
        approach: Configurations from the pregrasp to the grasp whose pads move straight along the
            contact normals, shape (K, J): the closing follows them, so that no link sweeps
            through the object on the way.
        grasp: Fitted configuration, shape (J,).
        squeeze_forces: The normal force each pad is to press with [N] (zeros: no balanced squeeze
            exists, the pads were pushed past the surface instead), shape (m,).
        grip: The largest balanced grip (None where none exists); :func:`squeezed` takes shares of it.
        palms: The palm's mocap pose (position, (w, x, y, z)) at each approach waypoint and at the
            squeeze, shape (K + 1, 7); None: held where the fit put it (a given grasp's stages
            may move it).
        spec: The spec the model was compiled from (:mod:`ogcp.sim_eval.hand.lean` recompiles it).
    """

    scene: GraspScene
    hand: MountedHand
    fingers: tuple[int, ...]
    pregrasp: NDArray[np.float64]
    approach: NDArray[np.float64]
    grasp: NDArray[np.float64]
    squeeze_forces: NDArray[np.float64]
    grip: Grip | None = None
    palms: NDArray[np.float64] | None = None
    spec: mujoco.MjSpec | None = None

    def ctrl(self, angles: ArrayLike) -> NDArray[np.float64]:
        """Servo targets that hold a configuration (other actuators at their reference), shape (nu,)."""
        return servo_targets(self.scene.model, self.hand, angles)


def servo_targets(model: mujoco.MjModel, hand: MountedHand, angles: ArrayLike) -> NDArray[np.float64]:
    """Each position actuator's control that holds a configuration (its length there for a
    ``<position>`` servo; :func:`~ogcp.sim_eval.hand.squeeze.servo_ctrl`), within its ctrl range."""
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    data.qpos[hand.qpos] = angles
    mujoco.mj_fwdPosition(model, data)
    ctrl = servo_ctrl(model, data.actuator_length)  # no force at rest there: gear included
    limited = model.actuator_ctrllimited.astype(bool)
    ctrl[limited] = np.clip(ctrl[limited], model.actuator_ctrlrange[limited, 0], model.actuator_ctrlrange[limited, 1])
    return ctrl


def moved_configuration(
    scene: FitScene, fit: HandFit, points: ArrayLike, normals: ArrayLike, radii_inward: float
) -> NDArray[np.float64]:
    """The fingers with their pads moved along the contact normals (inward > 0, in pad radii), the palm held.

    With the object's parts in ``scene``, the links are kept out of it too (a pregrasp that already
    touches the object pushes it away while the hand closes).
    """
    radii = np.array([scene.kinematics.fingers[f].radius for f in fit.fingers])
    inward = np.asarray(normals, dtype=float)
    moved = np.asarray(points, dtype=float) + radii_inward * radii[:, None] * inward
    palm = (fit.rotation, fit.translation)
    return fit_hand(scene, fit.fingers, moved, inward, fit.joint_angles, palm=palm).joint_angles


def build_hand_scene(
    kinematics: HandKinematics,
    fit: HandFit,
    points: ArrayLike,
    normals: ArrayLike,
    parts: Sequence[Part],
    com: NDArray[np.float64],
    inertia: NDArray[np.float64],
    settings: SimSettings,
    mu: float,
    torque_scale: float,
    torsion: float = 0.0,
    approach: bool = True,
) -> HandScene:
    """Compile the object and the hand at its fitted palm pose, in the pregrasp.

    Args:
        kinematics: The hand.
        fit: The fit of the grasp (palm pose, joint angles, chosen fingers).
        points: The contacts the fit aimed at, shape (m, 3) [m].
        normals: Their inward normals, shape (m, 3).
        parts: The object's convex parts.
        com: Object centre of mass, shape (3,) [m].
        inertia: Inertia about the COM, shape (3, 3) [kg·m²].
        settings: Simulation settings (lengths scaled to the object).
        mu: Friction coefficient of hand-object contacts.
        torque_scale: rho [m] of the scaled wrench space (the squeeze's balance).
        torsion: Torsional friction [m]; 0: condim 3.
        approach: Compute ogcp's approach (pads backed off along the normals, straight in); False:
            the grasp configuration alone, for a caller that brings its own pregrasp.

    Returns:
        The scene, not yet closed (:func:`close_hand`), squeezing with the full grip (:func:`squeezed`
        takes a share of it).
    """
    spec = mujoco.MjSpec()
    spec.modelname = "ogcp_hand_grasp"
    set_options(spec, settings, settings.gravity)
    add_object(spec, parts, com, inertia, settings.body_mass, settings, mu, torsion)
    attach_hand(spec, kinematics, free=True)
    quat = _wxyz(fit.rotation)
    spec.worldbody.add_body(name=WRIST, mocap=True, pos=fit.translation.tolist(), quat=quat.tolist())
    weld = spec.add_equality(name="ogcp_palm_weld", type=mujoco.mjtEq.mjEQ_WELD, name1=WRIST, name2=MOUNT)
    weld.objtype = mujoco.mjtObj.mjOBJ_BODY
    weld.solref = list(WELD_SOLREF)
    # Anchor, relative pose (position, quaternion) and torque scale: the mount *on* the mocap body.
    # Left unset, MuJoCo would keep the offset they have at compile time (the mount at the origin).
    weld.data = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    solid = {PREFIX + kinematics.geom_name(int(g)) for g in kinematics.solid_geoms}
    for geom in spec.geoms:
        if geom.name in solid:
            geom.contype, geom.conaffinity = 0, 1  # the object's parts have contype 1
            for key, value in contact_friction(mu, torsion).items():
                setattr(geom, key, value)
            geom.solref = list(settings.contact_solref)
            geom.solimp = [*settings.contact_solimp, 0.5, 2.0]
    for equality in spec.equalities:  # a coupled joint follows its driver, as stiffly as the palm's weld
        if equality.type == mujoco.mjtEq.mjEQ_JOINT:
            equality.solref = list(WELD_SOLREF)
    model = spec.compile()
    hand = MountedHand.find(model, kinematics)
    waypoints = np.array([fit.joint_angles])
    if approach:
        around = FitScene(kinematics, parts)
        waypoints = np.array(
            [moved_configuration(around, fit, points, normals, -f * PREGRASP_RADII) for f in APPROACH[:-1]]
            + [fit.joint_angles]
        )
        waypoints = waypoints[_first_clear(around, fit, waypoints) :]
    pregrasp = waypoints[0]
    mount_qpos = int(model.jnt_qposadr[model.body_jntadr[hand.mount]])
    start = model.qpos0.copy()
    start[mount_qpos : mount_qpos + 3] = fit.translation
    start[mount_qpos + 3 : mount_qpos + 7] = quat
    grasp_qpos = start.copy()
    grasp_qpos[hand.qpos] = fit.joint_angles
    start[hand.qpos] = pregrasp
    if settings.protocol != "dexgraspbench":  # their mode steps the hand as their simulator does
        steady_servos(model, grasp_qpos)  # servos the time step integrates
    ordered = (np.asarray(points, dtype=float), np.asarray(normals, dtype=float))
    grip = balanced_grip(
        model, hand, grasp_qpos, fit.fingers, *ordered, com, torque_scale, mu, settings.max_normal_force
    )
    if grip is not None:
        squeeze, forces = grip.targets(model, 1.0)
    else:
        forces = np.zeros(len(fit.fingers))
        squeeze = servo_targets(model, hand, moved_configuration(FitScene(kinematics), fit, *ordered, SQUEEZE_RADII))
    object_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "object")
    object_joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "object_free")
    object_geoms = np.flatnonzero(model.geom_bodyid == object_body).astype(np.intp)
    # A finger's pad is every geom rigidly attached to its tip body (a URDF pad is often a
    # geometry-less link fixed to the last moving one).
    welded = model.body_weldid[model.geom_bodyid[hand.geoms]]
    pad_geoms = tuple(hand.geoms[welded == model.body_weldid[hand.pads[f]]].astype(np.intp) for f in fit.fingers)
    scene = GraspScene(
        model,
        int(object_body),
        int(model.jnt_qposadr[object_joint]),
        object_geoms,
        np.array([geoms[0] if len(geoms) else -1 for geoms in pad_geoms], dtype=np.intp),
        squeeze,
        float(max(kinematics.fingers[f].radius for f in fit.fingers)),
        float(mu),
        float(torsion),
        finger_geoms=pad_geoms,
        watched_qpos=np.arange(mount_qpos, mount_qpos + 3, dtype=np.intp),
        start_qpos=start,
    )
    return HandScene(scene, hand, fit.fingers, pregrasp, waypoints, fit.joint_angles.copy(), forces, grip, spec=spec)


def squeezed(hand_scene: HandScene, share: float) -> HandScene:
    """The same scene squeezing with ``share`` (in (0, 1]) of its balanced grip (unchanged without one)."""
    if hand_scene.grip is None:
        return hand_scene
    targets, forces = hand_scene.grip.targets(hand_scene.scene.model, share)
    scene = dataclasses.replace(hand_scene.scene, preload_ctrl=targets)
    return dataclasses.replace(hand_scene, scene=scene, squeeze_forces=forces)


def _first_clear(scene: FitScene, fit: HandFit, approach: NDArray[np.float64]) -> int:
    """The first waypoint in which no link touches the object (the grasp itself, the last, if none).

    A hand that starts overlapping the object kicks it away: with gravity off it drifts off the grasp.
    """
    for k, angles in enumerate(approach[:-1]):
        scene.pose(angles, fit.rotation, fit.translation)
        if scene.depths()[0].max() <= 0.0:
            return k
    return len(approach) - 1


def close_hand(hand_scene: HandScene, steady_object: bool = True) -> HandScene:
    """Close the hand: pregrasp to grasp to squeeze.

    Args:
        hand_scene: The scene in its pregrasp.
        steady_object: Damp the object's motion while closing (:data:`CLOSING_DRAG_TIME`); False
            (the DexGraspBench mode) closes on the free object, as they do.

    Returns:
        The scene starting from the closed hand (its ``start_qpos``), for the protocol; a closing
        that diverged leaves the start where it was (the settling then reports it).
    """
    scene, model = hand_scene.scene, hand_scene.scene.model
    data = mujoco.MjData(model)
    data.qpos[:] = scene.start()
    mujoco.mj_forward(model, data)
    first = int(model.jnt_dofadr[model.body_jntadr[scene.object_body]])
    dofs = slice(first, first + 6)  # the object's free joint
    undamped = model.dof_damping[dofs].copy()
    mass, inertia = model.body_mass[scene.object_body], model.body_inertia[scene.object_body].mean()
    if steady_object:
        model.dof_damping[dofs] = np.repeat([mass, inertia], 3) / CLOSING_DRAG_TIME
    try:
        _close(hand_scene, data)
    finally:
        model.dof_damping[dofs] = undamped  # settling and the protocol run on the free object
    if not np.all(np.isfinite(data.qpos)):
        return hand_scene
    return dataclasses.replace(hand_scene, scene=dataclasses.replace(scene, start_qpos=data.qpos.copy()))


def _close(hand_scene: HandScene, data: mujoco.MjData) -> None:
    """Step the closing sequence of :func:`close_hand` from ``data``'s state."""
    scene, model = hand_scene.scene, hand_scene.scene.model
    steps = max(1, round(STAGE_TIME / model.opt.timestep))
    approach = [hand_scene.ctrl(angles) for angles in hand_scene.approach]
    legs = [*itertools.pairwise(approach), (approach[-1], scene.preload_ctrl)]
    palms = hand_scene.palms
    mocap = int(model.body_mocapid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, WRIST)])
    for leg, (start, end) in enumerate(legs):
        count = max(1, steps // (len(legs) - 1)) if leg < len(legs) - 1 else steps
        for k in range(count):
            share = min(1.0, (k + 1) / (0.5 * count))
            data.ctrl[:] = start + (end - start) * share
            if palms is not None:
                data.mocap_pos[mocap] = palms[leg, :3] + (palms[leg + 1, :3] - palms[leg, :3]) * share
                quat = palms[leg, 3:] + (palms[leg + 1, 3:] - palms[leg, 3:]) * share  # nlerp: stages lie close
                data.mocap_quat[mocap] = quat / np.linalg.norm(quat)
            mujoco.mj_step(model, data)


def _wxyz(rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    x, y, z, w = Rotation.from_matrix(rotation).as_quat()
    return np.array([w, x, y, z])
