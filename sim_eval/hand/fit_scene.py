"""The hand and the object's convex parts in one MuJoCo model: kinematics and penetration depths for fits.

:class:`FitScene` poses the hand (palm pose and finger joints) and measures, per solid hand geom,
how deep it is inside the object and inside other links (``mj_collision`` with zero margins). The
hand's designed overlaps (:mod:`ogcp.planner.hands.self_collision`) are not counted.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.sim_eval.hand.mount import PREFIX, MountedHand, attach_hand
from ogcp.sim_eval.scene.collision import Part


class FitScene:
    """The hand and the object's convex parts in one MuJoCo model, for kinematics and distances.

    Args:
        kinematics: The hand.
        parts: The object's convex parts, each ``(vertices (v, 3) [m], faces (f, 3))``, in the
            world frame; none: no collision terms.
        length_scale: The factor on the fit's tolerances (:func:`~ogcp.sim_eval.hand.fit.tolerance_scale`
            of the object's size); 1: as declared.
    """

    def __init__(self, kinematics: HandKinematics, parts: Sequence[Part] = (), length_scale: float = 1.0) -> None:
        if not (np.isfinite(length_scale) and length_scale > 0):
            raise ValueError(f"length_scale must be a positive number, got {length_scale!r}")
        #: The factor on the fit's tolerances.
        self.length_scale = float(length_scale)
        spec = mujoco.MjSpec()
        # A free mount: MuJoCo never collides two bodies welded to the world, so a fixed palm
        # would pass through a fixed object unseen.
        attach_hand(spec, kinematics, free=True)
        body = spec.worldbody.add_body(name="ogcp_object")
        for k, (vertices, faces) in enumerate(parts):
            spec.add_mesh(name=f"ogcp_part{k}", uservert=np.ravel(vertices).tolist(), userface=np.ravel(faces).tolist())
            body.add_geom(name=f"ogcp_part{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"ogcp_part{k}")
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.hand = MountedHand.find(self.model, kinematics)
        self.kinematics = kinematics
        self._mount_qpos = int(self.model.jnt_qposadr[self.model.body_jntadr[self.hand.mount]])
        joints = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, PREFIX + n) for n in kinematics.joint_names]
        #: dof address of each finger joint, in the kinematics' joint order, shape (J,).
        self.dofs = self.model.jnt_dofadr[joints].astype(np.intp)
        model = self.model
        # Every hand geom collides with every other and with the object; nothing else does.
        model.geom_contype[:] = 0
        model.geom_conaffinity[:] = 0
        self.object_geoms = np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"ogcp_part{k}") for k in range(len(parts))],
            dtype=np.intp,
        )
        for ids in (self.hand.geoms, self.object_geoms):
            model.geom_contype[ids] = 1
            model.geom_conaffinity[ids] = 1
        model.body_contype[:] = 1
        model.body_conaffinity[:] = 1
        model.geom_margin[:] = 0.0
        self._slot = {int(g): i for i, g in enumerate(self.hand.geoms)}
        #: Scene ids of the hand's solid geoms.
        self.hand_geom_ids = frozenset(self._slot)
        self._object = set(self.object_geoms.tolist())
        designed = kinematics.designed_pairs()
        names = self.hand.geom_names
        self._designed = {
            (int(a), int(b))
            for i, a in enumerate(self.hand.geoms)
            for j, b in enumerate(self.hand.geoms)
            if tuple(sorted((names[i], names[j]))) in designed
        }

    def pose(self, angles: ArrayLike, rotation: NDArray[np.float64], translation: NDArray[np.float64]) -> None:
        """Put the hand in a configuration with its palm at (rotation, translation); run kinematics."""
        self.data.qpos[:] = self.model.qpos0
        self.data.qpos[self._mount_qpos : self._mount_qpos + 3] = translation
        self.data.qpos[self._mount_qpos + 3 : self._mount_qpos + 7] = _wxyz(rotation)
        self.data.qpos[self.hand.qpos] = angles
        mujoco.mj_kinematics(self.model, self.data)

    def depths(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Per solid hand geom, its depth inside the object and inside other links, each shape (G,) [m]."""
        into_object, into_hand, _ = self.deepest()
        return into_object, into_hand

    def deepest(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.intp]]:
        """:meth:`depths`, and per solid hand geom the contact (index into ``data.contact``) of its
        larger depth, -1 where it is inside nothing, shape (G,)."""
        mujoco.mj_collision(self.model, self.data)
        into_object = np.zeros(len(self.hand.geoms))
        into_hand = np.zeros(len(self.hand.geoms))
        which = np.full(len(self.hand.geoms), -1, dtype=np.intp)
        ncon = self.data.ncon
        if not ncon:
            return into_object, into_hand, which
        depth = -self.data.contact.dist[:ncon]
        pairs = self.data.contact.geom[:ncon]
        for k in np.flatnonzero(depth > 0):  # the few penetrating contacts, not every candidate
            a, b = int(pairs[k, 0]), int(pairs[k, 1])
            if a in self._object or b in self._object:
                g = self._slot.get(b if a in self._object else a)
                if g is not None and depth[k] > into_object[g]:
                    into_object[g] = depth[k]
                    which[g] = k if depth[k] >= into_hand[g] else which[g]
            elif (min(a, b), max(a, b)) not in self._designed and a in self._slot and b in self._slot:
                for g in (self._slot[a], self._slot[b]):
                    if depth[k] > into_hand[g]:
                        into_hand[g] = depth[k]
                        which[g] = k if depth[k] >= into_object[g] else which[g]
        return into_object, into_hand, which


def _wxyz(rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    quat = np.empty(4)
    # MuJoCo's own conversion: a fit calls this for every residual, scipy's costs 40x as much.
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation, dtype=float).ravel())
    return quat
