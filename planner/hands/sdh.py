"""Kinematic model of the Schunk SDH three-finger hand (7 DOF), the numpy twin of its MJCF.

Frames and signs (the same in the MJCF, ``assets/hands/sdh.xml``):

- Palm frame: z is the palm axis; the finger bases lie at ``z = PALM_HEIGHT`` on an
  equilateral triangle of side 0.066 m centred (to rounding) on that axis. Finger 1 rotates
  and sits at y > 0, finger 2 rotates and sits at y < 0, finger 3 is the fixed thumb at x < 0.
- Each finger frame has z = palm z and x pointing from the finger base toward the palm axis
  (projected on the palm plane). Flexion is a rotation about the finger's local y axis;
  since the finger points along +z at zero flexion, a positive angle tilts it toward +x, i.e.
  it closes toward the palm axis.
- The base angle ``theta`` turns finger 1 by ``+theta`` and finger 2 by ``-theta`` about the
  palm z axis at their bases, so finger 2 is always the mirror image of finger 1 about the
  palm xz-plane. In the MJCF ``base_2`` has axis -z, so both base joints take the same value
  ``theta`` (equality ``q(base_2) = q(base_1)``); see :data:`MJCF_JOINT_INDEX`.
- The pad normal is the distal link's local +x expressed in the palm frame.

Configurations are 7-vectors ordered as :data:`JOINT_NAMES`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.infra.assets import asset_path
from ogcp.planner.infra.errors import OgcpError

PALM_HEIGHT = 0.0745
"""Height of the finger bases above the palm origin, along palm z [m]."""
PROXIMAL_OFFSET = 0.0165
"""Distance from a finger base up to its proximal flexion axis, along palm z [m]."""
PROXIMAL_LENGTH = 0.0865
"""Proximal link: proximal to distal flexion axis [m]."""
DISTAL_LENGTH = 0.0685
"""Distal link: distal flexion axis to fingertip [m]."""
FINGER_NAMES = ("finger_1", "finger_2", "thumb")
"""Finger order of every (..., 3, 3) result: the two rotating fingers, then the thumb."""


def _readonly(array: ArrayLike) -> NDArray[np.float64]:
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


FINGER_BASES = _readonly(
    [
        [0.01905, 0.033, PALM_HEIGHT],
        [0.01905, -0.033, PALM_HEIGHT],
        [-0.03811, 0.0, PALM_HEIGHT],
    ]
)
"""Finger base positions in the palm frame, shape (3, 3) [m]."""

# Derived from the (rounded) base coordinates rather than set to exactly -120, +120 and 0
# degrees, so that local x points exactly at the palm axis, as the MJCF's xyaxes does.
FINGER_YAWS = _readonly(np.arctan2(-FINGER_BASES[:, 1], -FINGER_BASES[:, 0]))
"""Angle of each finger frame's x axis about palm z at zero base rotation, shape (3,) [rad]."""
BASE_ROTATION_SIGN = _readonly([1.0, -1.0, 0.0])
"""How much each finger turns about palm z per radian of base angle, shape (3,)."""

JOINT_NAMES = ("base", "prox_1", "dist_1", "prox_2", "dist_2", "prox_3", "dist_3")
"""Names of the 7 entries of a configuration, in order."""
JOINT_LIMITS = _readonly([[0.0, np.pi / 2]] + [[-np.pi / 2, np.pi / 2]] * 6)
"""Lower and upper limit of each joint in :data:`JOINT_NAMES` order, shape (7, 2) [rad]."""
JOINT_LIMIT_TOLERANCE = 1e-6
"""Overshoot of a joint limit still accepted [rad]: configurations that went through float32
or a text round trip land a few 1e-8 rad outside, which is not a user error."""

MJCF_JOINT_INDEX: Mapping[str, int] = MappingProxyType(
    {"base_1": 0, "base_2": 0, "prox_1": 1, "dist_1": 2, "prox_2": 3, "dist_2": 4, "prox_3": 5, "dist_3": 6}
)
"""For each MJCF joint, the configuration entry it takes (both base joints take ``base``)."""
TIP_SITES = ("tip_1", "tip_2", "tip_3")
"""MJCF fingertip site names in :data:`FINGER_NAMES` order; each site's x axis is the pad normal."""

_PROXIMAL = np.array([1, 3, 5])
_DISTAL = np.array([2, 4, 6])
_MODEL_ASSET = "hands/sdh.xml"


@dataclass(frozen=True, eq=False)
class FingertipPoses:
    """Fingertip positions and pad normals in the palm frame.

    Rows are the fingers in :data:`FINGER_NAMES` order; leading dimensions, if any, are the
    batch of configurations. Unpacks as ``positions, normals = forward_kinematics(q)``.

    Attributes:
        positions: Fingertip points, shape (..., 3, 3) [m].
        normals: Unit pad normals, shape (..., 3, 3).
    """

    positions: NDArray[np.float64]
    normals: NDArray[np.float64]

    def __post_init__(self) -> None:
        positions = _readonly(self.positions)
        normals = _readonly(self.normals)
        if positions.shape[-2:] != (3, 3) or normals.shape != positions.shape:
            raise OgcpError(
                f"fingertip positions and normals must both have shape (..., 3, 3), got {positions.shape} "
                f"and {normals.shape}"
            )
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "normals", normals)

    def __iter__(self) -> Iterator[NDArray[np.float64]]:
        yield self.positions
        yield self.normals


def validate_configuration(q: ArrayLike) -> NDArray[np.float64]:
    """Check an SDH configuration (or a batch of them) and return it as a float array.

    Args:
        q: Joint angles in :data:`JOINT_NAMES` order, shape (7,) or (B, 7) [rad].

    Returns:
        A new float array of the same shape.

    Raises:
        OgcpError: On a wrong shape, a non-finite value or a joint more than
            :data:`JOINT_LIMIT_TOLERANCE` outside its range; the message names the joint.
    """
    try:
        q = np.array(q, dtype=float)
    except (TypeError, ValueError) as exc:
        raise OgcpError(f"SDH configuration must be numbers [rad] ({exc})") from exc
    if q.ndim not in (1, 2) or q.shape[-1] != len(JOINT_NAMES):
        raise OgcpError(
            f"SDH configuration must have shape (7,) or (B, 7) with joints {', '.join(JOINT_NAMES)}; got {q.shape}"
        )
    rows = np.atleast_2d(q)
    bad = ~np.isfinite(rows)
    if bad.any():
        row, joint = np.argwhere(bad)[0]
        raise OgcpError(f"SDH joint {JOINT_NAMES[joint]} is {rows[row, joint]}{_where(q, row)}; angles must be finite")
    low, high = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    bad = (rows < low - JOINT_LIMIT_TOLERANCE) | (rows > high + JOINT_LIMIT_TOLERANCE)
    if bad.any():
        row, joint = np.argwhere(bad)[0]
        raise OgcpError(
            f"SDH joint {JOINT_NAMES[joint]} = {rows[row, joint]:.6g} rad{_where(q, row)} is outside its range "
            f"[{low[joint]:.6g}, {high[joint]:.6g}] rad"
        )
    return q


def _where(q: NDArray[np.float64], row: int) -> str:
    return f" in configuration {row}" if q.ndim == 2 else ""


def forward_kinematics(q: ArrayLike) -> FingertipPoses:
    """Fingertip positions and pad normals of one configuration or a batch.

    Closed form: with base angle theta, flexions a (proximal) and c (distal), finger yaw
    ``psi = FINGER_YAWS + BASE_ROTATION_SIGN * theta`` and ``u = (cos psi, sin psi, 0)``,

    ``tip = base + u (Lp sin a + Ld sin(a + c)) + z (h + Lp cos a + Ld cos(a + c))`` and
    ``normal = u cos(a + c) - z sin(a + c)``.

    Args:
        q: Joint angles in :data:`JOINT_NAMES` order, shape (7,) or (B, 7) [rad].

    Returns:
        Poses with positions and normals of shape (3, 3) or (B, 3, 3), in the palm frame.

    Raises:
        OgcpError: If ``q`` is invalid (see :func:`validate_configuration`).
    """
    q = validate_configuration(q)
    yaw = FINGER_YAWS + BASE_ROTATION_SIGN * q[..., :1]  # (..., 3)
    proximal = q[..., _PROXIMAL]
    total = proximal + q[..., _DISTAL]
    reach = PROXIMAL_LENGTH * np.sin(proximal) + DISTAL_LENGTH * np.sin(total)
    height = PROXIMAL_OFFSET + PROXIMAL_LENGTH * np.cos(proximal) + DISTAL_LENGTH * np.cos(total)
    zeros = np.zeros_like(yaw)
    inward = np.stack([np.cos(yaw), np.sin(yaw), zeros], axis=-1)  # (..., 3, 3)
    up = np.stack([zeros, zeros, np.ones_like(yaw)], axis=-1)
    positions = FINGER_BASES + inward * reach[..., None] + up * height[..., None]
    normals = inward * np.cos(total)[..., None] - up * np.sin(total)[..., None]
    return FingertipPoses(positions, normals)


def random_configurations(count: int, seed: int = 0) -> NDArray[np.float64]:
    """Configurations drawn uniformly within :data:`JOINT_LIMITS`.

    Args:
        count: Number of configurations (>= 0).
        seed: Seed of the numpy Generator; the same seed gives the same configurations.

    Returns:
        Joint angles, shape (count, 7) [rad].

    Raises:
        OgcpError: If ``count`` or ``seed`` is not a non-negative integer.
    """
    for what, value in (("count", count), ("seed", seed)):
        if not _is_natural(value):
            raise OgcpError(f"{what} must be a non-negative integer, got {value!r}")
    rng = np.random.default_rng(int(seed))
    return rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], size=(int(count), len(JOINT_NAMES)))


def _is_natural(value: object) -> bool:
    # Accepts 3 and 3.0 (and numpy integers) but not True, 2.5, "3" or NaN.
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        return False
    # One bool() around the whole test: numpy scalars compare to numpy bools.
    return bool(np.isfinite(value) and int(value) == value and value >= 0)


def sdh_model_path() -> Path:
    """Path of the SDH MJCF, ``assets/hands/sdh.xml`` (shipped as package data).

    Returns:
        The absolute path of the model file.

    Raises:
        OgcpError: If the file is missing (a broken install).
    """
    return asset_path(_MODEL_ASSET)
