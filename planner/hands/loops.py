"""Closed kinematic loops of a hand: ``connect`` and ``weld`` equalities between its own bodies.

A four-bar linkage (a parallel gripper's jaw kept upright by a second link, Menagerie's Robotiq
2F-85) is written in MJCF as an open tree plus an equality that closes it. ogcp treats every joint
on the loop as part of the finger the loop moves (sampled, fitted, never welded as idle), fits the
hand with the loop's gap as a residual (:func:`loop_gap`), and lets the loop's force hold the
passive joints in the statics (MuJoCo's own equality rows). The loop's joints that no actuator
drives get no servo of their own when another joint of the loop is driven: the loop passes that
drive on.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

_MOVABLE = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
#: [m per rad] A weld's turning gap counts as this lever's length (a finger link's), in fits and tolerances.
LOOP_LEVER = 0.05
#: Gauss-Newton steps that close a sampled configuration's loops, and the gap that counts as closed [m].
CLOSING_STEPS = 20
CLOSED_GAP = 1e-7
_CLOSING = (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD))


@dataclass(frozen=True, eq=False)
class Loop:
    """One closing equality of a hand model, in that model's ids.

    Attributes:
        name: "body1-body2", for messages.
        kind: ``mjEQ_CONNECT`` (points meet: 3 rows) or ``mjEQ_WELD`` (frames meet: 6 rows).
        bodies: The two bodies the equality joins.
        anchors: The meeting point in each body's frame, shape (2, 3) [m].
        turn: For a weld, body 2's frame in body 1's frame where they meet, as a rotation matrix
            (3, 3); identity for a connect.
        joints: The hinges and slides on the loop: from each body up to their common ancestor.
    """

    name: str
    kind: int
    bodies: tuple[int, int]
    anchors: NDArray[np.float64]
    turn: NDArray[np.float64]
    joints: tuple[int, ...]

    @property
    def rows(self) -> int:
        """Residual rows of its gap: 3 (connect) or 6 (weld)."""
        return 3 if self.kind == int(mujoco.mjtEq.mjEQ_CONNECT) else 6


def attached_bodies(model: mujoco.MjModel, palm: int) -> list[int]:
    """The bodies of the subtree below the world that holds the palm (what a scene attaches)."""
    root = palm
    while model.body_parentid[root] != 0:
        root = int(model.body_parentid[root])
    below = [root]
    for body in range(root + 1, model.nbody):  # MuJoCo numbers a subtree's bodies after its root
        if int(model.body_parentid[body]) in below:
            below.append(body)
    return below


def joints_with_loops(joints: Iterable[int], loops: Iterable[Loop]) -> tuple[int, ...]:
    """``joints`` with those of every loop they belong to (and of the loops those close), sorted."""
    grown, loops = set(joints), tuple(loops)
    changed = True
    while changed:
        changed = False
        for loop in loops:
            if grown & set(loop.joints) and not set(loop.joints) <= grown:
                grown |= set(loop.joints)
                changed = True
    return tuple(sorted(grown))


def find_loops(model: mujoco.MjModel, hand_bodies: Iterable[int]) -> tuple[Loop, ...]:
    """The active ``connect`` and ``weld`` equalities between two of ``hand_bodies`` (compiled model).

    Body and site forms both count; a site's anchor is its position in its body.
    """
    inside = {int(b) for b in hand_bodies}
    loops = []
    for e in range(model.neq):
        kind = int(model.eq_type[e])
        if kind not in _CLOSING or not model.eq_active0[e]:
            continue
        first, second = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        if int(model.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE):
            sites = (first, second)
            if min(sites) < 0:
                continue
            bodies = (int(model.site_bodyid[first]), int(model.site_bodyid[second]))
            anchors = np.array([model.site_pos[first], model.site_pos[second]], dtype=float)
            turn = _site_turn(model, first, second) if kind == int(mujoco.mjtEq.mjEQ_WELD) else np.eye(3)
        else:
            bodies = (first, max(second, 0))
            anchors, turn = _body_anchors(model, e, kind)
        if not set(bodies) <= inside:
            continue
        names = "-".join(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body {b}" for b in bodies)
        loops.append(Loop(names, kind, bodies, anchors, turn, _loop_joints(model, *bodies)))
    return tuple(loops)


def _body_anchors(model: mujoco.MjModel, e: int, kind: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Anchors (2, 3) and relative turn of a body-form equality, as MuJoCo's compiler stored them.

    A connect keeps its anchor in body 1 (``eq_data[0:3]``) and the matching point in body 2
    (``eq_data[3:6]``). A weld keeps the anchor in body 2 (``eq_data[0:3]``), the same point in
    body 1 (``eq_data[3:6]``) and body 2's orientation in body 1 (``eq_data[6:10]``, wxyz).
    """
    data = model.eq_data[e]
    if kind == int(mujoco.mjtEq.mjEQ_CONNECT):
        return np.array([data[0:3], data[3:6]], dtype=float), np.eye(3)
    turn = np.empty(9)
    quat = np.asarray(data[6:10], dtype=float)
    mujoco.mju_quat2Mat(turn, quat / np.linalg.norm(quat))
    return np.array([data[3:6], data[0:3]], dtype=float), turn.reshape(3, 3)


def _site_turn(model: mujoco.MjModel, first: int, second: int) -> NDArray[np.float64]:
    """Site 2's frame in site 1's frame when they meet (they coincide): body 1 to site 1 to site 2."""
    one, two = np.empty(9), np.empty(9)
    mujoco.mju_quat2Mat(one, model.site_quat[first])
    mujoco.mju_quat2Mat(two, model.site_quat[second])
    # Body frames: R_b1 R_s1 = R_b2 R_s2 where the sites meet, so R_b1^T R_b2 = R_s1 R_s2^T.
    return np.asarray(one.reshape(3, 3) @ two.reshape(3, 3).T, dtype=float)


def _loop_joints(model: mujoco.MjModel, first: int, second: int) -> tuple[int, ...]:
    """Hinges and slides of the bodies from ``first`` and ``second`` up to (not including) their common ancestor."""
    ancestors = []
    body = first
    while True:
        ancestors.append(body)
        if body == 0:
            break
        body = int(model.body_parentid[body])
    body, above = second, []
    while body not in ancestors:
        above.append(body)
        body = int(model.body_parentid[body])
    common = body
    path = ancestors[: ancestors.index(common)] + above
    joints = [j for j in range(model.njnt) if int(model.jnt_bodyid[j]) in path and int(model.jnt_type[j]) in _MOVABLE]
    return tuple(sorted(joints))


def loop_gap(
    model: mujoco.MjModel, data: mujoco.MjData, loop: Loop
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """How far a loop is open in a posed state (``mj_kinematics`` done).

    Returns:
        The gap: body 1's anchor minus body 2's [m], then for a weld the rotation vector from body
        2's frame to where the loop wants it [rad], shape (3,) or (6,); and both anchors in the
        world, shape (2, 3) [m].
    """
    points = np.array(
        [
            data.xpos[b] + data.xmat[b].reshape(3, 3) @ anchor
            for b, anchor in zip(loop.bodies, loop.anchors, strict=True)
        ]
    )
    gap = points[0] - points[1]
    if loop.kind == int(mujoco.mjtEq.mjEQ_CONNECT):
        return gap, points[0], points[1]
    error = _turn_error(data, loop)
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, error.ravel())
    turn = np.empty(3)
    mujoco.mju_quat2Vel(turn, quat, 1.0)
    return np.concatenate([gap, turn]), points[0], points[1]


def _turn_error(data: mujoco.MjData, loop: Loop) -> NDArray[np.float64]:
    """The turn (3, 3) that would bring a weld's body 2 where the loop wants it, in the world."""
    wanted = data.xmat[loop.bodies[0]].reshape(3, 3) @ loop.turn
    return np.asarray(wanted @ data.xmat[loop.bodies[1]].reshape(3, 3).T, dtype=float)


def turn_rates(data: mujoco.MjData, loop: Loop) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(A1, A2)`` with d(turning gap) = A1 w1 - A2 w2 for the bodies' world angular velocities w, each (3, 3).

    The gap is the rotation vector of ``E = R1 T R2^T``, which turns at ``w1 - E w2`` in the
    world; its rotation vector changes by the inverse left Jacobian of SO(3) of that.
    """
    error = _turn_error(data, loop)
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, error.ravel())
    turn = np.empty(3)
    mujoco.mju_quat2Vel(turn, quat, 1.0)
    inverse = _so3_left_jacobian_inverse(turn)
    return inverse, inverse @ error


def _so3_left_jacobian_inverse(vector: NDArray[np.float64]) -> NDArray[np.float64]:
    angle = float(np.linalg.norm(vector))
    cross = np.array([[0.0, -vector[2], vector[1]], [vector[2], 0.0, -vector[0]], [-vector[1], vector[0], 0.0]])
    if angle < 1e-8:
        return np.eye(3) - 0.5 * cross
    factor = 1.0 / angle**2 - (1.0 + np.cos(angle)) / (2.0 * angle * np.sin(angle))
    return np.asarray(np.eye(3) - 0.5 * cross + factor * (cross @ cross), dtype=float)


def loop_system(
    model: mujoco.MjModel, data: mujoco.MjData, loops: Iterable[Loop]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Every loop's gap and its Jacobian over all dofs (``mj_kinematics`` and ``mj_comPos`` done).

    A weld's turning gap counts as :data:`LOOP_LEVER` times its angle.

    Returns:
        Gaps, shape (R,) [m]; d gaps / d qvel, shape (R, nv).
    """
    gaps, rows = [np.zeros(0)], [np.zeros((0, model.nv))]
    first, second = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    turn_first, turn_second = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    for loop in loops:
        gap, one, two = loop_gap(model, data, loop)
        mujoco.mj_jac(model, data, first, turn_first, one, loop.bodies[0])
        mujoco.mj_jac(model, data, second, turn_second, two, loop.bodies[1])
        gaps.append(gap[:3])
        rows.append(first - second)
        if loop.rows == 6:
            one_rate, two_rate = turn_rates(data, loop)
            gaps.append(LOOP_LEVER * gap[3:])
            rows.append(LOOP_LEVER * (one_rate @ turn_first - two_rate @ turn_second))
    return np.concatenate(gaps), np.vstack(rows)
