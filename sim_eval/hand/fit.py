"""Fit a hand to a grasp: pads on the contacts, within joint limits, no link inside the object.

The unknowns are the hand's independent finger joints and the palm's pose. :func:`fit_hand` solves

``min  sum_k |centre_k - (c_k - r_k n_k)|^2 + w^2 |pad_k - n_k|^2 + sum_g depth_g^2 + lam^2 |q_o - q_o0|^2``

by bounded least squares (``scipy.optimize.least_squares``, trust region reflective; joints within
their limits), in MuJoCo (``mj_kinematics``, ``mj_collision``), with analytic Jacobians
(:mod:`~ogcp.sim_eval.hand.fit_jacobian`; a depth's row from its deepest contact's normal).
``centre_k`` is chosen finger k's centre of pad rounding (the pad point moved ``r_k``, its
``tip_radius``, back along the pad normal) and ``c_k``, ``n_k`` the contact and its inward normal,
so a pad of that rounding touches the contact; ``pad_k`` is the pad normal; ``depth_g`` how far hand geom g is inside the object or
inside another link beyond :data:`LINK_TOLERANCE` (pairs that touch in the hand's reference pose
are its design); ``q_o`` the joints of the fingers that take no contact, kept near their start.
The first solve leaves collisions out; when a link ends up inside the object, a second solve adds
them. The hand's own solver options never matter here: only kinematics and distances are used.

A flat pad (a finger's ``pad_width``) weighs its tilt by :data:`FLAT_PAD_WEIGHT` widths and its
centre's offset along the contact's surface by :data:`FLAT_PAD_SLIDE`: it lies flat and may touch
anywhere within half its width; its residual is its face's distance from the contact's surface and
its slide beyond that half width.

A fit is *realised* (:class:`~ogcp.sim_eval.hand.fit_result.HandFit`) when every chosen finger's
residual is within :data:`RESIDUAL_TOLERANCE` and no link is inside the object or another link
beyond :data:`LINK_TOLERANCE`, both grown with objects larger than the simulation's reference.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.hand.fit_jacobian import PoseJacobian, loop_gaps, loop_rows
from ogcp.sim_eval.hand.fit_result import (
    LINK_TOLERANCE,
    LOOP_TOLERANCE,
    RESIDUAL_TOLERANCE,
    HandFit,
    better_fit,
    tolerance_scale,
)
from ogcp.sim_eval.hand.fit_scene import FitScene

__all__ = [
    "LINK_TOLERANCE",
    "LOOP_TOLERANCE",
    "RESIDUAL_TOLERANCE",
    "HandFit",
    "fit_hand",
    "measure_pose",
    "rigid_fit",
    "tolerance_scale",
]

#: Weight of a loop's gap, relative to a pad residual: the linkage closes before the pads reach.
LOOP_WEIGHT = 10.0
#: Weight of the pad-normal term, as a multiple of the pad's rounding radius [m per unit difference].
NORMAL_WEIGHT_RADII = 0.5
#: Weight of a flat pad's normal term, as a multiple of its width [m per unit difference]: a 20 mm
#: jaw weighs a tilt 100 mm per radian, so that it lies flat (1.7 degrees of tilt on a 3.5 cm box
#: touched with a jaw's edge, and a 2 N load rolled the box out of a 15 N pinch).
FLAT_PAD_WEIGHT = 5.0
#: Weight of a flat pad's slide along the surface, relative to its distance from it: a flat pad
#: touches wherever its face lies on the contact's surface, so sliding costs little (10 mm of slide
#: as much as 1 mm off the surface) and is free, for being realised, within half its width.
FLAT_PAD_SLIDE = 0.1
#: Weight of keeping the other fingers where they started [m per rad].
REST_WEIGHT = 1e-3
#: Weight of a link's depth beyond the tolerance, relative to a pad residual.
COLLISION_WEIGHT = 3.0
#: Weight of a sprung joint's distance from where its spring pushes it (its spring reference within
#: its range) [m per full range]: where the pads leave it free, an underactuated finger's passive
#: joint settles where its spring holds it (the Robotiq 2F-85's spring link keeps its coupler on
#: its stop), as the closed hand will.
SPRING_WEIGHT = 1e-3
#: How far inside each joint's range a start is moved, as a fraction of the range.
START_INSET = 1e-3
#: How far along the pad normals the rigid start also matches the pads [in pad radii]: it turns the
#: pads toward the surface, not only onto it.
RIGID_REACH_RADII = 3.0
#: Most residual evaluations of one solve: past a few hundred, a solve only creeps (a collision
#: solve ran to scipy's 100 per unknown, 2,800, within 1e-6 of its cost at 400).
MAX_EVALUATIONS = 400


def rigid_fit(source: ArrayLike, target: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Rotation R (3, 3) and translation t (3,) minimising sum |R source_i + t - target_i|^2 (Kabsch).

    Args:
        source: Points, shape (k, 3), k >= 1.
        target: Points, shape (k, 3).
    """
    source, target = np.asarray(source, dtype=float), np.asarray(target, dtype=float)
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - cs).T @ (target - ct))
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return rotation, ct - rotation @ cs


Pose = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


@dataclass(frozen=True, eq=False)
class _Targets:
    """What one fit aims at: the chosen fingers, their pad centres' targets and the contacts' normals."""

    scene: FitScene
    fingers: tuple[int, ...]
    targets: NDArray[np.float64]
    normals: NDArray[np.float64]
    radii: NDArray[np.float64]
    widths: NDArray[np.float64]

    def projections(self) -> NDArray[np.float64]:
        """Each pad's weights of its centre's offset, shape (m, 3, 3): the identity for a round pad;
        for a flat one, the offset off the contact's surface in full, the slide along it by
        :data:`FLAT_PAD_SLIDE`."""
        normal = np.einsum("ki,kj->kij", self.normals, self.normals)
        flat = normal + FLAT_PAD_SLIDE * (np.eye(3) - normal)
        return np.where((self.widths > 0)[:, None, None], flat, np.eye(3))

    def residuals(self, centre: NDArray[np.float64]) -> NDArray[np.float64]:
        """How far each pad is from touching its contact, shape (m,) [m]: a round pad's centre from its
        target; a flat pad's face from the contact's surface and, beyond half its width, its centre
        along the surface."""
        offset = centre - self.targets
        along = np.einsum("ki,ki->k", offset, self.normals)
        slide = np.linalg.norm(offset - along[:, None] * self.normals, axis=1)
        flat = np.hypot(along, np.maximum(slide - 0.5 * self.widths, 0.0))
        return np.where(self.widths > 0, flat, np.linalg.norm(offset, axis=1))

    def centres(self, pose: Pose) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The chosen pads' centres of rounding and normals in a pose, each shape (m, 3)."""
        self.scene.pose(*pose)
        world, pad = self.scene.hand.pads_world(self.scene.data)
        world, pad = world[list(self.fingers)], pad[list(self.fingers)]
        return world - self.radii[:, None] * pad, pad

    def summary(self, pose: Pose) -> HandFit:
        """The fit of a pose: residuals, pad angles, penetrations."""
        centre, pad = self.centres(pose)
        scene = self.scene
        into_object, into_hand = scene.depths() if len(scene.object_geoms) else (np.zeros(1), np.zeros(1))
        deepest = np.maximum(into_object, into_hand)
        worst = scene.hand.geom_names[int(np.argmax(deepest))] if deepest.max() > 0 else None
        cosine = np.clip(np.einsum("ij,ij->i", pad, self.normals), -1.0, 1.0)
        gaps = loop_gaps(scene).reshape(-1, 3)
        return HandFit(
            joint_angles=pose[0],
            rotation=pose[1],
            translation=pose[2],
            fingers=self.fingers,
            residuals=self.residuals(centre),
            normal_angles=np.arccos(cosine),
            penetration=float(into_object.max()),
            self_penetration=float(into_hand.max()),
            worst_link=worst,
            finger_names=tuple(scene.kinematics.fingers[f].name for f in self.fingers),
            loop_gap=float(np.linalg.norm(gaps, axis=1).max(initial=0.0)),
            length_scale=scene.length_scale,
        )


def fit_hand(
    scene: FitScene,
    fingers: Sequence[int],
    points: ArrayLike,
    normals: ArrayLike,
    start: ArrayLike | None = None,
    palm: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> HandFit:
    """Fit the hand so that finger ``fingers[k]`` touches contact k.

    Args:
        scene: The hand and the object (:class:`FitScene`).
        fingers: The chosen finger indices, one per contact.
        points: Contacts in the world (object) frame, shape (m, 3) [m].
        normals: Inward unit normals at the contacts, shape (m, 3).
        start: Starting configuration, shape (J,) (the plan's nearest sample); None: the reference.
        palm: The palm's pose (rotation (3, 3), position (3,) [m]) held fixed; None: fitted too.

    Returns:
        The best fit found (check :attr:`HandFit.realised`).

    Raises:
        OgcpError: For inputs of the wrong shape, non-finite values or fingers out of range.
    """
    kin = scene.kinematics
    chosen = tuple(int(f) for f in fingers)
    where = np.asarray(points, dtype=float)
    inward = np.asarray(normals, dtype=float)
    m = len(chosen)
    if where.shape != (m, 3) or inward.shape != (m, 3) or not (np.isfinite(where).all() and np.isfinite(inward).all()):
        raise OgcpError(
            f"a hand fit needs finite contacts and normals of shape ({m}, 3), got {where.shape} and {inward.shape}"
        )
    if len(set(chosen)) != m or not all(0 <= f < len(kin.fingers) for f in chosen):
        raise OgcpError(f"fingers {list(chosen)} must be distinct indices below {len(kin.fingers)}")
    inward = inward / np.linalg.norm(inward, axis=1, keepdims=True)
    q0 = kin.reference() if start is None else kin.check(start, tolerance=1e-6)
    # Strictly inside the limits: the trust region's scaling takes no step off a bound it starts on.
    inset = START_INSET * (kin.limits[:, 1] - kin.limits[:, 0])
    q0 = kin.complete(np.clip(q0, kin.limits[:, 0] + inset, kin.limits[:, 1] - inset))
    radii = np.array([kin.fingers[f].radius for f in chosen])
    widths = np.array([kin.fingers[f].width for f in chosen])
    aim = _Targets(scene, chosen, where - radii[:, None] * inward, inward, radii, widths)
    weigh = aim.projections()  # (m, 3, 3)
    weights = np.maximum(NORMAL_WEIGHT_RADII * float(radii.mean()), FLAT_PAD_WEIGHT * widths)  # (m,)
    free = kin.independent
    chosen_joints = {j for f in chosen for j in kin.fingers[f].joints}
    resting = np.array([k for k in free if int(kin.joint_ids[k]) not in chosen_joints], dtype=np.intp)

    # Rigid start: the palm placed so the start configuration's pads (and points along them) meet the targets.
    local, pad_local = kin.pads(q0)
    local, pad_local = local[list(chosen)], pad_local[list(chosen)]
    local_centres = local - radii[:, None] * pad_local
    reach = RIGID_REACH_RADII * radii[:, None]
    if palm is None:
        rotation0, shift0 = rigid_fit(
            np.vstack([local_centres, local_centres + reach * pad_local]),
            np.vstack([aim.targets, aim.targets + reach * inward]),
        )
    else:
        rotation0, shift0 = np.asarray(palm[0], dtype=float), np.asarray(palm[1], dtype=float)
    pose_variables = 6 if palm is None else 0
    # The fingers that touch nothing move only to clear a collision: without the collision terms
    # they are not variables (a five-finger hand fitted by three fingers has half the columns).
    # A closed loop's joints move too, wherever it is: its gap must close.
    looped = {j for loop in kin.loops for j in loop.joints}
    moving = np.array([k for k in free if int(kin.joint_ids[k]) in chosen_joints | looped], dtype=np.intp)
    stiffness = kin.model.jnt_stiffness[kin.joint_ids]
    sprung = np.flatnonzero(stiffness > 0)
    span = kin.limits[sprung, 1] - kin.limits[sprung, 0]
    spring_aim = np.clip(kin.model.qpos_spring[kin.qpos_index[sprung]], kin.limits[sprung, 0], kin.limits[sprung, 1])

    def unpack(x: NDArray[np.float64], variables: NDArray[np.intp]) -> Pose:
        angles = q0.copy()
        angles[variables] = x[: len(variables)]
        if not pose_variables:
            return kin.complete(angles), rotation0, shift0
        rotation = _rotvec_matrix(x[len(variables) : len(variables) + 3]) @ rotation0
        return kin.complete(angles), rotation, shift0 + x[len(variables) + 3 :]

    def residual(x: NDArray[np.float64], variables: NDArray[np.intp], collide: bool) -> NDArray[np.float64]:
        pose = unpack(x, variables)
        centre, pad = aim.centres(pose)
        parts = [
            np.einsum("kij,kj->ki", weigh, centre - aim.targets).ravel(),
            (weights[:, None] * (pad - inward)).ravel(),
            REST_WEIGHT * (pose[0][resting] - q0[resting]),
            LOOP_WEIGHT * loop_gaps(scene),
            SPRING_WEIGHT * (pose[0][sprung] - spring_aim) / span,
        ]
        if collide:
            into_object, into_hand = scene.depths()
            allowed = 0.5 * LINK_TOLERANCE * scene.length_scale
            parts.append(COLLISION_WEIGHT * np.maximum(np.maximum(into_object, into_hand) - allowed, 0.0))
        return np.concatenate(parts)

    def jacobian(x: NDArray[np.float64], variables: NDArray[np.intp], collide: bool) -> NDArray[np.float64]:
        pose = unpack(x, variables)
        scene.pose(*pose)
        palm = (x[len(variables) : len(variables) + 3], pose[2]) if pose_variables else None
        jac = PoseJacobian(scene, pose[0], variables, palm)
        world, pad = scene.hand.pads_world(scene.data)
        centre_rows, normal_rows = [], []
        for k, f in enumerate(chosen):
            moved, turned = jac.point_and_direction(world[f], pad[f], int(scene.hand.pads[f]))
            centre_rows.append(weigh[k] @ (moved - radii[k] * turned))
            normal_rows.append(weights[k] * turned)
        derivative = kin.complete_derivative(pose[0])
        rest = np.zeros((len(resting), jac.columns))
        rest[:, : len(variables)] = REST_WEIGHT * derivative[np.ix_(resting, variables)]
        spring = np.zeros((len(sprung), jac.columns))
        spring[:, : len(variables)] = SPRING_WEIGHT * derivative[np.ix_(sprung, variables)] / span[:, None]
        rows = [*centre_rows, *normal_rows, rest, LOOP_WEIGHT * loop_rows(scene, jac), spring]
        if collide:
            rows.append(COLLISION_WEIGHT * _depth_rows(scene, jac))
        return np.vstack(rows)

    def solve(start: NDArray[np.float64], variables: NDArray[np.intp], collide: bool) -> NDArray[np.float64]:
        low = np.concatenate([kin.limits[variables, 0], np.full(pose_variables, -np.inf)])
        high = np.concatenate([kin.limits[variables, 1], np.full(pose_variables, np.inf)])
        solved = least_squares(
            residual,
            start,
            jac=jacobian,
            bounds=(low, high),
            args=(variables, collide),
            method="trf",
            x_scale="jac",
            max_nfev=MAX_EVALUATIONS,
        )
        return np.asarray(solved.x)

    x = solve(np.concatenate([q0[moving], np.zeros(pose_variables)]), moving, False)
    first = unpack(x, moving)
    fit = aim.summary(first)
    if len(scene.object_geoms) and max(fit.penetration, fit.self_penetration) > fit.link_tolerance:
        # Every joint and the palm again, from the first solution (the pose increment restarts at 0).
        angles, rotation, shift = first
        increment = [_matrix_rotvec(rotation @ rotation0.T), shift - shift0] if pose_variables else []
        x = np.concatenate([angles[free], *increment])
        x = solve(x, free, True)
        second = aim.summary(unpack(x, free))
        fit = second if better_fit(second, fit) else fit
    return fit


def _depth_rows(scene: FitScene, jac: PoseJacobian) -> NDArray[np.float64]:
    """d depth / d unknowns of each solid hand geom beyond half the tolerance, shape (G, columns).

    A geom's depth is that of its deepest contact: ``-n . (v2 - v1)`` at the contact point, ``n``
    the contact normal from geom 1 to geom 2 and ``v`` the velocity of the point moving with each
    geom's body (the object's is still).
    """
    into_object, into_hand, which = scene.deepest()
    active = np.maximum(into_object, into_hand) - 0.5 * LINK_TOLERANCE * scene.length_scale > 0.0
    rows = np.zeros((len(which), jac.columns))
    contact = scene.data.contact
    for g in np.flatnonzero(active):
        k = int(which[g])
        normal, point = contact.frame[k, :3].copy(), contact.pos[k].copy()
        for side, sign in ((0, 1.0), (1, -1.0)):
            geom = int(contact.geom[k, side])
            if geom in scene.hand_geom_ids:
                rows[g] += sign * normal @ jac.point(point, int(scene.model.geom_bodyid[geom]))
    return rows


def _rotvec_matrix(vector: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation matrix of a rotation vector (axis times angle [rad]), Rodrigues' formula."""
    angle = float(np.linalg.norm(vector))
    if angle < 1e-12:
        return np.eye(3)
    k = vector / angle
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * cross + (1.0 - np.cos(angle)) * (cross @ cross)


def _matrix_rotvec(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation vector of a rotation matrix."""
    return np.asarray(Rotation.from_matrix(matrix).as_rotvec())


def measure_pose(
    scene: FitScene,
    fingers: Sequence[int],
    points: ArrayLike,
    normals: ArrayLike,
    pose: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
) -> HandFit:
    """A given pose measured as a fit (nothing solved): residuals to the contacts, pad angles, depths.

    Args:
        scene: The hand and the object.
        fingers: Finger ``fingers[k]`` takes contact k.
        points: Contacts, shape (m, 3) [m].
        normals: Their inward unit normals, shape (m, 3).
        pose: Joint angles (J,), palm rotation (3, 3) and palm position (3,) [m].
    """
    chosen = tuple(int(f) for f in fingers)
    inward = np.asarray(normals, dtype=float)
    inward = inward / np.linalg.norm(inward, axis=1, keepdims=True)
    radii = np.array([scene.kinematics.fingers[f].radius for f in chosen])
    widths = np.array([scene.kinematics.fingers[f].width for f in chosen])
    aim = _Targets(scene, chosen, np.asarray(points, dtype=float) - radii[:, None] * inward, inward, radii, widths)
    return aim.summary(pose)
