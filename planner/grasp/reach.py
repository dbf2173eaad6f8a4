"""Contacts a fingertip can reach: a sphere touching the surface there does not cut the object.

A fingertip is a sphere of radius r. It touches the surface at a contact p with inward
normal n when its centre is at ``p - r n``, outside the object. In a concavity narrower
than the tip (a slot, a groove, the crook of a handle) that sphere cuts the object, so the
tip cannot make that contact: the simulation would start with the tip inside the object.
Nor can it touch a surface inside the object: a mesh of several closed shells (a part
modelled inside another, overlapping bodies, a cavity) has faces whose tip centre lies inside
another shell (:mod:`ogcp.planner.grasp.shells`).
:func:`reachable` finds such contacts; :func:`fill_reachable` replaces them in a sample.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.grasp.defaults import DEFAULT_TIP_RADIUS_RATIO
from ogcp.planner.grasp.mesh_distance import SurfaceIndex
from ogcp.planner.grasp.shells import Shells
from ogcp.planner.infra.errors import OgcpError

#: Default cut depth a reachable contact may have, as a fraction of the tip radius. It
#: absorbs the faceting of curved concave surfaces (a sphere touching a facet near a crease
#: that turns by an angle a sinks r (1 - cos a) into the next facet: 0.5 % of r at the
#: donut's 5.6 deg creases, 1 % at 8 deg) and rounding on convex objects, where the exact
#: clearance is r, while still removing every concavity that is really narrower than the tip.
#: At the simulation's default tip (4 % of the diagonal) it is 0.04 % of the diagonal.
REACH_TOLERANCE = 0.01
#: Area-weighted batches drawn to replace unreachable contacts before giving up; batch k
#: draws ``max(2 * missing, 64) * 2**k`` points, so up to ~128x the shortfall are tried.
FILL_BATCHES = 6
_FIRST_FILL_STREAM = 2  # rng streams [seed, 0] and [seed, 1] belong to the plain sample
#: How far off the surface a sample without a tip radius is asked whether it lies inside another
#: shell, as a fraction of the object's diagonal.
OUTER_STEP = 1e-6


def default_tip_radius(mesh: trimesh.Trimesh, ratio: float = DEFAULT_TIP_RADIUS_RATIO) -> float:
    """The default fingertip radius of an object: ``ratio`` x its bounding-box diagonal.

    Args:
        mesh: Object surface [m].
        ratio: Fraction of the diagonal (default :data:`DEFAULT_TIP_RADIUS_RATIO`).

    Returns:
        The tip radius [m].
    """
    return ratio * float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices), axis=0)))


def check_tip_radius(tip_radius: float, tolerance: float | None = None) -> tuple[float, float]:
    """Validate a tip radius and a cut tolerance.

    Args:
        tip_radius: Fingertip sphere radius [m], > 0.
        tolerance: Allowed cut depth [m], in [0, tip_radius); None = ``REACH_TOLERANCE`` x r.

    Returns:
        ``(tip_radius, tolerance)`` [m] as floats.

    Raises:
        OgcpError: For a radius that is not a positive number or a tolerance out of range.
    """
    if isinstance(tip_radius, bool) or not isinstance(tip_radius, int | float) or not 0 < tip_radius < math.inf:
        raise OgcpError(f"tip radius must be a positive number of metres, got {tip_radius!r}")
    radius = float(tip_radius)
    if tolerance is None:
        return radius, REACH_TOLERANCE * radius
    if isinstance(tolerance, bool) or not isinstance(tolerance, int | float) or not 0 <= tolerance < radius:
        raise OgcpError(
            f"reach tolerance must be a number of metres in [0, tip radius {radius:.3g}), got {tolerance!r}"
        )
    return radius, float(tolerance)


def reach_settings(tip_radius: float | None, tolerance: float | None = None) -> tuple[float, float] | None:
    """The validated ``(tip_radius, tolerance)`` [m] of reach-aware sampling, or None without a tip.

    Args:
        tip_radius: Fingertip sphere radius [m]; None or 0 means no tip (sample everywhere).
        tolerance: Allowed cut depth [m]; None = :data:`REACH_TOLERANCE` x r.

    Raises:
        OgcpError: As :func:`check_tip_radius`.
    """
    if tip_radius is None or (
        isinstance(tip_radius, int | float) and not isinstance(tip_radius, bool) and tip_radius == 0
    ):
        return None
    return check_tip_radius(tip_radius, tolerance)


def reachable(
    mesh: trimesh.Trimesh | SurfaceIndex,
    points: ArrayLike,
    inward_normals: ArrayLike,
    tip_radius: float,
    tolerance: float | None = None,
) -> NDArray[np.bool_]:
    """Which contacts a fingertip sphere can touch without cutting the object.

    A contact is reachable when the sphere of radius r centred at ``p - r n`` lies outside
    the object up to ``tolerance``: its centre is on the outer side of the surface (the
    pseudonormal test of :class:`~ogcp.planner.grasp.mesh_distance.SurfaceIndex`) and at least
    ``r - tolerance`` from every triangle (exact distances). On a convex object every
    contact is reachable. The test depends only on the geometry, so scaling the mesh, the
    radius and the tolerance together gives the same answer.

    Args:
        mesh: Object surface with outward faces, or a prepared index of it.
        points: Contact points on the surface, shape (n, 3) [m].
        inward_normals: Inward surface normals there, shape (n, 3) (normalised here).
        tip_radius: Fingertip sphere radius r [m].
        tolerance: Allowed cut depth [m]; None = :data:`REACH_TOLERANCE` x r.

    Returns:
        Mask of reachable contacts, shape (n,).

    Raises:
        OgcpError: For a bad radius or tolerance, or points and normals that are not
            finite (n, 3) arrays of the same shape with non-zero normals.
    """
    radius, tolerance = check_tip_radius(tip_radius, tolerance)
    points = np.asarray(points, dtype=np.float64)
    normals = np.asarray(inward_normals, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or normals.shape != points.shape:
        raise OgcpError(f"points and normals must both have shape (n, 3), got {points.shape} and {normals.shape}")
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(normals))):
        raise OgcpError("points and normals must be finite")
    lengths = np.linalg.norm(normals, axis=1)
    if np.any(lengths == 0):
        raise OgcpError("contact normals must not be zero")
    index = mesh if isinstance(mesh, SurfaceIndex) else SurfaceIndex(mesh)
    centres = points - radius * normals / lengths[:, None]
    # A centre is within r of its own contact, so r bounds the search; a point given off
    # the surface may be farther, and is measured without a bound.
    near = index.nearest(centres, max_distance=radius + tolerance)
    lost = np.flatnonzero(near.face < 0)
    distance, outside, face = near.distance.copy(), near.outside.copy(), near.face.copy()
    if len(lost):
        far = index.nearest(centres[lost])
        distance[lost], outside[lost], face[lost] = far.distance, far.outside, far.face
    clear = (distance >= radius - tolerance) & outside
    # The nearest sheet's side is the whole answer for one closed shell; a centre inside another
    # shell (a part modelled inside the object, an overlapping body, a cavity) is inside too.
    if index.shells.count > 1 and clear.any():
        clear[clear] = ~index.shells.enclosed(centres[clear], face[clear])
    return clear


def fill_reachable(
    mesh: trimesh.Trimesh,
    points: NDArray[np.float64],
    faces: NDArray[np.int64],
    seed: int,
    tip_radius: float,
    tolerance: float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Replace the unreachable contacts of a surface sample by reachable ones.

    The reachable samples keep their order; the shortfall is filled, in order, from
    area-weighted batches drawn with the rng streams ``[seed, 2]``, ``[seed, 3]``, ... and
    filtered the same way. The result is deterministic, and equals the input when every
    sample is reachable.

    Args:
        mesh: Object surface with outward faces.
        points: Surface samples, shape (n, 3) [m].
        faces: Face of each sample, shape (n,); the contact normal is minus its normal.
        seed: Sampling seed.
        tip_radius: Fingertip sphere radius r [m].
        tolerance: Allowed cut depth [m]; None = :data:`REACH_TOLERANCE` x r.

    Returns:
        ``(points (n, 3) [m], faces (n,))``, every sample reachable.

    Raises:
        OgcpError: When fewer than n reachable samples turn up in :data:`FILL_BATCHES`
            batches: the tip is too large for most of the surface.
    """
    radius, tolerance = check_tip_radius(tip_radius, tolerance)
    index = SurfaceIndex(mesh)
    inward = -np.asarray(mesh.face_normals)

    def keep(points: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.bool_]:
        return reachable(index, points, inward[faces], radius, tolerance)

    kept, have, tried = _refill(mesh, points, faces, seed, keep)
    if have < len(points):
        diagonal = float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices), axis=0)))
        raise OgcpError(
            f"only {have} of {len(points)} contacts found where a fingertip of radius {radius:.3g} m "
            f"({100 * radius / diagonal:.3g}% of the object's {diagonal:.3g} m diagonal) touches the surface "
            f"without cutting it ({tried} samples tried); use a smaller --tip-radius"
        )
    return kept


def fill_outer(
    mesh: trimesh.Trimesh, points: NDArray[np.float64], faces: NDArray[np.int64], seed: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Replace the samples on surfaces inside the object (on a shell inside another) by samples outside.

    Contacts sampled without a tip radius need only lie on the outer surface; a mesh of one shell
    returns its sample as it is. The refill is :func:`fill_reachable`'s, with the same seeds.

    Raises:
        OgcpError: When fewer than n outer samples turn up.
    """
    shells = Shells(mesh.vertices, mesh.faces)
    if shells.count < 2:
        return points, faces
    normals = np.asarray(mesh.face_normals)
    step = OUTER_STEP * float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices), axis=0)))

    def keep(points: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.bool_]:
        return ~shells.enclosed(points + step * normals[faces], faces)

    kept, have, tried = _refill(mesh, points, faces, seed, keep)
    if have < len(points):
        raise OgcpError(
            f"only {have} of {len(points)} contacts found on the object's outer surface ({tried} samples tried)"
        )
    return kept


def _refill(
    mesh: trimesh.Trimesh,
    points: NDArray[np.float64],
    faces: NDArray[np.int64],
    seed: int,
    keep: Callable[[NDArray[np.float64], NDArray[np.int64]], NDArray[np.bool_]],
) -> tuple[tuple[NDArray[np.float64], NDArray[np.int64]], int, int]:
    """The samples ``keep`` accepts, in order, then accepted area-weighted samples from the rng
    streams ``[seed, 2]``, ``[seed, 3]``, ... until there are as many: ((points, faces), how many
    were found, how many were tried)."""
    n = len(points)
    kept_mask = keep(points, faces)
    kept_points, kept_faces = [points[kept_mask]], [faces[kept_mask]]
    have, tried = int(kept_mask.sum()), n
    for batch in range(FILL_BATCHES):
        if have == n:
            break
        size = max(2 * (n - have), 64) * 2**batch
        rng = np.random.default_rng([seed, _FIRST_FILL_STREAM + batch])
        extra_points, extra_faces = trimesh.sample.sample_surface(mesh, size, seed=rng)
        extra_faces = np.asarray(extra_faces)
        extra_points = np.asarray(extra_points)
        good = np.flatnonzero(keep(extra_points, extra_faces))[: n - have]
        kept_points.append(extra_points[good])
        kept_faces.append(extra_faces[good])
        have, tried = have + len(good), tried + size
    return (np.vstack(kept_points), np.concatenate(kept_faces)), have, tried
