"""Analytic Jacobians of the hand fit's residuals, from MuJoCo's ``mj_jac``.

Finite differences cost one forward kinematics per unknown and iteration: 20-30 per Jacobian of a
five-finger hand. Here one pass gives every
column: a point fixed to a link moves with ``jacp`` and turns with ``jacr`` per finger joint
(coupled joints through :meth:`HandKinematics.complete_derivative`), and with the palm's pose as
``t + exp(w) R0 x``, whose rotation-vector derivative is ``-[x - t]_x J_l(w)`` (``J_l`` the left
Jacobian of SO(3)).
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.loops import LOOP_LEVER, loop_gap, turn_rates
from ogcp.sim_eval.hand.fit_scene import FitScene


def skew(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cross-product matrix of a 3-vector: ``skew(a) @ b == cross(a, b)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def so3_left_jacobian(vector: NDArray[np.float64]) -> NDArray[np.float64]:
    """``J_l(w)``: ``exp(w + d) = exp(J_l(w) d) exp(w)`` to first order, shape (3, 3)."""
    angle = float(np.linalg.norm(vector))
    cross = skew(vector)
    if angle < 1e-8:
        return np.eye(3) + 0.5 * cross
    return np.eye(3) + (1.0 - np.cos(angle)) / angle**2 * cross + (angle - np.sin(angle)) / angle**3 * (cross @ cross)


class PoseJacobian:
    """Point and direction Jacobians of the posed hand with respect to the fit's unknowns.

    The unknowns are the finger joints ``variables`` (indices into the kinematics' joint order,
    independent ones) followed, when ``palm`` is set, by the palm's rotation vector ``w`` and
    translation ``t``. Build one after :meth:`FitScene.pose`.

    Args:
        scene: The posed scene.
        angles: The configuration it is posed in, shape (J,).
        variables: The finger joints that are unknowns, shape (V,).
        palm: ``(w, t)`` of the pose when the palm's pose is unknown too, else None.
    """

    def __init__(
        self,
        scene: FitScene,
        angles: NDArray[np.float64],
        variables: NDArray[np.intp],
        palm: tuple[NDArray[np.float64], NDArray[np.float64]] | None,
    ) -> None:
        self.scene = scene
        mujoco.mj_comPos(scene.model, scene.data)  # mj_jac reads cdof and subtree_com, which mj_kinematics leaves
        self._coupling = scene.kinematics.complete_derivative(angles)[:, variables]  # (J, V)
        self._palm = None if palm is None else (so3_left_jacobian(palm[0]), np.asarray(palm[1], dtype=float))
        self.columns = len(variables) + (0 if palm is None else 6)
        nv = scene.model.nv
        self._jacp, self._jacr = np.zeros((3, nv)), np.zeros((3, nv))

    def _joint_parts(self, point: NDArray[np.float64], body: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        mujoco.mj_jac(self.scene.model, self.scene.data, self._jacp, self._jacr, point, body)
        dofs = self.scene.dofs
        return self._jacp[:, dofs] @ self._coupling, self._jacr[:, dofs] @ self._coupling

    def point(self, point: NDArray[np.float64], body: int) -> NDArray[np.float64]:
        """d point / d unknowns for a point fixed to a hand body, shape (3, columns)."""
        moved, _ = self._joint_parts(point, body)
        if self._palm is None:
            return moved
        left, translation = self._palm
        return np.hstack([moved, -skew(point - translation) @ left, np.eye(3)])

    def point_and_direction(
        self, point: NDArray[np.float64], direction: NDArray[np.float64], body: int
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """d point and d direction / d unknowns for a point and a unit vector fixed to a hand body."""
        moved, turned = self._joint_parts(point, body)
        turn = -skew(direction) @ turned  # d n = omega x n
        if self._palm is None:
            return moved, turn
        left, translation = self._palm
        moved = np.hstack([moved, -skew(point - translation) @ left, np.eye(3)])
        turn = np.hstack([turn, -skew(direction) @ left, np.zeros((3, 3))])
        return moved, turn

    def turn(self, body: int) -> NDArray[np.float64]:
        """d (rotation of a hand body) / d unknowns, as a rotation vector in the world, shape (3, columns)."""
        _, turned = self._joint_parts(self.scene.data.xpos[body], body)
        if self._palm is None:
            return turned
        return np.hstack([turned, self._palm[0], np.zeros((3, 3))])


def loop_gaps(scene: FitScene) -> NDArray[np.float64]:
    """Every closed loop's gap in the posed scene, turns as :data:`LOOP_LEVER` lengths, shape (R,) [m]."""
    parts = [np.zeros(0)]
    for loop in scene.hand.loops:
        gap, _, _ = loop_gap(scene.model, scene.data, loop)
        parts.append(np.concatenate([gap[:3], LOOP_LEVER * gap[3:]]))
    return np.concatenate(parts)


def loop_rows(scene: FitScene, jac: PoseJacobian) -> NDArray[np.float64]:
    """d :func:`loop_gaps` / d unknowns, shape (R, columns)."""
    rows = [np.zeros((0, jac.columns))]
    for loop in scene.hand.loops:
        _, first, second = loop_gap(scene.model, scene.data, loop)
        rows.append(jac.point(first, loop.bodies[0]) - jac.point(second, loop.bodies[1]))
        if loop.rows == 6:  # the turning gap moves with the bodies' turns
            one_rate, two_rate = turn_rates(scene.data, loop)
            rows.append(LOOP_LEVER * (one_rate @ jac.turn(loop.bodies[0]) - two_rate @ jac.turn(loop.bodies[1])))
    return np.vstack(rows)
