"""A hand in a scene: its subtree attached to a mount body whose frame is the palm frame.

:func:`attach_hand` copies the hand's model (the subtree of the body below the world that holds
the palm, with its actuators, equalities and defaults; without a free joint, and with its idle
joints welded) under a frame of a new ``mount`` body, placed so that the mount's frame *is* the
palm frame at the hand's reference configuration. Placing the
palm at a pose is then placing the mount: a body pose in a fit, a mocap weld in a simulation.
:class:`MountedHand` finds the hand's joints, pads and geoms in the compiled scene by name.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.hands.loops import Loop

PREFIX = "hand/"
MOUNT = "ogcp_mount"
_OPTION_FIELDS = tuple(
    name
    for name in dir(mujoco.MjSpec().option)
    if not name.startswith("_") and not callable(getattr(mujoco.MjSpec().option, name))
)


def attach_hand(spec: mujoco.MjSpec, kinematics: HandKinematics, free: bool = False) -> mujoco.MjsBody:
    """Attach the hand below a new mount body of ``spec``'s world.

    Args:
        spec: The scene being built.
        kinematics: The hand.
        free: Give the mount a free joint (a simulation welds it to a mocap body).

    Returns:
        The mount body.
    """
    mount = spec.worldbody.add_body(name=MOUNT)
    if free:
        mount.add_freejoint(name=f"{MOUNT}_free")
    rotation, position = kinematics.palm_pose
    # The root's world pose composed with this frame puts the palm at the mount's origin.
    inverse = rotation.T
    frame = mount.add_frame(pos=(-inverse @ position).tolist(), quat=_wxyz(inverse).tolist())
    hand = kinematics.spec.copy()
    root = hand.body(mujoco.mj_id2name(kinematics.model, mujoco.mjtObj.mjOBJ_BODY, kinematics.root))
    # The mount carries a floating hand model instead of its free joint, and the joints that move
    # the palm (a wrist, a floating base), driven or not, are welded where they are, with what
    # drives or reads them: the palm must be as rigidly held as the mount. So are joints elsewhere
    # that move no finger and no actuator drives.
    idle = set(kinematics.idle_joints())
    root.mocap = False  # a teleoperated hand's palm may be a mocap body; the mount moves it now
    for body in [root, *root.find_all(mujoco.mjtObj.mjOBJ_BODY)]:
        for joint in list(body.joints):
            if joint.type == mujoco.mjtJoint.mjJNT_FREE or joint.name in idle:
                hand.delete(joint)
    for actuator in list(hand.actuators):
        if actuator.trntype == mujoco.mjtTrn.mjTRN_JOINT and actuator.target in idle:
            hand.delete(actuator)
    for sensor in list(hand.sensors):
        if sensor.objtype == mujoco.mjtObj.mjOBJ_JOINT and sensor.objname in idle:
            hand.delete(sensor)
    for equality in list(hand.equalities):
        if equality.type == mujoco.mjtEq.mjEQ_JOINT and {equality.name1, equality.name2} & idle:
            hand.delete(equality)
    # The scene's options win; a hand tuned for another simulator (the Shadow hand of MJX's tests:
    # one solver iteration, impratio 10) would otherwise make MuJoCo warn on every attach.
    for name in _OPTION_FIELDS:
        setattr(hand.option, name, copy.copy(getattr(spec.option, name)))
    frame.attach_body(root, PREFIX, "")
    # A URDF's meshes came in memory (ogcp.planner.hands.loading); the scene needs them too.
    spec.assets = {**spec.assets, **hand.assets}
    return mount


def in_subtree(model: mujoco.MjModel, body: int, root: int) -> bool:
    """Whether ``body`` is ``root`` or below it in the body tree."""
    while body > 0 and body != root:
        body = int(model.body_parentid[body])
    return body == root


def _wxyz(rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    x, y, z, w = Rotation.from_matrix(rotation).as_quat()
    return np.array([w, x, y, z])


@dataclass(frozen=True, eq=False)
class MountedHand:
    """Where the hand's parts are in a compiled scene.

    Attributes:
        kinematics: The hand.
        mount: Body id of the mount.
        qpos: qpos address of each finger joint, in the kinematics' joint order, shape (J,).
        pads: Body id of each finger's tip body, shape (F,).
        geoms: Scene geom id of each of the hand's solid geoms, shape (G,).
        geom_names: Their names in the hand's model.
        finger_of_geom: Finger index of each solid geom, or F for the palm and shared bodies, shape (G,).
        loops: The hand's closed loops, their bodies as scene ids.
    """

    kinematics: HandKinematics
    mount: int
    qpos: NDArray[np.intp]
    pads: NDArray[np.intp]
    geoms: NDArray[np.intp]
    geom_names: tuple[str, ...]
    finger_of_geom: NDArray[np.intp]
    loops: tuple[Loop, ...] = ()

    @classmethod
    def find(cls, model: mujoco.MjModel, kinematics: HandKinematics) -> MountedHand:
        """Look the hand's parts up in a scene built with :func:`attach_hand`."""

        def scene_id(kind: mujoco.mjtObj, name: str) -> int:
            found = mujoco.mj_name2id(model, kind, PREFIX + name)
            if found < 0:
                raise LookupError(f"{PREFIX + name} is missing from the scene")
            return int(found)

        hand = kinematics.model
        joints = [scene_id(mujoco.mjtObj.mjOBJ_JOINT, n) for n in kinematics.joint_names]
        pads = [
            scene_id(mujoco.mjtObj.mjOBJ_BODY, mujoco.mj_id2name(hand, mujoco.mjtObj.mjOBJ_BODY, f.body))
            for f in kinematics.fingers
        ]
        solid = kinematics.solid_geoms
        names = tuple(kinematics.geom_name(int(g)) for g in solid)
        groups = kinematics.body_groups[hand.geom_bodyid[solid]]

        def body(b: int) -> int:
            return scene_id(mujoco.mjtObj.mjOBJ_BODY, mujoco.mj_id2name(hand, mujoco.mjtObj.mjOBJ_BODY, b))

        loops = tuple(
            dataclasses.replace(loop, bodies=(body(loop.bodies[0]), body(loop.bodies[1]))) for loop in kinematics.loops
        )
        return cls(
            kinematics,
            int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, MOUNT)),
            model.jnt_qposadr[joints].astype(np.intp),
            np.array(pads, dtype=np.intp),
            np.array([scene_id(mujoco.mjtObj.mjOBJ_GEOM, n) for n in names], dtype=np.intp),
            names,
            np.asarray(groups, dtype=np.intp),
            loops,
        )

    def pads_world(self, data: mujoco.MjData) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Every finger's pad point and pad normal in the world, each shape (F, 3), after kinematics."""
        points = np.empty((len(self.pads), 3))
        normals = np.empty((len(self.pads), 3))
        for f, (body, finger) in enumerate(zip(self.pads, self.kinematics.fingers, strict=True)):
            frame = data.xmat[body].reshape(3, 3)
            points[f] = data.xpos[body] + frame @ finger.offset
            normals[f] = frame @ finger.normal
        return points, normals
