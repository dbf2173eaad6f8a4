"""Linearised friction cones and contact wrenches (the convention used everywhere in ogcp).

Cone edges ``f_j = n + mu (cos t_j a + sin t_j b)`` with ``t_j = 2 pi j / k``: normal
component 1, not normalised. The tangent basis is fixed exactly so that results never
depend on an arbitrary choice: ``a = unit(n x e)`` with ``e = (1, 0, 0)`` unless
``|n_x| >= 0.9``, then ``e = (0, 1, 0)``; ``b = n x a``. The wrench of an edge applied at
``p`` is ``[f, (p - com) x f / rho]``.

Soft fingers (torsional friction coefficient ``gamma`` > 0 [m], MuJoCo's condim 4 with
elliptic cones) add a moment about the normal: per unit normal force the contact transmits
``f = n + mu (x a + y b)`` and ``tau = gamma z n`` with ``x^2 + y^2 + z^2 <= 1``. The ball is
linearised by an inscribed polytope (:func:`soft_directions`): the k hard-cone edges on its
equator (so every hard grasp's wrenches are a subset), the two poles (pure torsion) and two
rings of ``ceil(k / 2)`` points at latitude +-45 degrees, offset by half a step: ``2 k + 2``
primitives for even k. The polytope contains the ball scaled by its inradius r
(:func:`soft_inradius`), so the linearised wrench set lies between the exact soft-finger set
with ``(r mu, r gamma)`` and the exact one with ``(mu, gamma)``: r = 0.816 at k = 8, 0.877 at
k = 12, 0.898 at k = 16, 0.922 at k = 64 (the hard cones' polygon: cos(pi / k) = 0.924 at 8).

The public functions check their arrays (shape, finite values) and raise
:class:`~ogcp.planner.infra.errors.OgcpError` naming the shape expected and the shape given.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError


def shaped_array(
    value: object, name: str, shape: str, ndim: int, last: int | None = None, hint: str = ""
) -> NDArray[np.float64]:
    """``value`` as a float array, checked against the shape its function documents.

    Args:
        value: An array-like argument of a public function.
        name: What it is, for the message (e.g. ``"wrenches"``).
        shape: The documented shape, as the message shows it (e.g. ``"(N, 6)"``).
        ndim: The number of axes required.
        last: The length the last axis must have; None for any.
        hint: Appended to the message for a wrong shape (how to get the right one).

    Returns:
        The array (no copy when ``value`` already is a float array).

    Raises:
        OgcpError: For a value that is not numeric or has another shape.
    """
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise OgcpError(f"{name} must be a numeric array of shape {shape} ({exc})") from None
    if array.ndim != ndim or (last is not None and array.shape[-1] != last):
        raise OgcpError(f"{name} must have shape {shape}, got {array.shape}" + (f"; {hint}" if hint else ""))
    return array


def check_finite(array: NDArray[np.float64], name: str) -> None:
    """Raise an :class:`OgcpError` naming the first NaN or infinite entry of ``array``, if any."""
    if not np.isfinite(array).all():
        # Located only on failure, so that the check costs one pass on good input.
        where = tuple(int(i) for i in np.argwhere(~np.isfinite(array))[0])
        raise OgcpError(f"{name} must be finite, got {array[where]} at index {where}")


def finite_array(
    value: object, name: str, shape: str, ndim: int, last: int | None = None, hint: str = ""
) -> NDArray[np.float64]:
    """:func:`shaped_array` with finite entries only; see there for the arguments.

    Raises:
        OgcpError: For a value that is not numeric, has another shape, or holds NaN or
            infinite entries.
    """
    array = shaped_array(value, name, shape, ndim, last, hint)
    check_finite(array, name)
    return array


def _normals_array(normals: object) -> NDArray[np.float64]:
    """Normals of shape (n, 3), finite and nonzero (a zero normal has no tangent basis)."""
    n = finite_array(normals, "normals", "(n, 3)", 2, 3)
    nonzero = n.any(axis=1)  # a quarter of the cost of the norms
    if not nonzero.all():
        raise OgcpError(f"normals must be nonzero, normal {int(np.argmin(nonzero))} is zero")
    return n


def _torsion_parameter(torsion: float) -> None:
    """Check the torsional friction coefficient (finite, >= 0) [m]."""
    if not (isinstance(torsion, Real) and not isinstance(torsion, bool) and math.isfinite(torsion) and torsion >= 0):
        raise OgcpError(f"torsional friction coefficient must be a finite number >= 0 [m], got {torsion!r}")


def _cone_parameters(mu: float, k: int) -> None:
    """Check the friction coefficient (finite, >= 0) and the number of cone edges (integer >= 1)."""
    if not (isinstance(mu, Real) and math.isfinite(mu) and mu >= 0):
        raise OgcpError(f"friction coefficient mu must be a finite number >= 0, got {mu!r}")
    if not (isinstance(k, Integral) and not isinstance(k, bool) and k >= 1):
        raise OgcpError(f"the number of cone edges k must be an integer >= 1, got {k!r}")


def tangent_basis(normals: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the fixed tangent basis (a, b) for unit normals.

    Args:
        normals: Unit normals, shape (n, 3).

    Returns:
        ``(a, b)``, each of shape (n, 3), with ``a = unit(n x e)`` and ``b = n x a``.

    Raises:
        OgcpError: For normals of another shape, not finite, or zero.
    """
    return _tangent_basis(_normals_array(normals))


def _tangent_basis(normals: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`tangent_basis` of checked normals."""
    e = np.zeros_like(normals)
    use_y = np.abs(normals[:, 0]) >= 0.9
    e[~use_y, 0] = 1.0
    e[use_y, 1] = 1.0
    a = np.cross(normals, e)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(normals, a)
    return a, b


def cone_edges(normals: NDArray[np.float64], mu: float, k: int) -> NDArray[np.float64]:
    """Linearised friction-cone edges.

    Args:
        normals: Inward unit normals, shape (n, 3).
        mu: Coulomb friction coefficient (>= 0).
        k: Number of cone edges (>= 1).

    Returns:
        Edge forces, shape (n, k, 3), normal component 1 [N per unit normal force].

    Raises:
        OgcpError: For normals of another shape, not finite or zero, or a bad mu or k.
    """
    _cone_parameters(mu, k)
    return _cone_edges(_normals_array(normals), float(mu), int(k))


def _cone_edges(normals: NDArray[np.float64], mu: float, k: int) -> NDArray[np.float64]:
    """:func:`cone_edges` of checked arguments."""
    a, b = _tangent_basis(normals)
    t = 2.0 * np.pi * np.arange(k) / k
    tangential = np.cos(t)[None, :, None] * a[:, None, :] + np.sin(t)[None, :, None] * b[:, None, :]
    return normals[:, None, :] + mu * tangential


def soft_directions(k: int, dense: bool = False) -> NDArray[np.float64]:
    """Vertices of the polytope that linearises the soft-finger ball, shape (K, 3).

    Row ``(x, y, z)`` stands for the tangential force ``mu (x a + y b)`` and the moment
    ``gamma z n`` per unit normal force. The first k rows are the hard cone's edges
    (``t_j = 2 pi j / k`` on the equator), then the poles ``z = +-1``, then two rings of
    ``ceil(k / 2)`` points at latitude +-45 degrees, offset by half of their step (the
    planner's set). ``dense`` instead puts ``max(1, k // 4)`` rings of k points on each
    hemisphere at evenly spaced latitudes: the fine set of the simulation's prediction LP
    (k = 32: 546 vertices, inradius 0.99).

    Args:
        k: Friction-cone edges (>= 1).
        dense: Whether to build the fine set.

    Returns:
        Unit vectors, shape (K, 3): K = 2 ceil(k / 2) + k + 2, or 2 k max(1, k // 4) + k + 2 dense.
    """
    _cone_parameters(0.0, k)
    t = 2.0 * np.pi * np.arange(k) / k
    rows = [np.stack([np.cos(t), np.sin(t), np.zeros(k)], axis=1), np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])]
    if dense:
        rings = max(1, k // 4)
        latitudes = 0.5 * np.pi * np.arange(1, rings + 1) / (rings + 1)
        count = k
    else:
        latitudes, count = np.array([0.25 * np.pi]), -(-k // 2)
    for j, phi in enumerate(latitudes):
        s = 2.0 * np.pi * (np.arange(count) + 0.5 * ((j + 1) % 2)) / count
        for z in (math.sin(phi), -math.sin(phi)):
            c = math.cos(phi)
            rows.append(np.stack([c * np.cos(s), c * np.sin(s), np.full(count, z)], axis=1))
    return np.vstack(rows)


def soft_inradius(k: int, dense: bool = False) -> float:
    """Radius of the largest ball about the origin inside the hull of :func:`soft_directions` [-].

    The linearised soft-finger set contains the exact one with mu and gamma scaled by it.
    """
    from scipy.spatial import ConvexHull  # only the documentation of the error needs it

    return float(np.min(-ConvexHull(soft_directions(k, dense)).equations[:, 3]))


def primitives_per_contact(k: int, torsion: float) -> int:
    """Number of wrench primitives of one contact: k for hard fingers, ``2 ceil(k/2) + k + 2`` for soft."""
    return k if torsion <= 0 else k + 2 + 2 * (-(-k // 2))


def contact_wrenches(
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    com: NDArray[np.float64],
    torque_scale: float,
    mu: float,
    k: int,
    torsion: float = 0.0,
    dense: bool = False,
) -> NDArray[np.float64]:
    """Wrenches of every cone edge (or soft-finger primitive) of every contact.

    Args:
        positions: Contact points, shape (n, 3) [m].
        normals: Inward unit normals, shape (n, 3).
        com: Wrench reference point (centre of mass), shape (3,) [m].
        torque_scale: rho [m] (> 0); torques are divided by it so they are commensurate with forces.
        mu: Coulomb friction coefficient (>= 0).
        k: Number of cone edges (>= 1).
        torsion: Torsional friction coefficient gamma [m]: 0 for hard fingers (point
            contacts with Coulomb friction), > 0 for soft fingers.
        dense: Soft fingers only: the fine linearisation (:func:`soft_directions`).

    Returns:
        Wrenches, shape (n, K, 6): force [N] then torque / rho [N], with K = k for hard
        fingers and K = :func:`primitives_per_contact` for soft ones (more when dense).

    Raises:
        OgcpError: For an array of another shape or with NaN or infinite values, a zero
            normal, or a bad rho, mu, k or torsion.
    """
    p = finite_array(positions, "positions", "(n, 3)", 2, 3)
    n = _normals_array(normals)
    if n.shape != p.shape:
        raise OgcpError(f"normals must have the shape of the positions {p.shape}, got {n.shape}")
    c = finite_array(com, "com", "(3,)", 1, 3)
    if not (isinstance(torque_scale, Real) and math.isfinite(torque_scale) and torque_scale > 0):
        raise OgcpError(f"torque scale rho must be a finite number > 0, got {torque_scale!r}")
    _cone_parameters(mu, k)
    _torsion_parameter(torsion)
    arms = (p - c)[:, None, :]
    if torsion <= 0:
        forces = _cone_edges(n, float(mu), int(k))
        torques = np.cross(np.broadcast_to(arms, forces.shape), forces) / float(torque_scale)
        return np.concatenate([forces, torques], axis=2)
    a, b = _tangent_basis(n)
    d = soft_directions(int(k), dense)
    forces = n[:, None, :] + float(mu) * (d[None, :, 0, None] * a[:, None, :] + d[None, :, 1, None] * b[:, None, :])
    torques = (
        np.cross(np.broadcast_to(arms, forces.shape), forces) + float(torsion) * d[None, :, 2, None] * n[:, None, :]
    )
    return np.concatenate([forces, torques / float(torque_scale)], axis=2)
