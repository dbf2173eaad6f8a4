"""A hand's joint couplings (MuJoCo joint equalities: URDF mimic joints, an MJCF's ``polycoef``).

A coupled joint follows its driver as ``y - y0 = c0 + c1 (x - x0) + ... + c4 (x - x0)^4`` about
the model's ``qpos0`` (MuJoCo's convention). Its own range may be narrower than its driver's
carries it (dex-urdf's Schunk SVH: a distal joint follows its driver x 1.045 with the same range),
so sampled and fitted configurations keep the driver where the coupled joint stays in range.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError

#: Angles of a driver tried for the range that keeps the joint it drives within its own.
COUPLING_GRID = 4001

Coupling = tuple[int, int, NDArray[np.float64]]


def joint_couplings(model: mujoco.MjModel, joint_ids: Sequence[int]) -> list[Coupling]:
    """(coupled joint, driving joint or -1, polynomial coefficients (5,)) of the active joint
    equalities among ``joint_ids``."""
    found = []
    ids = {int(j) for j in joint_ids}
    for e in range(model.neq):
        if model.eq_type[e] != mujoco.mjtEq.mjEQ_JOINT or not model.eq_active0[e]:
            continue
        dependent, driver = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        if dependent in ids and (driver < 0 or driver in ids):
            found.append((dependent, driver, model.eq_data[e, :5].copy()))
    return found


def narrowed_drivers(
    model: mujoco.MjModel,
    names: Sequence[str],
    joint_ids: Sequence[int],
    limits: NDArray[np.float64],
    couplings: Sequence[Coupling],
    where: Path | str,
) -> NDArray[np.float64]:
    """The joints' limits (J, 2) with each driver narrowed to the angles that keep the joint it
    drives within its own range (the longest such run, on a grid of :data:`COUPLING_GRID` angles).

    Args:
        model: The compiled hand.
        names: The joints' names, in ``joint_ids`` order.
        joint_ids: The hand's joints (model ids), shape (J,).
        limits: Their ranges, shape (J, 2) [rad or m].
        couplings: From :func:`joint_couplings`.
        where: The descriptor, for the error.

    Raises:
        OgcpError: If no angle of a driver keeps the joint it drives within range.
    """
    limits = np.array(limits, dtype=float)
    position = {int(j): k for k, j in enumerate(joint_ids)}
    for dependent, driver, poly in couplings:
        if driver < 0:
            continue
        d, k = position[driver], position[dependent]
        grid = np.linspace(limits[d, 0], limits[d, 1], COUPLING_GRID)
        x = grid - model.qpos0[model.jnt_qposadr[driver]]
        y = model.qpos0[model.jnt_qposadr[dependent]] + sum(c * x**p for p, c in enumerate(poly))
        low, high = limits[k]
        inside = (y >= low - 1e-9) & (y <= high + 1e-9)
        if inside.all():
            continue
        if not inside.any():
            raise OgcpError(
                f"{where}: joint {names[k]!r} follows {names[d]!r} outside its range [{low:.6g}, {high:.6g}] "
                "at every angle of it; widen one of their ranges or fix the coupling"
            )
        # A polynomial coupling may leave the range and come back: the longest run is kept.
        edges = np.flatnonzero(np.diff(np.concatenate([[0], inside.astype(np.int8), [0]])))
        starts, ends = edges[::2], edges[1::2] - 1
        longest = int(np.argmax(ends - starts))
        limits[d] = grid[starts[longest]], grid[ends[longest]]
    return limits
