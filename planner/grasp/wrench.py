"""Linearised friction cones and contact wrenches (the convention used everywhere in ogcp).

Cone edges ``f_j = n + mu (cos t_j a + sin t_j b)`` with ``t_j = 2 pi j / k``: normal
component 1, not normalised. The tangent basis is fixed exactly so that results never
depend on an arbitrary choice: ``a = unit(n x e)`` with ``e = (1, 0, 0)`` unless
``|n_x| >= 0.9``, then ``e = (0, 1, 0)``; ``b = n x a``. The wrench of an edge applied at
``p`` is ``[f, (p - com) x f / rho]``.

The public functions check their arrays (shape, finite values) and raise
:class:`~planner.infra.errors.OgcpError` naming the shape expected and the shape given.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np
from numpy.typing import NDArray

from planner.infra.errors import OgcpError


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


def contact_wrenches(
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    com: NDArray[np.float64],
    torque_scale: float,
    mu: float,
    k: int,
) -> NDArray[np.float64]:
    """Wrenches of every cone edge of every contact.

    Args:
        positions: Contact points, shape (n, 3) [m].
        normals: Inward unit normals, shape (n, 3).
        com: Wrench reference point (centre of mass), shape (3,) [m].
        torque_scale: rho [m] (> 0); torques are divided by it so they are commensurate with forces.
        mu: Coulomb friction coefficient (>= 0).
        k: Number of cone edges (>= 1).

    Returns:
        Wrenches, shape (n, k, 6): force [N] then torque / rho [N].

    Raises:
        OgcpError: For an array of another shape or with NaN or infinite values, a zero
            normal, or a bad rho, mu or k.
    """
    p = finite_array(positions, "positions", "(n, 3)", 2, 3)
    n = _normals_array(normals)
    if n.shape != p.shape:
        raise OgcpError(f"normals must have the shape of the positions {p.shape}, got {n.shape}")
    c = finite_array(com, "com", "(3,)", 1, 3)
    if not (isinstance(torque_scale, Real) and math.isfinite(torque_scale) and torque_scale > 0):
        raise OgcpError(f"torque scale rho must be a finite number > 0, got {torque_scale!r}")
    _cone_parameters(mu, k)
    forces = _cone_edges(n, float(mu), int(k))
    arms = (p - c)[:, None, :]
    torques = np.cross(np.broadcast_to(arms, forces.shape), forces) / float(torque_scale)
    return np.concatenate([forces, torques], axis=2)
