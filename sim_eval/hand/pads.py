"""The pads' gate: each chosen pad presses on the object near its contact; other links' contacts are listed.

A round pad touches the object at a point or two; a flat one (a gripper's jaw, a box-shaped
fingertip) in a patch, of which MuJoCo reports a few corners, and where within the patch the
force sits is statically indeterminate: a tilt of a hundredth of a degree moves it from one end
of the jaw to the other. A pad therefore counts as on its contact when the patch it presses with
(the convex hull of its contact points) passes within :data:`PAD_REACH_RADII` pad radii of it.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import nnls

from ogcp.sim_eval.hand.predict import RealisedContacts
from ogcp.sim_eval.hand.scene import HandScene

#: A pad counts as on its contact when the patch it presses with lies within this many pad radii of it.
PAD_REACH_RADII = 3.0
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


def pad_gate(
    closed: HandScene, realised: RealisedContacts, targets: NDArray[np.float64], model: mujoco.MjModel
) -> tuple[NDArray[np.bool_], list[dict[str, Any]]]:
    """Whether each chosen pad presses near its contact; the other links' contacts.

    Args:
        closed: The closed hand's scene.
        realised: The hand's contacts with the object, settled.
        targets: Each chosen finger's contact, in finger order, shape (m, 3) [m].
        model: The scene's model (for geom names).

    Returns:
        Per chosen pad whether it is on its contact, shape (m,); and the other links' contacts as
        ``{"link": geom name, "force": normal force [N]}``, summed per geom, sorted by name.
    """
    finger_geoms = closed.scene.finger_geoms or ()
    radii = np.array([closed.hand.kinematics.fingers[f].radius for f in closed.fingers])
    ok = np.zeros(len(finger_geoms), dtype=bool)
    pad_geoms = {int(g) for geoms in finger_geoms for g in geoms}
    for k, geoms in enumerate(finger_geoms):
        mine = np.isin(realised.geoms, geoms) & (realised.forces > 0)
        if mine.any():
            ok[k] = distance_to_hull(realised.points[mine], targets[k]) <= PAD_REACH_RADII * radii[k]
    extra: dict[str, float] = {}
    for geom, force in zip(realised.geoms, realised.forces, strict=True):
        if int(geom) not in pad_geoms:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(geom)) or f"geom {int(geom)}"
            extra[name] = extra.get(name, 0.0) + float(force)
    return ok, [{"link": name, "force": force} for name, force in sorted(extra.items())]
