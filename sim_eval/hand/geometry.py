"""A posed hand's surface as triangles: what a figure draws, taken from the same MuJoCo geoms that collide."""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np
import trimesh
from numpy.typing import NDArray


def geom_triangles(model: mujoco.MjModel, geom: int) -> tuple[NDArray[np.float64], NDArray[np.int64]] | None:
    """A geom's surface in its own frame: vertices (v, 3) [m] and faces (f, 3); None for planes and the rest."""
    kind, size = int(model.geom_type[geom]), model.geom_size[geom]
    shape: trimesh.Trimesh | None = None
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        mesh = int(model.geom_dataid[geom])
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        first, faces = model.mesh_faceadr[mesh], model.mesh_facenum[mesh]
        return model.mesh_vert[start : start + count].astype(float), model.mesh_face[first : first + faces].astype(
            np.int64
        )
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        shape = trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    elif kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        shape = trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[12, 12])
    elif kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        shape = trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=16)
    elif kind == mujoco.mjtGeom.mjGEOM_BOX:
        shape = trimesh.creation.box(extents=2 * size[:3])
    elif kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        shape = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        shape.vertices = shape.vertices * size[:3]
    if shape is None:
        return None
    return np.asarray(shape.vertices, dtype=float), np.asarray(shape.faces, dtype=np.int64)


def posed_triangles(
    model: mujoco.MjModel, data: mujoco.MjData, geoms: Iterable[int]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The geoms' surfaces in the world after kinematics, merged: vertices (v, 3) [m], faces (f, 3)."""
    vertices, faces, offset = [], [], 0
    for geom in map(int, geoms):
        found = geom_triangles(model, geom)
        if found is None:
            continue
        v, f = found
        vertices.append(v @ data.geom_xmat[geom].reshape(3, 3).T + data.geom_xpos[geom])
        faces.append(f + offset)
        offset += len(v)
    if not vertices:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return np.vstack(vertices), np.vstack(faces)
