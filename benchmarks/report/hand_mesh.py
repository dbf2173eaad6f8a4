"""The settled hand of a simulated grasp as triangles for the 3D viewer.

A grasp tested with a hand records the pose it settled in (``settled_joint_angles``, and the palm
held at ``palm_rotation`` and ``palm_position`` in the object's frame, which starts at the world's
origin). The hand is compiled again from its descriptor (a path, else a built-in name), checked
against the recorded sha256, posed there, and its collision geoms turned into triangles (the
scene coarsens them to :data:`HAND_FACES`). A hand that cannot be rebuilt is left out with a note, never stops the page.
"""

from __future__ import annotations

import functools
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.hands.registry import resolve_hand
from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.geometry import posed_triangles

#: Most faces kept of a hand's surface: the object's mesh keeps more, the hand frames it.
HAND_FACES = 8_000


@functools.lru_cache(maxsize=4)
def _hand(source: str, sha256: str | None) -> HandKinematics:
    descriptor = resolve_hand(source)
    if sha256 is not None and descriptor.sha256 != sha256:
        raise OgcpError(f"hand descriptor {descriptor.path} changed since the simulation (its sha256 differs)")
    with warnings.catch_warnings():  # said when the hand was planned for and simulated; not again per picture
        warnings.simplefilter("ignore")
        return HandKinematics(descriptor)


def settled_hand(block: dict[str, Any]) -> tuple[NDArray[np.float64], NDArray[np.int64]] | None:
    """The hand of a grasp's ``hand`` block as it settled: vertices (V, 3) [m] in the object's frame
    and faces (F, 3), or None when the block holds no settled pose (an unreachable grasp, fingertips).

    Raises:
        OgcpError: If the hand cannot be found, compiled, or its descriptor changed since.
    """
    source = block.get("descriptor") or block.get("name")
    if not source or "settled_joint_angles" not in block:
        return None
    try:
        angles = np.asarray(block["settled_joint_angles"], dtype=float)
        rotation = np.asarray(block["palm_rotation"], dtype=float)
        position = np.asarray(block["palm_position"], dtype=float)
    except (KeyError, TypeError, ValueError):
        return None
    if rotation.shape != (3, 3) or position.shape != (3,) or not np.isfinite(np.concatenate([angles, position])).all():
        return None
    sha = block.get("descriptor_sha256")
    kinematics = _hand(str(source), sha if isinstance(sha, str) else None)
    if len(angles) != len(kinematics.joint_names):
        return None
    scene = FitScene(kinematics)
    scene.pose(angles, rotation, position)
    vertices, faces = posed_triangles(scene.model, scene.data, scene.hand.geoms)
    return np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)
