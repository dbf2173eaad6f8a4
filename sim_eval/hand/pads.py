"""The pads' gate: each chosen pad presses on the object near its contact; other links' contacts are listed.

A round pad touches the object at a point or two; a flat one (a gripper's jaw, a box-shaped
fingertip) in a patch, of which MuJoCo reports a few corners, and where within the patch the
force sits is statically indeterminate: a tilt of a hundredth of a degree moves it from one end
of the jaw to the other. A pad therefore counts as on its contact when the patch it presses with
(the convex hull of its contact points) passes within :data:`PAD_REACH_RADII` pad radii of it, or,
pressing on the object anywhere, when its surface passes within :data:`PAD_SURFACE_TOLERANCE` of
it along the pad's normal: a jaw tilted a fraction of a degree on a box's face touches along one
edge, centimetres from the contact it still lies on.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import nnls

from ogcp.sim_eval.hand.predict import RealisedContacts
from ogcp.sim_eval.hand.scene import HandScene
from ogcp.sim_eval.protocols.gates import GateFailure

#: A pad counts as on its contact when the patch it presses with lies within this many pad radii of it.
PAD_REACH_RADII = 3.0
#: A pad that presses on the object and whose surface passes this close to its contact, along the
#: pad's normal, is on its contact wherever its patch is [m]: the fit's own tolerance.
PAD_SURFACE_TOLERANCE = 1e-3
#: Weight of the row that makes the hull's barycentric weights sum to one in the least-squares fit.
_SUM_WEIGHT = 1e3


def distance_to_hull(points: NDArray[np.float64], target: NDArray[np.float64]) -> float:
    """[m] Distance from ``target`` (3,) to the convex hull of ``points`` (K, 3), K >= 1.

    The nearest hull point is ``w @ points`` with barycentric weights ``w >= 0`` summing to one:
    non-negative least squares with the sum held by a heavily weighted row.
    """
    points = np.asarray(points, dtype=float)
    scale = max(float(np.ptp(points, axis=0).max()), float(np.linalg.norm(target - points[0])), 1e-9)
    matrix = np.vstack([points.T / scale, np.full(len(points), _SUM_WEIGHT)])
    wanted = np.concatenate([np.asarray(target, dtype=float) / scale, [_SUM_WEIGHT]])
    weights, _ = nnls(matrix, wanted)
    weights /= max(float(weights.sum()), 1e-12)
    return float(np.linalg.norm(weights @ points - target))


@dataclass(frozen=True, eq=False)
class PadGate:
    """Where each chosen pad settled against its contact, and the other links' contacts.

    Attributes:
        off: How far each pad's contact patch is from its contact, shape (m,) [m]; inf where the
            pad presses nothing.
        reach: How far the patch may be (:data:`PAD_REACH_RADII` pad radii), shape (m,) [m].
        surface_gap: How far the pad's surface passes from its contact along the pad's normal,
            shape (m,) [m]; inf where the normal through the contact misses the pad.
        on: Whether each pad presses on its contact: its patch within reach, or, pressing
            anywhere, its surface within :data:`PAD_SURFACE_TOLERANCE` of the contact (a flat jaw
            on a flat face touches where a hundredth of a degree of tilt puts its patch: at an edge).
        extra: The other links' contacts, ``{"link": geom name, "force": normal force [N]}``,
            summed per geom, sorted by name.
    """

    off: NDArray[np.float64]
    reach: NDArray[np.float64]
    surface_gap: NDArray[np.float64]
    on: NDArray[np.bool_]
    extra: list[dict[str, Any]]


def pad_gate(
    closed: HandScene, realised: RealisedContacts, targets: NDArray[np.float64], data: mujoco.MjData
) -> PadGate:
    """Whether each chosen pad presses near its contact; the other links' contacts.

    Args:
        closed: The closed hand's scene.
        realised: The hand's contacts with the object, settled.
        targets: Each chosen finger's contact, in finger order, shape (m, 3) [m].
        data: The settled state, kinematics computed.
    """
    model = closed.scene.model
    finger_geoms = closed.scene.finger_geoms or ()
    radii = np.array([closed.hand.kinematics.fingers[f].radius for f in closed.fingers])
    _, pad_normals = closed.hand.pads_world(data)
    off = np.full(len(finger_geoms), np.inf)
    gap = np.full(len(finger_geoms), np.inf)
    pad_geoms = {int(g) for geoms in finger_geoms for g in geoms}
    for k, geoms in enumerate(finger_geoms):
        mine = np.isin(realised.geoms, geoms) & (realised.forces > 0)
        if mine.any():
            off[k] = distance_to_hull(realised.points[mine], targets[k])
            gap[k] = surface_gap(model, data, geoms, targets[k], pad_normals[closed.fingers[k]])
    extra: dict[str, float] = {}
    for geom, force in zip(realised.geoms, realised.forces, strict=True):
        if int(geom) not in pad_geoms:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(geom)) or f"geom {int(geom)}"
            extra[name] = extra.get(name, 0.0) + float(force)
    reach = PAD_REACH_RADII * radii
    on = (off <= reach) | (gap <= PAD_SURFACE_TOLERANCE)
    return PadGate(off, reach, gap, on, [{"link": name, "force": force} for name, force in sorted(extra.items())])


def surface_gap(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    geoms: NDArray[np.intp],
    point: NDArray[np.float64],
    normal: NDArray[np.float64],
) -> float:
    """[m] How far the surface of ``geoms`` passes from ``point`` along the line of a pad's ``normal``.

    A ray from :data:`PAD_SURFACE_TOLERANCE` beyond the point (inside the object, where the pad's
    normal points) back toward the pad: a pad sunk into the object by less than that still counts
    its gap as the depth. inf when the line misses every geom.
    """
    unit = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    start = np.asarray(point, dtype=float) + PAD_SURFACE_TOLERANCE * unit
    back = -unit
    nearest = np.inf
    for geom in np.asarray(geoms, dtype=np.intp):
        g = int(geom)
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            hit = mujoco.mj_rayMesh(model, data, g, start, back)
        else:
            hit = mujoco.mju_rayGeom(
                data.geom_xpos[g], data.geom_xmat[g], model.geom_size[g], start, back, int(model.geom_type[g])
            )
        if hit >= 0:
            nearest = min(nearest, abs(hit - PAD_SURFACE_TOLERANCE))
    return float(nearest)


def pad_off_contact(finger: int, distance: float, reach: float) -> GateFailure:
    """Why a grasp is invalid when chosen finger ``finger``'s pad settled away from its contact [m]."""
    advice = (
        "the hand settled elsewhere than the fit put it: a servo, a soft joint equality or a closed loop "
        "gave way under the squeeze (stiffen them in the model), or the pad slid"
    )
    if not np.isfinite(distance):  # NaN in the record: no distance to give
        advice = "another link may be touching the object instead (see extra_contacts)"
        distance = float("nan")
    return GateFailure("pad", finger, distance, reach, "m", advice)
