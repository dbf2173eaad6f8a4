"""Helpers for plans that carry their contacts: where their mesh is, whether contacts lie on it, versions.

A plan records its full contact set (:func:`ogcp.planner.records.plan.contact_set_record`), so
the set is not sampled again: it is checked against the object instead. This module finds
the object's mesh file from a plan written anywhere, measures how far each recorded contact
lies from the mesh surface (and whether its normal is its face's), and compares the library
versions a plan was made with against the running ones, for messages and for deciding
whether re-sampling must reproduce the recorded set.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, cast

import numpy as np
import trimesh
from numpy.typing import NDArray

from ogcp.planner.infra.provenance import provenance

#: [m] how far a recorded contact may lie from the mesh surface. Sampled points are convex
#: combinations of a face's vertices, off its plane by rounding only (~1e-17 m at ogcp's
#: diagonals); 1e-9 m is the precision every recorded position is checked to.
SURFACE_TOLERANCE = 1e-9
#: [-] per component: a recorded inward normal vs the negated unit normal of its face.
FACE_NORMAL_TOLERANCE = 1e-9
#: The libraries whose versions decide the sampled contacts (ogcp's sampler, trimesh's even
#: sampling, numpy's generators, scipy's trees).
SAMPLING_PACKAGES = ("ogcp", "trimesh", "numpy", "scipy")
#: Point-face pairs compared at once by :func:`surface_misfit` (bounds its memory).
_PAIRS_PER_BLOCK = 2_000_000


def mesh_candidates(source: dict[str, Any], mesh: dict[str, Any], plan_file: Path | None) -> list[Path]:
    """Where a plan's mesh file may be, in the order tried, without repeats.

    1. Relative to the plan file (``path_from_plan``, recorded where the plan was written by
       ``ogcp plan -o``): the plan moved together with its mesh.
    2. The absolute path recorded at planning: the plan moved, the mesh did not.
    3. The path as given at planning, relative to the current folder (older plans' only path).
    4. That path relative to the plan file's folder: a plan written in the folder it was planned from.

    Args:
        source: The contact set's source (``path`` as given at planning).
        mesh: The contact set's ``mesh`` block (``path_from_plan``, ``absolute_path``); may be empty.
        plan_file: The plan's file, None when the record did not come from a file.
    """
    folder = None if plan_file is None else Path(plan_file).resolve().parent
    given = source.get("path")
    paths: list[Path] = []
    if folder is not None and isinstance(mesh.get("path_from_plan"), str):
        paths.append(folder / mesh["path_from_plan"])
    if isinstance(mesh.get("absolute_path"), str):
        paths.append(Path(mesh["absolute_path"]))
    if isinstance(given, str):
        paths.append(Path(given))
        if folder is not None and not Path(given).is_absolute():
            paths.append(folder / given)
    unique: list[Path] = []
    for path in paths:
        if path not in unique:
            unique.append(path)
    return unique


def surface_misfit(
    mesh: trimesh.Trimesh, positions: NDArray[np.float64], normals: NDArray[np.float64]
) -> tuple[int, float, float] | None:
    """The first contact that is not on the mesh surface with its face's inward normal, if any.

    A contact fits when some face lies within :data:`SURFACE_TOLERANCE` of it and that face's
    inward unit normal matches its normal to :data:`FACE_NORMAL_TOLERANCE` (on an edge, either
    face will do). Faces are pre-selected by their bounding boxes, so the cost is about
    n * faces comparisons plus exact distances to the few faces near each contact.

    Args:
        mesh: The object.
        positions: Contact points, shape (n, 3) [m].
        normals: Inward unit normals, shape (n, 3).

    Returns:
        None when every contact fits; else ``(index, distance [m], normal error [-])`` of the
        first that does not: its distance to the surface, and the normal error on the nearest
        face within tolerance (inf where no face is).
    """
    triangles = np.asarray(mesh.triangles, dtype=float)
    inward = -np.asarray(mesh.face_normals, dtype=float)
    low = triangles.min(axis=1) - SURFACE_TOLERANCE
    high = triangles.max(axis=1) + SURFACE_TOLERANCE
    block = max(1, _PAIRS_PER_BLOCK // max(1, len(triangles)))
    for start in range(0, len(positions), block):
        points = positions[start : start + block]
        near = np.all((points[:, None, :] >= low[None]) & (points[:, None, :] <= high[None]), axis=2)
        rows, faces = np.nonzero(near)
        distance = np.full(len(points), np.inf)
        normal_error = np.full(len(points), np.inf)
        if len(rows):
            gaps = _face_gaps(triangles[faces], points[rows])
            np.minimum.at(distance, rows, gaps)
            on = gaps <= SURFACE_TOLERANCE
            errors = np.max(np.abs(normals[start + rows[on]] - inward[faces[on]]), axis=1)
            np.minimum.at(normal_error, rows[on], errors)
        bad = (distance > SURFACE_TOLERANCE) | (normal_error > FACE_NORMAL_TOLERANCE)
        if np.any(bad):
            row = int(np.argmax(bad))
            gap = float(distance[row])
            if not np.isfinite(gap):  # no face near it: measure against all of them, for the message
                gap = float(np.min(_face_gaps(triangles, np.broadcast_to(points[row], (len(triangles), 3)))))
            return start + row, gap, float(normal_error[row])
    return None


def _face_gaps(triangles: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    """How far each point is from its triangle [m]: off the plane, and beyond the edge it is furthest outside.

    Exact for points on the triangle or beside an edge (all that matters against a tolerance of
    nanometres). trimesh's ``closest_point`` is not used: it reports ~1e-6 m for points inside
    the thin faces of the amphora. Degenerate faces (no area) give inf.

    Args:
        triangles: Vertices of each triangle, shape (m, 3, 3) [m].
        points: One point per triangle, shape (m, 3) [m].
    """
    v0, v1, v2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2, w = v1 - v0, v2 - v0, points - v0
    cross = np.cross(e1, e2)
    twice_area = np.linalg.norm(cross, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        plane = np.abs(np.einsum("ij,ij->i", w, cross)) / twice_area
        d00, d01, d11 = (np.einsum("ij,ij->i", a, b) for a, b in ((e1, e1), (e1, e2), (e2, e2)))
        d20, d21 = np.einsum("ij,ij->i", w, e1), np.einsum("ij,ij->i", w, e2)
        denominator = d00 * d11 - d01 * d01
        b1 = (d11 * d20 - d01 * d21) / denominator
        b2 = (d00 * d21 - d01 * d20) / denominator
        b0 = 1.0 - b1 - b2
        # A barycentric coordinate times its vertex's height is the distance to the opposite edge.
        heights = twice_area[:, None] / np.linalg.norm(np.stack([v2 - v1, v2 - v0, v1 - v0], axis=1), axis=2)
        outside = np.max(np.maximum(-np.stack([b0, b1, b2], axis=1) * heights, 0.0), axis=1)
        gaps = np.hypot(plane, outside)
    return np.where(np.isfinite(gaps), gaps, np.inf)


def _recorded_build(record: dict[str, Any]) -> tuple[dict[str, Any], Any]:
    recorded = record.get("provenance")
    recorded = recorded if isinstance(recorded, dict) else {}
    versions = recorded.get("versions")
    return (versions if isinstance(versions, dict) else {}), recorded.get("git_commit")


def versions_note(record: dict[str, Any]) -> str:
    """``recorded with trimesh 4.4.9, running 5.2.0`` for each tracked library whose version differs; "" if none.

    Libraries a plan does not record (older plans) are not reported.
    """
    recorded, _ = _recorded_build(record)
    running = cast(dict[str, Any], provenance()["versions"])
    differ = [
        f"{name} {recorded[name]}, running {running.get(name)}"
        for name in sorted(recorded)
        if name in running and recorded[name] != running.get(name)
    ]
    return f"recorded with {'; '.join(differ)}" if differ else ""


def same_sampling_build(record: dict[str, Any]) -> bool:
    """Whether this build samples contacts as the plan's did: same sampling libraries and ogcp commit.

    Only then must re-sampling reproduce the recorded set exactly (an edited n, seed or tip
    radius shows); elsewhere it may legitimately differ and the recorded set stands alone.
    """
    versions, commit = _recorded_build(record)
    running = provenance()
    running_versions = cast(dict[str, Any], running["versions"])
    if any(name not in versions or versions[name] != running_versions.get(name) for name in SAMPLING_PACKAGES):
        return False
    return bool(commit == running.get("git_commit"))
