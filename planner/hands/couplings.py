"""A hand's joint couplings (MuJoCo joint equalities: URDF mimic joints, an MJCF's ``polycoef``).

A coupled joint follows its driver as ``y - y0 = c0 + c1 (x - x0) + ... + c4 (x - x0)^4`` about
the model's ``qpos0`` (MuJoCo's convention). Its own range may be narrower than its driver's
carries it (dex-urdf's Schunk SVH: a distal joint follows its driver x 1.045 with the same range),
so sampled and fitted configurations keep the driver where the coupled joint stays in range.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
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
    drives within its own range (the longest such run on a grid of :data:`COUPLING_GRID` angles,
    its ends bisected to where the driven joint meets its limit).

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
        origin = (float(model.qpos0[model.jnt_qposadr[driver]]), float(model.qpos0[model.jnt_qposadr[dependent]]))
        low, high = limits[k]
        within = functools.partial(_within, origin=origin, poly=poly, low=float(low), high=float(high))
        grid = np.linspace(limits[d, 0], limits[d, 1], COUPLING_GRID)
        inside = within(grid)
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
        first, last = int(starts[longest]), int(ends[longest])
        # Each end bisected to where the coupled joint meets its limit, between the grid's points.
        lower = grid[first] if first == 0 else _boundary(within, grid[first], grid[first - 1])
        upper = grid[last] if last == len(grid) - 1 else _boundary(within, grid[last], grid[last + 1])
        limits[d] = lower, upper
    return limits


def _within(
    angles: NDArray[np.float64], origin: tuple[float, float], poly: NDArray[np.float64], low: float, high: float
) -> NDArray[np.bool_]:
    """Whether the coupled joint, following driver ``angles`` by ``poly`` about ``origin`` (the two
    joints' qpos0), stays within [low, high]."""
    x = angles - origin[0]
    y = origin[1] + sum(c * x**p for p, c in enumerate(poly))
    return np.asarray((y >= low - 1e-9) & (y <= high + 1e-9))


def _boundary(within: Callable[[NDArray[np.float64]], NDArray[np.bool_]], inside: float, outside: float) -> float:
    """The last angle from ``inside`` toward ``outside`` that ``within`` allows (60 bisections)."""
    for _ in range(60):
        middle = 0.5 * (inside + outside)
        if within(np.array([middle]))[0]:
            inside = middle
        else:
            outside = middle
    return inside
