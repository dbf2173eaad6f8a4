"""Inverse kinematics of the Schunk SDH: joint angles and palm pose that put the fingertips on a grasp.

The reachability model (:class:`ogcp.planner.hands.reachability.SDHReachability`) records, for a grasp,
the joint angles of its nearest *sampled* configuration, matched on the fingertips' shape
(pairwise distances and normal differences) only: at the default 10,000 samples those fingertips
miss the contacts by 15-20 mm once the palm is placed as well as it can be. :func:`fit_hand`
refines them: starting from the recorded angles and the rigid (Kabsch) palm pose, it solves

``min over q, R, t   sum_k |R tip_k(q) + t - target_k|^2 + w^2 |R pad_k(q) - n_k|^2``

within the joint limits (:data:`ogcp.planner.hands.sdh.JOINT_LIMITS`), by bounded least squares
(``scipy.optimize.least_squares``, trust region reflective). ``tip_k`` is finger k's fingertip
point (the end of its distal link, :func:`ogcp.planner.hands.sdh.forward_kinematics`), ``target_k``
the contact moved ``offset`` back along its inward normal ``n_k`` (where the centre of a finger of
radius ``offset`` is when its surface touches the contact), and ``pad_k`` the pad normal. With 13
unknowns for 9 position equations, a reachable grasp is met to numerical precision and the
remaining freedom turns the pads towards the surface; ``w`` [m] is how many metres of fingertip
misplacement one unit of normal difference is worth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from ogcp.planner.hands.reachability import self_collision_free
from ogcp.planner.hands.sdh import JOINT_LIMITS, JOINT_NAMES, forward_kinematics
from ogcp.planner.infra.errors import OgcpError

#: Default weight of the pad-normal term [m per unit normal difference]: a pad 11 deg off
#: (difference 0.2) costs as much as a fingertip 1 mm off its contact.
NORMAL_WEIGHT = 0.005
#: How far inside its limits a start is moved, so that the bounded solver starts feasible [rad].
LIMIT_MARGIN = 1e-9
#: How far along the pad normals the rigid start also matches the fingertips [m]: it turns the
#: pads towards the surface, not only the tips onto it.
RIGID_REACH = 0.03
#: Normal weights [m] the continuation start solves with, in turn (those above the fit's own weight),
#: before the final solve at that weight.
CONTINUATION = (0.32, 0.16, 0.08, 0.04, 0.02, 0.01)


@dataclass(frozen=True, eq=False)
class HandFit:
    """The hand's configuration and placement that best puts its fingertips on a grasp.

    Attributes:
        joint_angles: Joint angles in :data:`ogcp.planner.hands.sdh.JOINT_NAMES` order, shape (7,) [rad],
            within :data:`ogcp.planner.hands.sdh.JOINT_LIMITS`.
        rotation: Rotation from the palm frame to the world (object) frame, shape (3, 3).
        translation: Palm origin in the world frame, shape (3,) [m].
        residuals: Distance of each finger's fingertip point from its target, fingers in
            :data:`ogcp.planner.hands.sdh.FINGER_NAMES` order, shape (3,) [m].
        normal_angles: Angle between each pad normal and its contact's inward normal, shape (3,) [rad].
        collision_free: Whether links of different fingers keep their clearance
            (:func:`ogcp.planner.hands.reachability.self_collision_free`).
    """

    joint_angles: NDArray[np.float64]
    rotation: NDArray[np.float64]
    translation: NDArray[np.float64]
    residuals: NDArray[np.float64]
    normal_angles: NDArray[np.float64]
    collision_free: bool

    @property
    def max_residual(self) -> float:
        """The largest fingertip residual [m]."""
        return float(self.residuals.max())

    def to_world(self, points: ArrayLike) -> NDArray[np.float64]:
        """Palm-frame points, shape (..., 3) [m], in the world frame [m]."""
        return np.asarray(points, dtype=float) @ self.rotation.T + self.translation


def rigid_fit(source: ArrayLike, target: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The rotation and translation that best map ``source`` onto ``target`` (least squares, Kabsch).

    Args:
        source: Points, shape (k, 3) [m].
        target: Where they should go, shape (k, 3) [m].

    Returns:
        Rotation (3, 3), a proper one (determinant +1), and translation (3,) [m] with
        ``target ~ source @ rotation.T + translation``.
    """
    source, target = np.asarray(source, dtype=float), np.asarray(target, dtype=float)
    s0, t0 = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - s0).T @ (target - t0))
    flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T)) or 1.0])
    rotation = vt.T @ flip @ u.T
    return rotation, t0 - rotation @ s0


def fingertip_targets(points: ArrayLike, normals: ArrayLike, offset: float = 0.0) -> NDArray[np.float64]:
    """Where the fingertip points go: each contact moved ``offset`` [m] out along its inward normal, shape (3, 3) [m]."""
    return np.asarray(points, dtype=float) - offset * np.asarray(normals, dtype=float)


def _check(points: ArrayLike, normals: ArrayLike, angles: ArrayLike) -> tuple[NDArray[np.float64], ...]:
    points, normals = np.asarray(points, dtype=float), np.asarray(normals, dtype=float)
    angles = np.asarray(angles, dtype=float)
    if points.shape != (3, 3) or normals.shape != (3, 3):
        raise OgcpError(
            f"the SDH fit needs 3 contacts and 3 normals of shape (3, 3), got {points.shape}, {normals.shape}"
        )
    if angles.shape != (len(JOINT_NAMES),):
        raise OgcpError(f"the SDH fit starts from {len(JOINT_NAMES)} joint angles, got shape {angles.shape}")
    if not (np.isfinite(points).all() and np.isfinite(normals).all() and np.isfinite(angles).all()):
        raise OgcpError("the SDH fit needs finite contacts, normals and joint angles")
    return points, normals / np.linalg.norm(normals, axis=1, keepdims=True), angles


def evaluate_fit(
    angles: ArrayLike, rotation: ArrayLike, translation: ArrayLike, points: ArrayLike, normals: ArrayLike, offset: float
) -> HandFit:
    """How well a given configuration and palm pose put the fingertips on the contacts.

    Args:
        angles: Joint angles, shape (7,) [rad], within the joint limits.
        rotation: Palm-to-world rotation, shape (3, 3).
        translation: Palm origin in the world, shape (3,) [m].
        points: Each finger's contact, fingers in :data:`ogcp.planner.hands.sdh.FINGER_NAMES` order, shape (3, 3) [m].
        normals: Their inward unit normals, shape (3, 3).
        offset: Distance of a fingertip point from its contact along the normal [m] (the finger's radius).

    Returns:
        The fit with its residuals.
    """
    q: NDArray[np.float64] = np.clip(np.asarray(angles, dtype=float), JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
    turn, shift = np.asarray(rotation, dtype=float), np.asarray(translation, dtype=float)
    tips, pads = forward_kinematics(q)
    targets = fingertip_targets(points, normals, offset)
    residuals = np.linalg.norm(tips @ turn.T + shift - targets, axis=1)
    cosines = np.clip(np.einsum("ij,ij->i", pads @ turn.T, np.asarray(normals, dtype=float)), -1.0, 1.0)
    free = bool(self_collision_free(q)[0])
    return HandFit(q, turn, shift, residuals, np.arccos(cosines), free)


def fit_hand(
    points: ArrayLike,
    normals: ArrayLike,
    angles: ArrayLike,
    offset: float = 0.0,
    normal_weight: float = NORMAL_WEIGHT,
) -> HandFit:
    """Joint angles and palm pose that put the SDH's fingertips on three contacts (see the module docstring).

    Args:
        points: Each finger's contact, fingers in :data:`ogcp.planner.hands.sdh.FINGER_NAMES` order, shape (3, 3) [m].
        normals: Their inward unit normals, shape (3, 3): the pad normals wanted.
        angles: Starting joint angles (the recorded ones), shape (7,) [rad].
        offset: Distance of each fingertip point from its contact, back along the normal [m]: 0
            puts the points on the contacts, the finger's radius puts its surface there.
        normal_weight: Weight of the pad-normal term [m per unit normal difference], >= 0.

    Returns:
        The better of the refined fit and the start (recorded angles, rigidly placed), by the
        sum of squares minimised; its residuals say how far each fingertip is from its target.

    Raises:
        OgcpError: On shapes other than (3, 3) and (7,), non-finite values or a negative weight.
    """
    points, normals, start = _check(points, normals, angles)
    if not (np.isfinite(normal_weight) and normal_weight >= 0):
        raise OgcpError(f"normal_weight must be a finite number >= 0 [m], got {normal_weight!r}")
    low, high = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    start = np.clip(start, low + LIMIT_MARGIN, high - LIMIT_MARGIN)
    targets = fingertip_targets(points, normals, offset)
    tips, pads = forward_kinematics(start)
    # The rigid start: the tips onto their targets and, as far as their shape allows, the pads along the normals.
    base, shift = rigid_fit(
        np.vstack([tips, tips + RIGID_REACH * pads]), np.vstack([targets, targets + RIGID_REACH * normals])
    )

    def residual(x: NDArray[np.float64], weight: float) -> NDArray[np.float64]:
        rotation = Rotation.from_rotvec(x[7:10]).as_matrix() @ base
        tips, pads = forward_kinematics(np.clip(x[:7], low, high))
        placed = tips @ rotation.T + x[10:]
        return np.concatenate([(placed - targets).ravel(), weight * (pads @ rotation.T - normals).ravel()])

    bounds = (np.concatenate([low, np.full(6, -np.inf)]), np.concatenate([high, np.full(6, np.inf)]))

    def solve(x: NDArray[np.float64], weight: float) -> NDArray[np.float64]:
        found = least_squares(
            residual, x, args=(weight,), bounds=bounds, method="trf", x_scale="jac", xtol=1e-12, ftol=1e-12
        )
        return np.asarray(found.x, dtype=float)

    x0 = np.concatenate([start, np.zeros(3), shift])
    candidates = [x0, solve(x0, normal_weight)]
    # Continuation: the pads first turned towards the surface under a heavier normal term, then
    # the tips pulled onto the contacts; it leaves basins where a finger touches with its back.
    chained = x0
    for weight in (w for w in CONTINUATION if w > normal_weight):
        chained = solve(chained, weight)
    candidates.append(solve(chained, normal_weight))
    x = min(candidates, key=lambda c: float(np.sum(residual(c, normal_weight) ** 2)))
    rotation = Rotation.from_rotvec(x[7:10]).as_matrix() @ base
    return evaluate_fit(x[:7], rotation, x[10:], points, normals, offset)
