"""Linearised friction cones and contact wrenches (the convention used everywhere in ogcp).

Cone edges ``f_j = n + mu (cos t_j a + sin t_j b)`` with ``t_j = 2 pi j / k``: normal
component 1, not normalised. The tangent basis is fixed exactly so that results never
depend on an arbitrary choice: ``a = unit(n x e)`` with ``e = (1, 0, 0)`` unless
``|n_x| >= 0.9``, then ``e = (0, 1, 0)``; ``b = n x a``. The wrench of an edge applied at
``p`` is ``[f, (p - com) x f / rho]``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def tangent_basis(normals: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the fixed tangent basis (a, b) for unit normals.

    Args:
        normals: Unit normals, shape (n, 3).

    Returns:
        ``(a, b)``, each of shape (n, 3), with ``a = unit(n x e)`` and ``b = n x a``.
    """
    normals = np.asarray(normals, dtype=float)
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
        mu: Coulomb friction coefficient.
        k: Number of cone edges.

    Returns:
        Edge forces, shape (n, k, 3), normal component 1 [N per unit normal force].
    """
    a, b = tangent_basis(normals)
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
        torque_scale: rho [m]; torques are divided by it so they are commensurate with forces.
        mu: Coulomb friction coefficient.
        k: Number of cone edges.

    Returns:
        Wrenches, shape (n, k, 6): force [N] then torque / rho [N].
    """
    forces = cone_edges(normals, mu, k)
    arms = (np.asarray(positions, dtype=float) - np.asarray(com, dtype=float))[:, None, :]
    torques = np.cross(np.broadcast_to(arms, forces.shape), forces) / torque_scale
    return np.concatenate([forces, torques], axis=2)
