"""The object as a rigid body for simulation: convex parts and mass properties.

Mass and inertia come from the watertight mesh, never from the union of convex parts, whose
overlaps would count some volume twice. Distances to the parts live in :mod:`ogcp.sim_eval.scene.collision`.
"""

from __future__ import annotations

import warnings

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import QhullError

from ogcp.planner.grasp.contact_set import NonWatertightWarning, mass_properties
from ogcp.planner.infra.errors import OgcpError

Part = tuple[NDArray[np.float64], NDArray[np.int64]]


def is_closed_manifold(faces: NDArray[np.int64]) -> bool:
    """CoACD's edge test: every directed edge occurs once and its reverse occurs too.

    That holds exactly for a closed, consistently oriented surface. (CoACD also rejects
    self-intersecting meshes, which this does not test.)

    Args:
        faces: Triangles as vertex indices, shape (f, 3).
    """
    faces = np.asarray(faces, dtype=np.int64)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    unique = np.unique(edges, axis=0)
    if len(unique) != len(edges):
        return False
    # Every reversed edge is among the edges exactly when adding them creates no new row.
    return len(np.unique(np.concatenate([unique, edges[:, ::-1]]), axis=0)) == len(unique)


def hull_part(points: ArrayLike) -> Part | None:
    """Convex hull of a point set as a closed mesh with outward faces; None when it has no volume.

    Args:
        points: Points, shape (n, 3) [m] (not modified).

    Returns:
        ``(vertices (v, 3), faces (f, 3))``, both read-only, or None for a flat or degenerate set.
    """
    try:
        hull = trimesh.convex.convex_hull(np.array(points, dtype=np.float64), repair=True)
    except (QhullError, ValueError):
        return None
    if len(hull.faces) < 4 or not hull.volume > 0:
        return None
    vertices = np.array(hull.vertices, dtype=np.float64)
    faces = np.array(hull.faces, dtype=np.int64)
    vertices.setflags(write=False)
    faces.setflags(write=False)
    return vertices, faces


def object_inertia(mesh: trimesh.Trimesh, mass: float = 0.1) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Centre of mass and inertia tensor of the object at uniform density.

    A closed, consistently oriented mesh gives exact values. For an open mesh the volume is
    undefined: the COM is then the planner's (area-weighted surface centroid, see
    :func:`ogcp.planner.grasp.contact_set.mass_properties`), so that simulated torques act about the same
    point as the planned wrenches, and the inertia tensor is that of the mesh's convex hull
    about the hull's own centroid; a :class:`NonWatertightWarning` says so.

    Args:
        mesh: Object mesh [m].
        mass: Object mass [kg].

    Returns:
        ``(com, inertia)``: COM, shape (3,) [m]; inertia about the COM in the mesh frame,
        shape (3, 3) [kg·m²], symmetric.

    Raises:
        OgcpError: For a non-positive mass, a closed mesh with inconsistent or inward faces,
            or an open mesh whose convex hull is flat.
    """
    if isinstance(mass, bool) or not isinstance(mass, int | float) or not (0 < mass < float("inf")):
        raise OgcpError(f"object mass must be a positive number of kilograms, got {mass!r}")
    if mesh.is_watertight:
        if not mesh.is_winding_consistent:
            raise OgcpError(
                "the object mesh is closed but its faces are not consistently oriented; "
                "its volume is undefined (repair it with trimesh.repair.fix_normals)"
            )
        volume = float(mesh.volume)
        if not volume > 0:
            raise OgcpError(
                f"the object mesh encloses a volume of {volume:.3g} m^3, which is not positive; "
                "its faces point inward (flip them with mesh.invert())"
            )
        com = np.array(mesh.center_mass, dtype=float)
        inertia = np.array(mesh.moment_inertia, dtype=float) * (mass / volume)
    else:
        hull = mesh.convex_hull
        if not hull.volume > 0:
            raise OgcpError("the object mesh is open and its convex hull is flat: it has no volume to give a mass")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NonWatertightWarning)
            com, _ = mass_properties(mesh)
        warnings.warn(
            "mesh is not watertight: centre of mass = area-weighted surface centroid (as planned), "
            "inertia from the convex hull",
            NonWatertightWarning,
            stacklevel=2,
        )
        inertia = np.array(hull.moment_inertia, dtype=float) * (mass / float(hull.volume))
    return np.asarray(com, dtype=float), 0.5 * (inertia + inertia.T)
