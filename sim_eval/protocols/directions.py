"""Disturbance directions for the physics validation (unit 6-vectors in scaled wrench space).

Scaled space is the planner's ``[force [N], torque / rho [N]]``. A direction ``d`` means an
external disturbance ``s d`` applied to the object, ramped in ``s`` until it moves.

The set combines the 12 signed axes, quasi-uniform directions on the 5-sphere and, when a
Q1 certificate is known, the direction Q1 predicts to be weakest.

Uniformity of :func:`sphere_directions` (seed 0, minimum pairwise angle; a plain normalised
Gaussian draw of the same size over seeds 0-4 in brackets): n = 16: 76 deg (18-38 deg);
n = 64: 55 deg (12-18 deg); n = 200: 43 deg (8-13 deg).
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError

DIM = 6
AXIS_NAMES = ("fx", "fy", "fz", "tx", "ty", "tz")
#: Repulsion iterations and the Riesz exponent s of the energy sum 1 / |x_i - x_j|^s.
#: s = 5 (the sphere's dimension) is the exponent whose minimisers are asymptotically
#: uniform; 200 steps settle n <= 200 to within a degree of the final minimum angle.
REPULSION_ITERATIONS = 200
RIESZ_EXPONENT = 5.0
#: First step as a fraction of the mean nearest-neighbour angle; it decays linearly to 0
#: so the points settle instead of oscillating around the minimum.
FIRST_STEP = 0.5


@dataclass(frozen=True)
class DirectionSet:
    """Labelled disturbance directions.

    Attributes:
        vectors: Unit directions in scaled wrench space, shape (D, 6).
        labels: One label per direction: ``"+fx"`` ... ``"-tz"`` for the axes, ``"s00"``
            ... for sphere directions, ``"q1-weakest"`` for the Q1 direction.
    """

    vectors: NDArray[np.float64]
    labels: tuple[str, ...]

    def __post_init__(self) -> None:
        vectors = np.array(self.vectors, dtype=float)
        if vectors.ndim != 2 or vectors.shape[1] != DIM:
            raise OgcpError(f"direction vectors must have shape (D, 6), got {vectors.shape}")
        if len(self.labels) != len(vectors):
            raise OgcpError(f"{len(vectors)} directions need as many labels, got {len(self.labels)}")
        vectors.setflags(write=False)
        object.__setattr__(self, "vectors", vectors)
        object.__setattr__(self, "labels", tuple(self.labels))

    def __len__(self) -> int:
        return len(self.labels)


def _count(value: object, name: str) -> int:
    try:
        count = operator.index(value)  # type: ignore[arg-type]
    except TypeError:
        raise OgcpError(f"{name} must be an integer >= 0, got {value!r}") from None
    if count < 0:
        raise OgcpError(f"{name} must be an integer >= 0, got {value!r}")
    return count


def axis_directions() -> NDArray[np.float64]:
    """The 12 signed force and torque axes.

    Returns:
        Unit directions, shape (12, 6), ordered ``+fx, -fx, +fy, -fy, ..., +tz, -tz``.
    """
    eye = np.eye(DIM)
    return np.stack([eye, -eye], axis=1).reshape(2 * DIM, DIM)


def axis_labels() -> tuple[str, ...]:
    """Labels of :func:`axis_directions`, in the same order."""
    return tuple(f"{sign}{name}" for name in AXIS_NAMES for sign in "+-")


def _nearest_angles(x: NDArray[np.float64]) -> NDArray[np.float64]:
    gram = x @ x.T
    np.fill_diagonal(gram, -1.0)
    return np.arccos(np.clip(gram.max(axis=1), -1.0, 1.0))


def min_pairwise_angle(vectors: NDArray[np.float64]) -> float:
    """Smallest angle between two of the given unit vectors [rad] (pi for fewer than 2).

    Args:
        vectors: Unit vectors, shape (n, dim).

    Returns:
        The minimum pairwise angle [rad].
    """
    x = np.asarray(vectors, dtype=float)
    return float(_nearest_angles(x).min()) if len(x) >= 2 else math.pi


def sphere_directions(n: int, seed: int) -> NDArray[np.float64]:
    """Quasi-uniform unit directions on the 5-sphere, deterministic for a seed.

    A normalised Gaussian draw (``numpy.random.default_rng(seed)``) is spread by projected
    gradient steps on the Riesz energy ``sum 1 / |x_i - x_j|^5``: each point moves along
    its tangential repulsion by a decaying fraction of the mean nearest-neighbour angle,
    then is renormalised. See the module docstring for the uniformity reached.

    Args:
        n: Number of directions (>= 0).
        seed: Seed of the random start.

    Returns:
        Unit directions, shape (n, 6).

    Raises:
        OgcpError: A negative or non-integer n or seed.
    """
    n = _count(n, "number of sphere directions")
    seed = _count(seed, "seed")
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, DIM))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    if n < 2:
        return x
    power = (RIESZ_EXPONENT + 2.0) / 2.0
    for it in range(REPULSION_ITERATIONS):
        diff = x[:, None, :] - x[None, :, :]
        dist2 = np.einsum("ijk,ijk->ij", diff, diff)
        np.fill_diagonal(dist2, np.inf)
        # Coincident points (dist2 = 0) would give infinite forces; the Gaussian start
        # makes them a probability-zero event, and the floor keeps the step finite anyway.
        force = np.einsum("ijk,ij->ik", diff, np.maximum(dist2, 1e-300) ** -power)
        force -= np.sum(force * x, axis=1, keepdims=True) * x
        norm = np.linalg.norm(force, axis=1, keepdims=True)
        step = FIRST_STEP * (1.0 - it / REPULSION_ITERATIONS) * float(_nearest_angles(x).mean())
        x = x + step * force / np.maximum(norm, 1e-300)
        x /= np.linalg.norm(x, axis=1, keepdims=True)
    return x


def weakest_q1_direction(certificate_direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """The disturbance direction along which Q1 predicts the least resistance.

    The certificate's ``direction`` u is the outward normal of the hull facet nearest the
    origin: the grasp produces at most ``q1 u`` along u. A disturbance ``s d`` must be
    balanced by the contact wrench ``-s d``, so the weakest disturbance is ``d = -u``.

    Args:
        certificate_direction: ``Q1Certificate.direction``, shape (6,).

    Returns:
        The unit disturbance direction ``-u / |u|``, shape (6,).

    Raises:
        OgcpError: Wrong shape, non-finite entries (a degenerate certificate) or zero length.
    """
    u = np.asarray(certificate_direction, dtype=float)
    if u.shape != (DIM,):
        raise OgcpError(f"certificate direction must have shape (6,), got {u.shape}")
    if not np.all(np.isfinite(u)):
        raise OgcpError("certificate direction is not finite (degenerate Q1 certificate)")
    norm = float(np.linalg.norm(u))
    if norm == 0.0:
        raise OgcpError("certificate direction has zero length")
    return -u / norm


def direction_set(
    n_sphere: int = 64, seed: int = 0, certificate_direction: NDArray[np.float64] | None = None
) -> DirectionSet:
    """The validation's disturbance directions: axes, sphere directions, Q1-weakest.

    Args:
        n_sphere: Number of quasi-uniform sphere directions (>= 0).
        seed: Seed of :func:`sphere_directions`.
        certificate_direction: Optional ``Q1Certificate.direction``, shape (6,); adds
            :func:`weakest_q1_direction` of it, labelled ``"q1-weakest"``.

    Returns:
        The :class:`DirectionSet`: 12 axes, then ``n_sphere`` sphere directions (labels
        ``s00``, ``s01``, ... zero-padded to a common width), then the Q1 direction.

    Raises:
        OgcpError: Invalid count, seed or certificate direction.
    """
    sphere = sphere_directions(n_sphere, seed)
    width = max(2, len(str(max(len(sphere) - 1, 0))))
    parts = [axis_directions(), sphere]
    labels = list(axis_labels()) + [f"s{i:0{width}d}" for i in range(len(sphere))]
    if certificate_direction is not None:
        parts.append(weakest_q1_direction(certificate_direction)[None, :])
        labels.append("q1-weakest")
    return DirectionSet(np.vstack(parts), tuple(labels))
