"""Hand grasps another planner posed: palm pose and joint angles, checked against the compiled hand.

An ``ogcp.grasps/1`` grasp with a ``hand`` block (:mod:`ogcp.planner.records.hand_poses`) is not
fitted: the hand is put where the record says, its contacts are where the chosen pads are (or the
record's own contacts), and it is closed and tested exactly as ogcp's own hand grasps
(:func:`ogcp.sim_eval.hand.trial.simulate_hand_grasp`), from the record's pregrasp and to its
squeeze where it gives them. This module turns the record's names into the hand's indices, with
one-line errors that name the JSON path, and finds the pads that touch the object.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh
from numpy.typing import NDArray

from ogcp.planner.grasp.mesh_distance import SurfaceIndex
from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.hand_poses import HandPose, HandStage
from ogcp.sim_eval.hand.scene import WRIST, HandScene, servo_targets

#: A pad takes a contact when its point lies within this many pad radii of the surface (fingers not named).
TOUCH_RADII = 1.0
#: A posed link deeper than this inside the object is refused unsimulated [m] (DexGraspBench's max_pene).
GIVEN_MAX_PENETRATION = 0.01


@dataclass(frozen=True, eq=False)
class Stage:
    """A configuration resolved against the hand.

    Attributes:
        joint_angles: The finger joints in the kinematics' order, couplings applied, shape (J,).
        rotation: Palm frame to object frame, shape (3, 3).
        translation: Palm origin in the object frame, shape (3,) [m].
    """

    joint_angles: NDArray[np.float64]
    rotation: NDArray[np.float64]
    translation: NDArray[np.float64]

    @property
    def palm(self) -> NDArray[np.float64]:
        """Palm position and (w, x, y, z) quaternion, shape (7,): a mocap pose."""
        return np.concatenate([self.translation, quaternion_of(self.rotation)])


@dataclass(frozen=True, eq=False)
class GivenPose:
    """A posed hand grasp, resolved: the grasp, its fingers, and the optional stages around it.

    Attributes:
        grasp: The grasp configuration.
        fingers: Finger indices; finger ``fingers[k]`` takes contact k.
        pregrasp: Where the closing starts, or None: ogcp's pregrasp.
        squeeze: Where the servos aim after the grasp, or None: ogcp's balanced squeeze.
    """

    grasp: Stage
    fingers: tuple[int, ...]
    pregrasp: Stage | None = None
    squeeze: Stage | None = None


def quaternion_of(rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit (w, x, y, z) quaternion of a rotation matrix, shape (4,)."""
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation, dtype=float).ravel())
    return quat


def rotation_of(quaternion: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation matrix of a unit (w, x, y, z) quaternion, shape (3, 3)."""
    matrix = np.empty(9)
    mujoco.mju_quat2Mat(matrix, np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion))
    return matrix.reshape(3, 3)


def resolve_stage(kinematics: HandKinematics, stage: HandStage, palm: Stage | None, where: str) -> Stage:
    """A record's stage as the hand's configuration; the palm defaults to ``palm``'s.

    Raises:
        OgcpError: For a joint the hand does not have (listing its joints), a finger joint left
            out (one that a coupling sets may be), or an angle outside its range.
    """
    names = kinematics.joint_names
    unknown = [name for name in stage.joint_angles if name not in names]
    if unknown:
        raise OgcpError(
            f"{where}.joint_angles.{unknown[0]}: the {kinematics.descriptor.name} hand has no such joint; "
            f"its finger joints are {', '.join(names)}"
        )
    driven = set(kinematics.independent.tolist())
    missing = [names[k] for k in sorted(driven) if names[k] not in stage.joint_angles]
    if missing:
        raise OgcpError(f"{where}.joint_angles: missing joint(s) {', '.join(missing)}")
    angles = kinematics.reference()
    for k, name in enumerate(names):
        if name in stage.joint_angles:
            angles[k] = stage.joint_angles[name]
    try:
        angles = kinematics.check(kinematics.complete(angles), tolerance=1e-4)
    except OgcpError as exc:
        raise OgcpError(f"{where}.joint_angles: {exc}") from None
    limits = kinematics.limits
    angles = np.clip(angles, limits[:, 0], limits[:, 1])
    if stage.palm_quaternion is not None:
        rotation = rotation_of(stage.palm_quaternion)
    elif palm is not None:
        rotation = palm.rotation
    else:
        raise OgcpError(f"{where}.palm_quaternion: missing")
    if stage.palm_position is not None:
        translation = np.array(stage.palm_position, dtype=float)
    elif palm is not None:
        translation = palm.translation
    else:
        raise OgcpError(f"{where}.palm_position: missing")
    return Stage(angles, rotation, translation)


def pad_points(kinematics: HandKinematics, stage: Stage) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Every finger's pad point and pad normal (out of the pad: into the object) in the object frame, each (F, 3)."""
    points, normals = kinematics.pads(stage.joint_angles)
    return points @ stage.rotation.T + stage.translation, normals @ stage.rotation.T


def resolve_pose(
    kinematics: HandKinematics,
    pose: HandPose,
    mesh: trimesh.Trimesh,
    where: str,
    contacts: NDArray[np.float64] | None = None,
) -> tuple[GivenPose, NDArray[np.float64], NDArray[np.float64]]:
    """A record's hand grasp against the hand and the object, with the contacts it makes.

    Args:
        kinematics: The hand.
        pose: The grasp's ``hand`` block.
        mesh: The object, in the record's frame [m].
        where: JSON path of the block (``FILE: grasps[3].hand``), for messages.
        contacts: The record's own contact points, shape (m, 3) [m], or None: the pads' points.

    Returns:
        The resolved pose, and the chosen pads' points (m, 3) [m] and normals (m, 3), out of the
        pads (into the object). With the record's contacts, finger k takes contact k: the named
        fingers, else the nearest pads.

    Raises:
        OgcpError: One line naming the JSON path, for unknown joints or fingers, angles out of
            range, fewer than two pads near the surface, or fingers and contacts that differ in number.
    """
    grasp = resolve_stage(kinematics, pose.grasp, None, where)
    stages = {
        name: None if stage is None else resolve_stage(kinematics, stage, grasp, f"{where}.{name}")
        for name, stage in (("pregrasp", pose.pregrasp), ("squeeze", pose.squeeze))
    }
    points, normals = pad_points(kinematics, grasp)
    names = kinematics.descriptor.finger_names
    if pose.fingers is not None:
        unknown = [name for name in pose.fingers if name not in names]
        if unknown:
            raise OgcpError(
                f"{where}.fingers: the {kinematics.descriptor.name} hand has no finger {unknown[0]!r}; "
                f"its fingers are {', '.join(names)}"
            )
        fingers = tuple(names.index(name) for name in pose.fingers)
    elif contacts is not None:
        fingers = _nearest_pads(points, contacts, where)
    else:
        radii = np.array([finger.radius for finger in kinematics.fingers])
        distance = np.abs(SurfaceIndex(mesh).nearest(points).distance)
        fingers = tuple(int(f) for f in np.flatnonzero(distance <= TOUCH_RADII * radii))
        if len(fingers) < 2:
            closest = ", ".join(f"{names[f]} {distance[f] * 1e3:.1f} mm" for f in np.argsort(distance)[:3])
            raise OgcpError(
                f"{where}: only {len(fingers)} pad(s) lie within {TOUCH_RADII:g} pad radius of the surface "
                f'({closest}); name the fingers that grasp ("fingers") or give the contacts'
            )
    if contacts is not None and len(fingers) != len(contacts):
        raise OgcpError(f"{where}.fingers: {len(fingers)} finger(s) named for {len(contacts)} contacts")
    given = GivenPose(grasp, fingers, stages["pregrasp"], stages["squeeze"])
    return given, points[list(fingers)], normals[list(fingers)]


def _nearest_pads(pads: NDArray[np.float64], contacts: NDArray[np.float64], where: str) -> tuple[int, ...]:
    """Each contact's pad: the nearest one not taken, contacts nearest to a pad first."""
    if len(contacts) > len(pads):
        raise OgcpError(f"{where}: {len(contacts)} contacts for a hand of {len(pads)} fingers")
    distance = np.linalg.norm(contacts[:, None, :] - pads[None, :, :], axis=2)
    chosen: dict[int, int] = {}
    for flat in np.argsort(distance, axis=None):
        contact, pad = divmod(int(flat), len(pads))
        if contact not in chosen and pad not in chosen.values():
            chosen[contact] = pad
    return tuple(chosen[k] for k in range(len(contacts)))


def stage_path(approach: Sequence[Stage], squeeze: Stage) -> NDArray[np.float64]:
    """The palm's mocap poses along a closing: per approach waypoint, then the squeeze, shape (K + 1, 7)."""
    return np.array([stage.palm for stage in (*approach, squeeze)])


def given_scene(opened: HandScene, given: GivenPose) -> HandScene:
    """An opened hand scene that closes through the record's stages instead of ogcp's.

    With a pregrasp, the closing starts there (hand and palm) and goes straight to the grasp; with
    a squeeze, the servos aim at it (no balanced grip, no ladder of shares) and the palm ends at
    its pose, where the mocap then holds it for the whole protocol.
    """
    model, hand = opened.scene.model, opened.hand
    approach = [given.pregrasp, given.grasp] if given.pregrasp is not None else [given.grasp] * len(opened.approach)
    angles = np.array([stage.joint_angles for stage in approach]) if given.pregrasp is not None else opened.approach
    last = given.squeeze if given.squeeze is not None else given.grasp
    palms = stage_path(approach, last)
    for k in range(1, len(palms)):  # q and -q are one rotation: interpolate along the short way
        if palms[k, 3:] @ palms[k - 1, 3:] < 0:
            palms[k, 3:] *= -1
    wrist = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, WRIST)
    model.body_pos[wrist], model.body_quat[wrist] = palms[-1, :3], palms[-1, 3:]
    start = opened.scene.start_qpos.copy() if opened.scene.start_qpos is not None else model.qpos0.copy()
    mount = int(model.jnt_qposadr[model.body_jntadr[hand.mount]])
    start[mount : mount + 7] = palms[0]
    start[hand.qpos] = angles[0]
    scene = dataclasses.replace(opened.scene, start_qpos=start)
    grip, forces = opened.grip, opened.squeeze_forces
    if given.squeeze is not None:
        scene = dataclasses.replace(scene, preload_ctrl=servo_targets(model, hand, given.squeeze.joint_angles))
        grip, forces = None, np.zeros(len(given.fingers))
    return dataclasses.replace(
        opened, scene=scene, pregrasp=angles[0], approach=angles, squeeze_forces=forces, grip=grip, palms=palms
    )
