"""Any hand's kinematics from its compiled MuJoCo model: the one kinematic truth.

:class:`HandKinematics` compiles a descriptor's model (:mod:`ogcp.planner.hands.loading`), checks
what the descriptor names against it (:mod:`~ogcp.planner.hands.fingers`: the palm, each finger's
tip body carried by joints relative to the palm, its joints on that chain), and answers in the palm
frame:

- the pads' contact points and normals of a configuration or a batch (``mj_kinematics``);
- random configurations within the joint limits, with MuJoCo's joint equalities (a joint that
  mirrors another, as the SDH's two base joints) kept and closed loops (:mod:`~ogcp.planner.hands.loops`)
  closed;
- which fingers (and the palm) collide with each other in a configuration (``mj_collision`` with
  every hand geom made collidable; the overlaps the model was built with, such as a convex hull
  that swallows the next link, are not collisions: :mod:`~ogcp.planner.hands.self_collision`).

A *configuration* is the vector of the hand's finger joints, :attr:`HandKinematics.joint_names`
order [rad or m]; joints outside the fingers (a wrist above the palm) stay at their reference.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.hands.couplings import joint_couplings, narrowed_drivers
from ogcp.planner.hands.descriptor import HandDescriptor
from ogcp.planner.hands.fingers import MOVABLE, Finger, body_id, resolve_finger
from ogcp.planner.hands.loading import compile_spec, hand_spec
from ogcp.planner.hands.loops import (
    CLOSED_GAP,
    CLOSING_STEPS,
    attached_bodies,
    find_loops,
    joints_with_loops,
    loop_system,
)
from ogcp.planner.hands.model_checks import (
    HandModelWarning,  # noqa: F401  (its first home: warnings filtered by this path)
    warn_about_model,
)
from ogcp.planner.hands.self_collision import (
    OVERLAP_SAMPLES,
    OVERLAP_SEED,
    collision_model,
    designed_overlaps,
    penetrating_pairs,
)
from ogcp.planner.hands.servos import add_servos
from ogcp.planner.infra.errors import OgcpError

__all__ = ["UNLIMITED_HINGE", "Finger", "HandKinematics"]

#: Range given to a hinge that has none [rad].
UNLIMITED_HINGE = (-np.pi, np.pi)


class HandKinematics:
    """A hand's compiled model and its fingertip kinematics in the palm frame.

    Args:
        descriptor: The hand (see :func:`ogcp.planner.hands.descriptor.load_descriptor`).

    Raises:
        OgcpError: One line naming the descriptor for a model MuJoCo refuses, an unknown palm or
            tip body, a tip body not below the palm, a finger with no joint, a named joint that is
            unknown, not on the finger's chain, or not a hinge or slide.
    """

    def __init__(self, descriptor: HandDescriptor) -> None:
        self.descriptor = descriptor
        spec = hand_spec(descriptor)
        for k, geom in enumerate(spec.geoms):  # scenes that attach the hand find its geoms by name
            if not geom.name:
                geom.name = f"ogcp_geom{k}"
        plain = compile_spec(descriptor, spec)
        self.palm = body_id(descriptor, plain, descriptor.palm, "palm")
        self.loops = find_loops(plain, attached_bodies(plain, self.palm))  # a scene holds the palm's root subtree
        fingers = [resolve_finger(descriptor, plain, self.palm, k) for k in range(len(descriptor.fingers))]
        self.fingers = tuple(dataclasses.replace(f, joints=joints_with_loops(f.joints, self.loops)) for f in fingers)
        joint_ids = sorted({j for finger in self.fingers for j in finger.joints})
        servos = add_servos(spec, plain, joint_ids, self.loops, descriptor.actuation, str(descriptor.path))
        self.servos, self.replaced_actuators = servos.joints, servos.replaced
        self.model = compile_spec(descriptor, spec)
        self.spec = spec
        self.data = mujoco.MjData(self.model)
        self.joint_ids = np.array(joint_ids, dtype=np.intp)
        self.joint_names = tuple(mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joint_ids)
        self.qpos_index = self.model.jnt_qposadr[self.joint_ids]
        self.limits = np.array([self._range(j) for j in joint_ids])
        self._couplings = joint_couplings(self.model, joint_ids)
        self.limits = narrowed_drivers(
            self.model, self.joint_names, joint_ids, self.limits, self._couplings, descriptor.path
        )
        self.reference_qpos = self._reference_qpos()
        self.reference_qpos[self.qpos_index] = self.complete(self.reference_qpos[self.qpos_index])
        self.independent = np.array(
            [k for k, j in enumerate(joint_ids) if j not in {dep for dep, _, _ in self._couplings}], dtype=np.intp
        )
        self.body_groups = self._body_groups()
        self.root = self._root()
        in_hand = np.array([self._is_below(int(b), self.root) for b in self.model.geom_bodyid], dtype=bool)
        self._collider = collision_model(self.model, in_hand)
        listed = [
            (
                body_id(descriptor, self.model, a, "ignore_collisions"),
                body_id(descriptor, self.model, b, "ignore_collisions"),
            )
            for a, b in descriptor.ignore_collisions
        ]
        samples = self.sample(OVERLAP_SAMPLES, OVERLAP_SEED)
        self.overlaps = designed_overlaps(self._collider, self._pose, self.reference(), samples, listed)
        self.palm_pose = self._palm_pose()
        warn_about_model(self)

    def _range(self, joint: int) -> tuple[float, float]:
        if self.model.jnt_limited[joint]:
            low, high = self.model.jnt_range[joint]
            return float(low), float(high)
        if self.model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_HINGE:
            return UNLIMITED_HINGE
        name = mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, joint)
        raise OgcpError(f"{self.descriptor.path}: slide joint {name!r} has no range; give it one in the model")

    def _reference_qpos(self) -> NDArray[np.float64]:
        qpos = self.model.qpos0.copy()
        qpos[self.qpos_index] = np.clip(qpos[self.qpos_index], self.limits[:, 0], self.limits[:, 1])
        return qpos

    def _body_groups(self) -> NDArray[np.intp]:
        """Each body's finger index, or len(fingers) for the palm and bodies no single finger owns."""
        palm_group = len(self.fingers)
        group = np.full(self.model.nbody, palm_group, dtype=np.intp)
        owners: dict[int, set[int]] = {}
        for f, finger in enumerate(self.fingers):
            first = min(self.model.jnt_bodyid[j] for j in finger.joints)
            for b in range(self.model.nbody):
                below_first = self._is_below(b, int(first))
                on_path = self._is_below(finger.body, b) and below_first
                if on_path or self._is_below(b, finger.body):
                    owners.setdefault(b, set()).add(f)
        for b, fs in owners.items():
            if len(fs) == 1:
                group[b] = fs.pop()
        return group

    def _is_below(self, body: int, ancestor: int) -> bool:
        while body != ancestor:
            if body == 0:
                return False
            body = int(self.model.body_parentid[body])
        return True

    def _root(self) -> int:
        """The body below the world whose subtree holds the palm (what a scene attaches)."""
        body = self.palm
        while self.model.body_parentid[body] != 0:
            body = int(self.model.body_parentid[body])
        return body

    def _palm_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The palm's world rotation (3, 3) and position (3,) [m] in the hand's own model, at the reference."""
        self._pose(self.model, self.data, self.reference())
        return self.data.xmat[self.palm].reshape(3, 3).copy(), self.data.xpos[self.palm].copy()

    def idle_joints(self) -> tuple[str, ...]:
        """Hinges and slides of the hand below its root that a scene welds at their reference.

        Those that move the palm (a wrist, or a floating base's slides and hinges between the root
        and the palm, driven or not: the simulated wrist holds the palm, rigidly), and those
        elsewhere that move no finger and no actuator drives.
        """
        model = self.model
        driven = {
            int(model.actuator_trnid[a, 0])
            for a in range(model.nu)
            if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
        }
        fingers = set(self.joint_ids.tolist())
        idle = []
        for j in range(model.njnt):
            body = int(model.jnt_bodyid[j])
            if j in fingers or int(model.jnt_type[j]) not in MOVABLE or not self._is_below(body, self.root):
                continue
            if j not in driven or self._is_below(self.palm, body):
                idle.append(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j))
        return tuple(idle)

    @property
    def solid_geoms(self) -> NDArray[np.intp]:
        """Hand geoms (below the root) that collide with anything: the ones the object can touch."""
        model = self.model
        below = np.array([self._is_below(int(model.geom_bodyid[g]), self.root) for g in range(model.ngeom)])
        solid = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
        return np.flatnonzero(below & solid)

    def geom_name(self, geom: int) -> str:
        """A hand geom's name (unnamed geoms were given ``ogcp_geomK``)."""
        return mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_GEOM, geom) or f"geom {geom}"

    def designed_pairs(self) -> set[tuple[str, str]]:
        """Geom pairs (by name) that overlap by design (:mod:`~ogcp.planner.hands.self_collision`): never collisions."""
        return {tuple(sorted((self.geom_name(a), self.geom_name(b)))) for a, b in self.overlaps.pairs}  # type: ignore[misc]

    # ----- configurations ----------------------------------------------------------------------

    def reference(self) -> NDArray[np.float64]:
        """The model's reference configuration, within limits, shape (J,)."""
        return self.reference_qpos[self.qpos_index].copy()

    def complete(self, angles: ArrayLike) -> NDArray[np.float64]:
        """``angles`` with every coupled joint set from its driver, shape (..., J)."""
        q = np.array(angles, dtype=float)
        position = {int(j): k for k, j in enumerate(self.joint_ids)}
        for dependent, driver, poly in self._couplings:
            base = self.model.qpos0[self.model.jnt_qposadr[dependent]]  # MuJoCo's equality is about qpos0
            if driver < 0:
                q[..., position[dependent]] = base + poly[0]
                continue
            x = q[..., position[driver]] - self.model.qpos0[self.model.jnt_qposadr[driver]]
            q[..., position[dependent]] = base + sum(c * x**p for p, c in enumerate(poly))
        return q

    def complete_derivative(self, angles: ArrayLike) -> NDArray[np.float64]:
        """d complete(angles) / d angles at one configuration, shape (J, J): coupled rows follow their driver."""
        q = np.asarray(angles, dtype=float)
        derivative = np.eye(len(self.joint_ids))
        position = {int(j): k for k, j in enumerate(self.joint_ids)}
        for dependent, driver, poly in self._couplings:
            derivative[position[dependent]] = 0.0
            if driver >= 0:
                x = q[position[driver]] - self.model.qpos0[self.model.jnt_qposadr[driver]]
                slope = sum(p * c * x ** (p - 1) for p, c in enumerate(poly) if p)
                derivative[position[dependent], position[driver]] = slope
        return derivative

    def check(self, angles: ArrayLike, tolerance: float = 1e-6) -> NDArray[np.float64]:
        """A configuration as floats, shape (J,), checked finite and within limits.

        Raises:
            OgcpError: Naming the first joint that is not finite or is outside its range.
        """
        q = np.asarray(angles, dtype=float)
        if q.shape != (len(self.joint_ids),):
            raise OgcpError(
                f"the {self.descriptor.name} hand's configuration has {len(self.joint_ids)} joints "
                f"({', '.join(self.joint_names)}); got shape {q.shape}"
            )
        low, high = self.limits[:, 0], self.limits[:, 1]
        bad = ~np.isfinite(q) | (q < low - tolerance) | (q > high + tolerance)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise OgcpError(
                f"the {self.descriptor.name} hand's joint {self.joint_names[k]} = {q[k]:.6g} is outside its range "
                f"[{low[k]:.6g}, {high[k]:.6g}]"
            )
        return q.copy()

    def sample(self, count: int, seed: int | np.random.SeedSequence) -> NDArray[np.float64]:
        """Configurations with independent joints uniform within their limits, shape (count, J).

        ``seed``: an integer, or a seed sequence for a stream of its own.
        """
        rng = np.random.default_rng(seed)
        q = np.tile(self.reference(), (count, 1))
        low, high = self.limits[self.independent, 0], self.limits[self.independent, 1]
        q[:, self.independent] = rng.uniform(low, high, size=(count, len(self.independent)))
        return self.close_loops(self.complete(q))

    def close_loops(self, angles: ArrayLike) -> NDArray[np.float64]:
        """Configurations (n, J) moved, loop joints only, to where every closed loop is closed (Gauss-Newton).

        Each step is the least-norm change of the loops' joints that closes their gaps to first order,
        within the limits, for at most :data:`~ogcp.planner.hands.loops.CLOSING_STEPS` steps. A
        configuration whose loops cannot close within the limits stays where the last step left it
        (the fit then reports the gap); a hand without loops is returned as given.
        """
        q = np.array(angles, dtype=float, ndmin=2)
        if not self.loops:
            return q
        looped = {j for loop in self.loops for j in loop.joints}
        columns = np.array([k for k, j in enumerate(self.joint_ids) if int(j) in looped], dtype=np.intp)
        dofs = self.model.jnt_dofadr[self.joint_ids[columns]]
        low, high = self.limits[columns, 0], self.limits[columns, 1]
        for row in q:
            for _ in range(CLOSING_STEPS):
                self._pose(self.model, self.data, row)
                mujoco.mj_comPos(self.model, self.data)
                gaps, jacobian = loop_system(self.model, self.data, self.loops)
                if np.abs(gaps).max(initial=0.0) < CLOSED_GAP:
                    break
                step = np.linalg.lstsq(jacobian[:, dofs], -gaps, rcond=None)[0]
                row[columns] = np.clip(row[columns] + step, low, high)
                row[:] = self.complete(row)
        return q

    def qpos(self, angles: ArrayLike) -> NDArray[np.float64]:
        """The full qpos of a configuration (other joints at their reference), shape (nq,)."""
        qpos = self.reference_qpos.copy()
        qpos[self.qpos_index] = angles
        return qpos

    # ----- kinematics --------------------------------------------------------------------------

    def _pose(self, model: mujoco.MjModel, data: mujoco.MjData, angles: ArrayLike) -> None:
        data.qpos[:] = self.qpos(angles)
        mujoco.mj_kinematics(model, data)

    def pads(self, angles: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Every finger's pad point and pad normal in the palm frame, each shape (F, 3) [m]."""
        self._pose(self.model, self.data, angles)
        return self._pads_now(self.data)

    def _pads_now(self, data: mujoco.MjData) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        rotation = data.xmat[self.palm].reshape(3, 3)
        origin = data.xpos[self.palm]
        points = np.empty((len(self.fingers), 3))
        normals = np.empty((len(self.fingers), 3))
        for f, finger in enumerate(self.fingers):
            frame = data.xmat[finger.body].reshape(3, 3)
            points[f] = (data.xpos[finger.body] + frame @ finger.offset - origin) @ rotation
            normals[f] = (frame @ finger.normal) @ rotation
        return points, normals

    def pads_many(self, angles: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`pads` of a batch, each shape (N, F, 3)."""
        q = np.atleast_2d(np.asarray(angles, dtype=float))
        points = np.empty((len(q), len(self.fingers), 3))
        normals = np.empty_like(points)
        for n, row in enumerate(q):
            points[n], normals[n] = self.pads(row)
        return points, normals

    def collisions(self, angles: ArrayLike) -> NDArray[np.bool_]:
        """Which groups collide in each configuration, shape (N, G, G) with G = fingers + 1.

        Group ``F`` (the last) is the palm and every body no single finger owns. Designed overlaps
        (:mod:`~ogcp.planner.hands.self_collision`) are not collisions.
        """
        q = np.atleast_2d(np.asarray(angles, dtype=float))
        size = len(self.fingers) + 1
        hits = np.zeros((len(q), size, size), dtype=bool)
        data = mujoco.MjData(self._collider)
        body = self._collider.geom_bodyid
        for n, row in enumerate(q):
            self._pose(self._collider, data, row)
            for g, h in penetrating_pairs(self._collider, data) - self.overlaps.pairs:
                a, b = self.body_groups[body[g]], self.body_groups[body[h]]
                hits[n, a, b] = hits[n, b, a] = True
        return hits

    def describe(self) -> dict[str, object]:
        """JSON-ready summary: joints, limits, fingers, servos added."""
        return {
            **self.descriptor.to_dict(),
            "joints": list(self.joint_names),
            "limits": self.limits.tolist(),
            "fingers": [f.name for f in self.fingers],
            "servos_added": list(self.servos),
            "actuators_replaced": list(self.replaced_actuators),
            "ignored_collisions": sorted(self.designed_pairs()),
        }
